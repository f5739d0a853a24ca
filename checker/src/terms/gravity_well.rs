//! A fixed point mass M at a centre, attracting every massive body: V = −G M m / |x − c|.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct GravityWell;

impl Definition for GravityWell {
    const SPEC: Spec = Spec {
        name: "GravityWell",
        keyword: "well",
        shape: Shape::External,
        params: &[
            Param::scalar("G", Dim::GRAVITATIONAL),
            Param::scalar("M", Dim::MASS),
            Param::vector("center", Dim::LENGTH).or(0.0),
        ],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = [p[2].clone(), p[3].clone(), p[4].clone()];
        -(p[0].clone() * p[1].clone() * s[0].m.clone() / norm2(&sub3(&s[0].x, &c)).sqrt())
    }
}
