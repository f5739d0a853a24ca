//! Lennard-Jones shifted to zero at the cutoff: V(r) − V(r_c) for r < r_c (continuous energy,
//! the force still jumps).

use super::lennard_jones::{cut, lj, PARAMS};
use super::{constant, Definition, Shape, Site, Spec};
use crate::real::Real;

pub struct LennardJonesShifted;

impl Definition for LennardJonesShifted {
    const SPEC: Spec = Spec { name: "LennardJonesShifted", keyword: "lj_shifted", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let at_cutoff = constant::<Self, R>(p, 0);
        cut(p, s, p[2].clone(), |r2| lj(&p[0], &p[1], r2) - at_cutoff)
    }

    /// V(r_c).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        vec![lj(&p[0], &p[1], p[2].clone().powi(2))]
    }
}
