//! Harmonic trap pulling every body to a centre: V = ½ k |x − c|².

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct HarmonicTrap;

impl Definition for HarmonicTrap {
    const SPEC: Spec = Spec {
        name: "HarmonicTrap",
        keyword: "trap",
        shape: Shape::External,
        params: &[Param::scalar("k", Dim::STIFFNESS), Param::vector("center", Dim::LENGTH).or(0.0)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = [p[1].clone(), p[2].clone(), p[3].clone()];
        p[0].lift(0.5) * p[0].clone() * norm2(&sub3(&s[0].x, &c))
    }
}
