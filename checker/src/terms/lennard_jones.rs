//! Lennard-Jones, plain, cut at r_c: V = 4ε[(σ/r)¹² − (σ/r)⁶] for r < r_c, 0 beyond (the energy
//! jumps at r_c: use the shifted variants where energy must be conserved).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, select, sub3, Real};
use crate::units::Dim;

pub struct LennardJones;

pub(super) const PARAMS: &[Param] =
    &[Param::scalar("epsilon", Dim::ENERGY), Param::scalar("sigma", Dim::LENGTH), Param::scalar("cutoff", Dim::LENGTH)];

/// 4ε[(σ²/r²)⁶ − (σ²/r²)³], from r².
#[inline(always)]
pub(super) fn lj<R: Real>(eps: &R, sigma: &R, r2: R) -> R {
    let s6 = (sigma.clone().powi(2) / r2).powi(3);
    eps.lift(4.0) * eps.clone() * (s6.clone().powi(2) - s6)
}

/// `inside(r²)` within the cutoff, zero (as an energy) beyond.
#[inline(always)]
pub(super) fn cut<R: Real>(p: &[R], s: &[&Site<R>], rc: R, inside: impl FnOnce(R) -> R) -> R {
    let r2 = norm2(&sub3(&s[1].x, &s[0].x));
    let rc2 = rc.powi(2);
    select(r2.lt(&rc2), || inside(r2), || p[0].clone() * p[0].lift(0.0))
}

impl Definition for LennardJones {
    const SPEC: Spec = Spec { name: "LennardJones", keyword: "lj", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        cut(p, s, p[2].clone(), |r2| lj(&p[0], &p[1], r2))
    }
}
