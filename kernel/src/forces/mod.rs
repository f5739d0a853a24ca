//! Fast, hand-derived forces. A term supplies one `eval` for one instance — of `Bonded` (listed
//! bodies), `Paired` (every pair, on the displacement) or `Field` (each body alone) — and
//! `groups` loops over the instances in flat arrays, monomorphized per term. They never call the
//! checker's generic definitions; tests hold the two together (forces = −∇V − ∂F/∂v to
//! round-off, energies equal).

mod groups;

mod gravity;
mod harmonic_bond;
mod uniform_acceleration;

#[cfg(test)]
pub(crate) mod dual;

use groups::{Bonds, Fields, Pairs};
use lagra_checker::model::{Model, TermInstance};
use lagra_checker::terms::Kind;
use std::fmt;

/// A configuration where a term's force is undefined (bodies at one point, a bond stretched past
/// its limit, ...): a clear error, never a NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct Singularity {
    pub term: &'static str,
    pub bodies: Vec<usize>,
    pub what: &'static str,
}

impl fmt::Display for Singularity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b: Vec<String> = self.bodies.iter().map(|b| b.to_string()).collect();
        write!(f, "{}: bodies {}: {}", self.term, b.join(", "), self.what)
    }
}

/// The state as a force sees it.
pub struct Frame<'a> {
    pub x: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    pub m: &'a [f64],
    pub q: &'a [f64],
}

/// A homogeneous group of term instances.
pub trait Force: Send + Sync {
    /// Adds the group's generalized forces to `f` and returns its potential energy.
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity>;
    /// Whether the force depends on velocities (the solver then iterates its closing kick).
    fn velocity_dependent(&self) -> bool;
}

/// Forces on N listed bodies, and the energy, of one instance with parameters `p`.
pub trait Bonded<const N: usize> {
    fn eval(p: &[f64], x: &[[f64; 3]; N], v: &[[f64; 3]; N]) -> Result<([[f64; 3]; N], f64), &'static str>;
    fn velocity_dependent(_p: &[f64]) -> bool {
        false
    }
}

/// The force on body i and the energy of one pair, given the displacement d = x_j − x_i
/// (the minimum image in a periodic box); body j feels the opposite force.
pub trait Paired {
    fn eval(p: &[f64], d: [f64; 3], mq: [f64; 4]) -> Result<([f64; 3], f64), &'static str>;
}

/// The force on one body and its energy, from its position, velocity, mass and charge.
pub trait Field {
    fn eval(p: &[f64], x: &[f64; 3], v: &[f64; 3], m: f64, q: f64) -> Result<([f64; 3], f64), &'static str>;
    fn velocity_dependent(_p: &[f64]) -> bool {
        false
    }
}

/// The group for all instances of one kind: one line per term kind.
pub fn group(kind: Kind, t: &[&TermInstance], m: &Model) -> Box<dyn Force> {
    match kind {
        Kind::HarmonicBond => Bonds::<harmonic_bond::Fast, 2>::boxed(kind, t, m),
        Kind::UniformAcceleration => Fields::<uniform_acceleration::Fast>::boxed(kind, t),
        Kind::Gravity => Pairs::<gravity::Fast>::boxed(kind, t, m),
    }
}
