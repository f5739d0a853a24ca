//! Coulomb interaction between every pair of charges: V = k qᵢ qⱼ / r (bare, no cutoff).

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{norm2, sub3, Real};
use crate::units::Dim;

pub struct Coulomb;

impl Definition for Coulomb {
    const SPEC: Spec =
        Spec { name: "Coulomb", keyword: "coulomb", shape: Shape::Pairwise, params: &[Param::scalar("k", Dim::COULOMB)] };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        p[0].clone() * s[0].q.clone() * s[1].q.clone() / norm2(&sub3(&s[1].x, &s[0].x)).sqrt()
    }
}
