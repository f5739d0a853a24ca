//! `lagra-noether-derive`: the symbolic side of Noether's theorem, with symbolica. It
//! instantiates the checker's term definitions over symbolic expressions (`sym`), varies each
//! along the generators of the symmetries of space and time (`derive`), and writes the table
//! that `lagra-noether` reads (`noether/derived.json`) and its rendering (`docs/noether.md`).
//!
//! Symbolica allows one thread per user machine-wide (unlicensed, a second one is killed):
//! everything here runs on the thread that holds `lock::Exclusive`.

pub mod cli;
pub mod derive;
pub mod lock;
pub mod render;
pub mod sym;

#[cfg(test)]
mod tests;
