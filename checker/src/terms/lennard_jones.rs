//! Lennard-Jones, plain, cut at r_c: V = 4ε[(σ/r)¹² − (σ/r)⁶] for r < r_c, 0 beyond (the energy
//! jumps at r_c: use the shifted variants where energy must be conserved).

use super::{constant, Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, select, sub3, Real};
use crate::units::Dim;

pub struct LennardJones;

pub(super) const PARAMS: &[Param] =
    &[Param::scalar("epsilon", Dim::ENERGY), Param::scalar("sigma", Dim::LENGTH), Param::scalar("cutoff", Dim::LENGTH)];

/// 4ε, σ² and r_c²: the constants (`Definition::constants`) every Lennard-Jones term starts
/// with, worked out once for an instance instead of once for every pair (three of the eighteen
/// interval operations a pair took).
pub(super) fn prepared<R: Real>(eps: &R, sigma: &R, rc: R) -> Vec<R> {
    vec![eps.lift(4.0) * eps.clone(), sigma.clone().powi(2), rc.powi(2)]
}

/// 4ε[(σ²/r²)⁶ − (σ²/r²)³], from 4ε, σ² and r².
#[inline(always)]
pub(super) fn lj<R: Real>(four_eps: &R, sigma2: &R, r2: R) -> R {
    let s6 = (sigma2.clone() / r2).powi(3);
    four_eps.clone() * (s6.clone().powi(2) - s6)
}

/// `inside(r²)` within the cutoff (r_c², `rc2`), zero (as an energy) beyond.
#[inline(always)]
pub(super) fn cut<R: Real>(p: &[R], s: &[&Site<R>], rc2: R, inside: impl FnOnce(R) -> R) -> R {
    let r2 = norm2(&sub3(&s[1].x, &s[0].x));
    select(r2.lt(&rc2), || inside(r2), || p[0].clone() * p[0].lift(0.0))
}

impl Definition for LennardJones {
    const SPEC: Spec = Spec { name: "LennardJones", keyword: "lj", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = |k| constant::<Self, R>(p, k);
        cut(p, s, c(2), |r2| lj(&c(0), &c(1), r2))
    }

    /// 4ε, σ², r_c² (`prepared`).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        prepared(&p[0], &p[1], p[2].clone())
    }
}
