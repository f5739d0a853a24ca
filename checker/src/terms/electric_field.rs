//! A uniform electric field on every charge: V = −q E·x.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, Real};
use crate::units::Dim;

pub struct ElectricField;

impl Definition for ElectricField {
    const SPEC: Spec = Spec {
        name: "ElectricField",
        keyword: "electric",
        shape: Shape::External,
        params: &[Param::vector("E", Dim::ELECTRIC)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let e = [p[0].clone(), p[1].clone(), p[2].clone()];
        -(s[0].q.clone() * dot3(&e, &s[0].x))
    }
}
