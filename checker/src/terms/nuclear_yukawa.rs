//! A toy nuclear force between every pair of bodies, whatever their charge: the attractive
//! Yukawa potential of one-pion exchange, V = −g e^{−r/λ} / r, λ the range (ħ/m_π c ≈ 1.4 fm).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct NuclearYukawa;

impl Definition for NuclearYukawa {
    const SPEC: Spec = Spec {
        name: "NuclearYukawa",
        keyword: "nuclear",
        shape: Shape::Pairwise,
        params: &[Param::scalar("g", Dim::ENERGY_LENGTH), Param::scalar("range", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        -(p[0].clone() * (-(r.clone() / p[1].clone())).exp() / r)
    }
}
