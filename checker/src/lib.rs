//! `lagra-checker`: Lagra's trusted core.
//!
//! It holds the one definition of every interaction term (generic over [`real::Real`]), their
//! dimensions, the claims a scene may declare, and the decision that turns rigorous interval
//! enclosures into PASS or FAIL. It depends on no other crate of the project: the code that did
//! the arithmetic is not the code that signs off on it.

#![forbid(unsafe_code)]

pub mod broad_phase;
pub mod certificate;
pub mod checksum;
pub mod claims;
pub mod cli;
pub mod decision;
pub mod enclosure;
mod exact_sum;
pub mod helpers;
mod joints;
pub mod model;
pub mod monitor;
pub mod mpfi;
pub mod outward;
pub mod quantities;
pub mod real;
pub mod recheck;
pub mod render;
mod solids;
mod soundness;
pub mod states;
pub mod terms;
pub mod thermostat;
pub mod units;

/// Stand-ins for `kani::any`, so the Kani harnesses type-check where Kani cannot be installed:
/// `cargo rustc -p lagra-checker --lib -- --cfg kani_typecheck` (run by `.ci/run`). Every
/// harness module (`proofs`) reads `any` from here, which is Kani's own under Kani.
#[cfg(kani_typecheck)]
mod kani_typecheck {
    pub fn any<T: Default>() -> T {
        T::default()
    }
}
#[cfg(kani)]
use kani::any;
#[cfg(kani_typecheck)]
use kani_typecheck::any;
