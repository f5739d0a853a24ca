//! A uniform magnetic field B on every charge, in the Lagrangian form L = q A·v with the
//! symmetric gauge A = ½ B × x: the Euler–Lagrange force is q v × B; no potential energy, and the
//! field does no work.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{cross3, dot3, norm2, Real};
use crate::units::Dim;

pub struct MagneticField;

impl Definition for MagneticField {
    const SPEC: Spec = Spec {
        name: "MagneticField",
        keyword: "magnetic",
        shape: Shape::External,
        params: &[Param::vector("B", Dim::MAGNETIC)],
    };

    /// Zero, as an energy.
    fn potential<R: Real>(_p: &[R], s: &[&Site<R>]) -> R {
        s[0].m.clone() * norm2(&s[0].v) * s[0].m.lift(0.0)
    }

    fn gyroscopic<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        let b = [p[0].clone(), p[1].clone(), p[2].clone()];
        let a = cross3(&b, &s[0].x).map(|c| c.lift(0.5) * c);
        Some(s[0].q.clone() * dot3(&a, &s[0].v))
    }
}
