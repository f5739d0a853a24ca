//! Coulomb with a cutoff and a reaction field (the medium beyond r_c a dielectric ε_rf):
//! V = k qᵢ qⱼ (1/r + k_rf r² − c_rf) for r < r_c, with k_rf = (ε_rf − 1)/((2ε_rf + 1) r_c³)
//! and c_rf = 1/r_c + k_rf r_c², so V(r_c) = 0. ε_rf = 1 is a plain shifted cutoff.

use super::lennard_jones::cut;
use super::{Definition, Param, Shape, Site, Spec};
use crate::real::Real;
use crate::units::Dim;

pub struct CoulombReactionField;

impl Definition for CoulombReactionField {
    const SPEC: Spec = Spec {
        name: "CoulombReactionField",
        keyword: "coulomb_rf",
        shape: Shape::Pairwise,
        params: &[
            Param::scalar("k", Dim::COULOMB),
            Param::scalar("cutoff", Dim::LENGTH),
            Param::scalar("epsilon_rf", Dim::NONE).or(1.0),
        ],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (rc, e) = (p[1].clone(), p[2].clone());
        let krf = (e.clone() - e.lift(1.0)) / ((e.lift(2.0) * e.clone() + e.lift(1.0)) * rc.clone().powi(3));
        let crf = rc.lift(1.0) / rc.clone() + krf.clone() * rc.clone().powi(2);
        let qq = p[0].clone() * s[0].q.clone() * s[1].q.clone();
        // the zero beyond the cutoff must be an energy: k q q / r_c times 0
        let scaled = [qq.clone() / rc.clone()];
        cut(&scaled, s, rc.powi(2), |r2| qq * (r2.clone().sqrt().powi(-1) + krf * r2 - crf))
    }
}
