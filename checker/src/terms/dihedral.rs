//! Proper dihedral on four bodies: V = k (1 + cos(nφ − δ)), φ the angle between the planes
//! (x₀, x₁, x₂) and (x₁, x₂, x₃) in the IUPAC convention, φ = atan2(|b₂| b₁·n₂, n₁·n₂) with
//! bᵢ = xᵢ − xᵢ₋₁, n₁ = b₁×b₂, n₂ = b₂×b₃. A series is several dihedrals on the same bodies.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{cross3, dot3, norm2, sub3, Real};
use crate::units::Dim;

pub struct Dihedral;

impl Definition for Dihedral {
    const SPEC: Spec = Spec {
        name: "Dihedral",
        keyword: "dihedral",
        shape: Shape::Bond(4),
        params: &[Param::scalar("k", Dim::ENERGY), Param::scalar("n", Dim::NONE), Param::scalar("phase", Dim::NONE)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (b1, b2, b3) = (sub3(&s[1].x, &s[0].x), sub3(&s[2].x, &s[1].x), sub3(&s[3].x, &s[2].x));
        let (n1, n2) = (cross3(&b1, &b2), cross3(&b2, &b3));
        let phi = (norm2(&b2).sqrt() * dot3(&b1, &n2)).atan2(dot3(&n1, &n2));
        p[0].clone() * (p[0].lift(1.0) + (p[1].clone() * phi - p[2].clone()).cos())
    }
}
