//! Hydrogen bond on [donor, hydrogen, acceptor], the DREIDING distance-angle form (Mayo,
//! Olafson & Goddard 1990): V = D [5(R₀/r)¹² − 6(R₀/r)¹⁰] cos⁴θ, r the donor–acceptor distance
//! and θ the D–H···A angle at the hydrogen (strongest straight, θ = 180°; the well has depth D
//! at r = R₀).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, norm2, sub3, Real};
use crate::units::Dim;

pub struct HydrogenBond;

impl Definition for HydrogenBond {
    const SPEC: Spec = Spec {
        name: "HydrogenBond",
        keyword: "hbond",
        shape: Shape::Bond(3),
        params: &[Param::scalar("D", Dim::ENERGY), Param::scalar("R0", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (u, w) = (sub3(&s[0].x, &s[1].x), sub3(&s[2].x, &s[1].x));
        let cos2 = dot3(&u, &w).powi(2) / (norm2(&u) * norm2(&w));
        let s2 = p[1].clone().powi(2) / norm2(&sub3(&s[2].x, &s[0].x));
        let radial = s2.lift(5.0) * s2.clone().powi(6) - s2.lift(6.0) * s2.powi(5);
        p[0].clone() * radial * cos2.powi(2)
    }
}
