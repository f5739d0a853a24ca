//! Weeks–Chandler–Andersen repulsion: Lennard-Jones cut at its minimum r_c = 2^{1/6}σ and
//! lifted by ε, V = 4ε[(σ/r)¹² − (σ/r)⁶] + ε for r < r_c: purely repulsive, continuous with
//! its force (the bead–bead repulsion of Kremer–Grest polymers).

use super::lennard_jones::{cut, lj, prepared};
use super::{constant, Definition, Param, Shape, Site, Spec};
use crate::real::Real;
use crate::units::Dim;

pub struct Wca;

/// 2^{1/6}, the position of the Lennard-Jones minimum in units of σ.
pub const MINIMUM: f64 = 1.122_462_048_309_373;

impl Definition for Wca {
    const SPEC: Spec = Spec {
        name: "Wca",
        keyword: "wca",
        shape: Shape::Pairwise,
        params: &[Param::scalar("epsilon", Dim::ENERGY), Param::scalar("sigma", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = |k| constant::<Self, R>(p, k);
        cut(p, s, c(2), |r2| lj(&c(0), &c(1), r2) + p[0].clone())
    }

    /// 4ε, σ², r_c² (`prepared`, r_c = 2^{1/6}σ).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        prepared(&p[0], &p[1], p[1].lift(MINIMUM) * p[1].clone())
    }

    fn reach(p: &[f64]) -> f64 {
        MINIMUM * p[1]
    }
}
