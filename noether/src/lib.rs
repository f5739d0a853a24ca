//! Noether's theorem for a scene: which of the symmetries of space and time every term of the
//! scene respects, so which quantities must be conserved, which term breaks the others, and the
//! claims that follow.
//!
//! The term × symmetry table is derived symbolically, from the checker's own term definitions,
//! by `lagra-noether-derive` (symbolica), and checked in as `noether/derived.json`; this crate
//! reads it and never links symbolica, so `lagra run` does not either. It proposes; the checker
//! disposes: a derived conservation law becomes a claim that the checker certifies or refutes.

mod analysis;
mod table;

pub use analysis::{analyse, Analysis, Law, Status};
pub use table::{parameter_names, Part, Symmetry, Table, TermSymmetries, Verdict, DERIVED};
