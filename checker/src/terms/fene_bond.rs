//! FENE bond (finitely extensible nonlinear elastic): V = −½ k R₀² ln(1 − (r/R₀)²), infinite at
//! r = R₀: the bond cannot stretch past R₀ (Kremer–Grest polymers).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct FeneBond;

impl Definition for FeneBond {
    const SPEC: Spec = Spec {
        name: "FeneBond",
        keyword: "fene",
        shape: Shape::Bond(2),
        params: &[Param::scalar("k", Dim::STIFFNESS), Param::scalar("R0", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r02 = p[1].clone().powi(2);
        let x = norm2(&sub3(&s[1].x, &s[0].x)) / r02.clone();
        -(p[0].lift(0.5) * p[0].clone() * r02 * (x.lift(1.0) - x).ln())
    }
}
