//! A uniform gravitational field g acting on every body's mass: V = −m g·x.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, Real};
use crate::units::Dim;

pub struct UniformAcceleration;

impl Definition for UniformAcceleration {
    const SPEC: Spec = Spec {
        name: "UniformAcceleration",
        keyword: "gravity",
        shape: Shape::External,
        params: &[Param::vector("g", Dim::ACCELERATION)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let g = [p[0].clone(), p[1].clone(), p[2].clone()];
        -(s[0].m.clone() * dot3(&g, &s[0].x))
    }
}
