//! A toy of the strong force between colour charges: V = (cᵢ·cⱼ)(4α/r − 3σr), the colour
//! charges being weights of SU(3)'s fundamental representation (red, green, blue, and the
//! antiquarks' negatives; |c|² = 1/3). For a quark and its antiquark (a colour singlet meson)
//! cᵢ·cⱼ = −1/3: the Cornell potential −(4/3)α/r + σr, Coulomb-like at short range and
//! confining at long range. For two quarks of different colours cᵢ·cⱼ = −1/6: −(2/3)α/r +
//! (σ/2)r, the antitriplet channel. A classical toy, not QCD: the colours do not rotate.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct QcdCoulomb;

impl Definition for QcdCoulomb {
    const SPEC: Spec = Spec {
        name: "QcdCoulomb",
        keyword: "qcd",
        shape: Shape::Pairwise,
        params: &[Param::scalar("alpha", Dim::ENERGY_LENGTH), Param::scalar("sigma", Dim([1, 1, -2, 0]))],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let r = norm2(&sub3(&s[1].x, &s[0].x)).sqrt();
        let cc = s[0].colour[0].clone() * s[1].colour[0].clone() + s[0].colour[1].clone() * s[1].colour[1].clone();
        cc.clone() * (cc.lift(4.0) * p[0].clone() / r.clone() - cc.lift(3.0) * p[1].clone() * r)
    }
}
