//! Lennard-Jones with energy and force shifted to zero at the cutoff:
//! V(r) − V(r_c) − (r − r_c) V′(r_c) for r < r_c, V′(r) = 24ε[(σ/r)⁶ − 2(σ/r)¹²]/r.

use super::lennard_jones::{cut, lj, prepared, PARAMS};
use super::{constant, Definition, Shape, Site, Spec};
use crate::real::Real;

pub struct LennardJonesForceShifted;

impl Definition for LennardJonesForceShifted {
    const SPEC: Spec =
        Spec { name: "LennardJonesForceShifted", keyword: "lj_force_shifted", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let c = |k| constant::<Self, R>(p, k);
        cut(p, s, c(2), |r2| lj(&c(0), &c(1), r2.clone()) - c(3) - (r2.sqrt() - p[2].clone()) * c(4))
    }

    /// 4ε, σ², r_c² (`prepared`), then V(r_c) and the slope V′(r_c).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        let (eps, sigma, rc) = (&p[0], &p[1], p[2].clone());
        let s6 = (sigma.clone() / rc.clone()).powi(6);
        let slope = eps.lift(24.0) * eps.clone() * (s6.clone() - s6.lift(2.0) * s6.powi(2)) / rc.clone();
        let mut c = prepared(eps, sigma, rc);
        c.extend([lj(&c[0], &c[1], c[2].clone()), slope]);
        c
    }
}
