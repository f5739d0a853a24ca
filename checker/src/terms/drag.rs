//! Linear drag on every body: no potential, a Rayleigh dissipation F = ½ γ |v|² (force −γv).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, Real};
use crate::units::Dim;

pub struct Drag;

impl Definition for Drag {
    const SPEC: Spec =
        Spec { name: "Drag", keyword: "drag", shape: Shape::External, params: &[Param::scalar("gamma", Dim::DAMPING)] };

    /// Zero, as an energy (so that the dimension check still sees an energy).
    fn potential<R: Real>(_p: &[R], s: &[&Site<R>]) -> R {
        s[0].m.clone() * norm2(&s[0].v) * s[0].m.lift(0.0)
    }

    fn rayleigh<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        Some(p[0].lift(0.5) * p[0].clone() * norm2(&s[0].v))
    }

    fn dissipates(p: &[f64]) -> bool {
        p[0] != 0.0
    }
}
