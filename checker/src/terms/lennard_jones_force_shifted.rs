//! Lennard-Jones with energy and force shifted to zero at the cutoff:
//! V(r) − V(r_c) − (r − r_c) V′(r_c) for r < r_c, V′(r) = 24ε[(σ/r)⁶ − 2(σ/r)¹²]/r.

use super::lennard_jones::{cut, lj, PARAMS};
use super::{constant, Definition, Shape, Site, Spec};
use crate::real::Real;

pub struct LennardJonesForceShifted;

impl Definition for LennardJonesForceShifted {
    const SPEC: Spec =
        Spec { name: "LennardJonesForceShifted", keyword: "lj_force_shifted", shape: Shape::Pairwise, params: PARAMS };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (at_cutoff, slope, rc) = (constant::<Self, R>(p, 0), constant::<Self, R>(p, 1), p[2].clone());
        cut(p, s, rc.clone(), |r2| lj(&p[0], &p[1], r2.clone()) - at_cutoff - (r2.sqrt() - rc) * slope)
    }

    /// V(r_c) and the slope V′(r_c).
    fn constants<R: Real>(p: &[R]) -> Vec<R> {
        let (eps, sigma, rc) = (&p[0], &p[1], p[2].clone());
        let s6 = (sigma.clone() / rc.clone()).powi(6);
        let slope = eps.lift(24.0) * eps.clone() * (s6.clone() - s6.lift(2.0) * s6.powi(2)) / rc.clone();
        vec![lj(eps, sigma, rc.powi(2)), slope]
    }
}
