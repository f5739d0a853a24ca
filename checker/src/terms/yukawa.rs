//! Screened Coulomb (Yukawa) between every pair of charges: V = k qᵢ qⱼ e^{−r/λ} / r, λ the
//! screening length (a Debye length in a plasma, a fifth force's range).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct Yukawa;

impl Definition for Yukawa {
    const SPEC: Spec = Spec {
        name: "Yukawa",
        keyword: "yukawa",
        shape: Shape::Pairwise,
        params: &[Param::scalar("k", Dim::COULOMB), Param::scalar("range", Dim::LENGTH)],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        p[0].clone() * s[0].q.clone() * s[1].q.clone() * (-(r.clone() / p[1].clone())).exp() / r
    }
}
