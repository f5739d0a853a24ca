//! A uniform magnetic field B on every charge, in the Lagrangian form L = q A·v with the
//! symmetric gauge A = ½ B × x: the Euler–Lagrange force is q v × B; no potential energy, and the
//! field does no work.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{cross3, dot3, norm2, Real, Vec3};
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

    /// q B × x for the momentum (the canonical q A plus the boundary term of δL = q A(a)·v);
    /// ½q x × (B × x) = ½q (B|x|² − x (x·B)) for the angular momentum (x × q A).
    fn charge_share<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<[Vec3<R>; 2]> {
        let (b, x, q) = ([p[0].clone(), p[1].clone(), p[2].clone()], &s[0].x, &s[0].q);
        let momentum = cross3(&b, x).map(|c| q.clone() * c);
        let (r2, xb) = (norm2(x), dot3(x, &b));
        let angular = std::array::from_fn(|c| {
            q.lift(0.5) * q.clone() * (b[c].clone() * r2.clone() - x[c].clone() * xb.clone())
        });
        Some([momentum, angular])
    }

    fn gyroscopic<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        let b = [p[0].clone(), p[1].clone(), p[2].clone()];
        let a = cross3(&b, &s[0].x).map(|c| c.lift(0.5) * c);
        Some(s[0].q.clone() * dot3(&a, &s[0].v))
    }
}
