//! Harmonic angle on three bodies, the middle one the vertex: V = ½ k (θ − θ₀)².

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, norm2, sub3, Real};
use crate::units::Dim;

pub struct HarmonicAngle;

impl Definition for HarmonicAngle {
    const SPEC: Spec = Spec {
        name: "HarmonicAngle",
        keyword: "angle",
        shape: Shape::Bond(3),
        params: &[Param::scalar("k", Dim::ENERGY), Param::scalar("theta0", Dim::NONE)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (u, w) = (sub3(&s[0].x, &s[1].x), sub3(&s[2].x, &s[1].x));
        let theta = (dot3(&u, &w) / (norm2(&u) * norm2(&w)).sqrt()).acos();
        p[0].lift(0.5) * p[0].clone() * (theta - p[1].clone()).powi(2)
    }
}
