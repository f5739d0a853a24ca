//! Fast, hand-derived forces: one group per term kind, laid out as flat arrays. They never call
//! the checker's generic definitions; tests hold the two together (forces = −∇V to round-off).

mod gravity;
mod harmonic_bond;
mod uniform_acceleration;

#[cfg(test)]
pub(crate) mod dual;

use lagra_checker::model::{Model, TermInstance};
use lagra_checker::terms::Kind;
use std::fmt;

/// Two bodies at the same point, where a term's force has no defined value.
#[derive(Clone, Debug, PartialEq)]
pub struct Singularity {
    pub term: &'static str,
    pub i: usize,
    pub j: usize,
}

impl fmt::Display for Singularity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: bodies {} and {} are at the same point, where the force is undefined", self.term, self.i, self.j)
    }
}

/// The state as a force sees it.
pub struct Frame<'a> {
    pub x: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    pub m: &'a [f64],
}

/// A homogeneous group of term instances.
pub trait Force: Send + Sync {
    /// Adds the group's generalized forces to `f` and returns its potential energy.
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity>;
    /// Whether the force depends on velocities (the solver then iterates its closing kick).
    fn dissipative(&self) -> bool {
        false
    }
}

/// The group for all instances of one kind. One line per term kind.
pub fn group(kind: Kind, instances: &[&TermInstance], model: &Model) -> Box<dyn Force> {
    match kind {
        Kind::HarmonicBond => Box::new(harmonic_bond::HarmonicBonds::new(instances)),
        Kind::UniformAcceleration => Box::new(uniform_acceleration::UniformField::new(instances)),
        Kind::Gravity => Box::new(gravity::PairGravity::new(instances, model)),
    }
}

/// `f[i] += a`, `f[j] −= a`: a pair force, applied so that the two are exactly opposite.
#[inline(always)]
pub(crate) fn apply_pair(f: &mut [[f64; 3]], i: usize, j: usize, a: [f64; 3]) {
    for c in 0..3 {
        f[i][c] += a[c];
        f[j][c] -= a[c];
    }
}
