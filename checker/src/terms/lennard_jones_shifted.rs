//! Lennard-Jones shifted to zero at the cutoff: V(r) − V(r_c) for r < r_c (continuous energy,
//! the force still jumps).

use super::lennard_jones::{cut, lj, prepared, PARAMS};
use super::{constant, Definition, Shape, Site, Spec};
use crate::real::Real;

pub struct LennardJonesShifted;

impl Definition for LennardJonesShifted {
    const SPEC: Spec = Spec { name: "LennardJonesShifted", keyword: "lj_shifted", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = |k| constant::<Self, R>(p, k);
        cut(p, s, c(2), |r2| lj(&c(0), &c(1), r2) - c(3))
    }

    /// 4ε, σ², r_c² (`prepared`), then V(r_c).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        let mut c = prepared(&p[0], &p[1], p[2].clone());
        c.push(lj(&c[0], &c[1], c[2].clone()));
        c
    }
}
