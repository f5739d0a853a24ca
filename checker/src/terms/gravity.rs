//! Newtonian gravity between two massive bodies: V = −G m₀ m₁ / r.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct Gravity;

impl Definition for Gravity {
    const SPEC: Spec = Spec {
        name: "Gravity",
        keyword: "gravity",
        shape: Shape::Pairwise,
        params: &[Param::scalar("G", Dim::GRAVITATIONAL)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        -(p[0].clone() * s[0].m.clone() * s[1].m.clone() / r)
    }
}
