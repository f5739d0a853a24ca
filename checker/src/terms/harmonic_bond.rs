//! A spring between two bodies: V = ½k(r − r₀)², with an optional Rayleigh damping on the
//! relative velocity along the bond, F = ½γ(ṙ)², ṙ = (v₁ − v₀)·r̂.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, norm2, sub3, Real};
use crate::units::Dim;

pub struct HarmonicBond;

impl Definition for HarmonicBond {
    const SPEC: Spec = Spec {
        name: "HarmonicBond",
        keyword: "harmonic",
        shape: Shape::Bond(2),
        params: &[
            Param::scalar("k", Dim::STIFFNESS),
            Param::scalar("r0", Dim::LENGTH),
            Param::scalar("damping", Dim::DAMPING).or(0.0),
        ],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (k, r0) = (p[0].clone(), p[1].clone());
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        k.lift(0.5) * k * (r - r0).powi(2)
    }

    fn rayleigh<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        let gamma = p[2].clone();
        let d = sub3(&s[1].x, &s[0].x);
        let rdot = dot3(&sub3(&s[1].v, &s[0].v), &d) / norm2(&d).sqrt();
        Some(gamma.lift(0.5) * gamma * rdot.powi(2))
    }

    fn dissipates(p: &[f64]) -> bool {
        p[2] != 0.0
    }
}
