//! Morse bond: V = D (1 − e^{−a(r − r₀)})², a well of depth D that lets a bond break.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct MorseBond;

impl Definition for MorseBond {
    const SPEC: Spec = Spec {
        name: "MorseBond",
        keyword: "morse",
        shape: Shape::Bond(2),
        params: &[Param::scalar("D", Dim::ENERGY), Param::scalar("a", Dim::INVERSE_LENGTH), Param::scalar("r0", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        let e = (-(p[1].clone() * (r - p[2].clone()))).exp();
        p[0].clone() * (e.lift(1.0) - e).powi(2)
    }
}
