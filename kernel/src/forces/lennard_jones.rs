//! Lennard-Jones in its three cut variants, from r² (no square root inside the cutoff except
//! for the force-shifted one): V = 4ε(s¹² − s⁶), s = σ/r; the force on i is
//! 24ε(s⁶ − 2s¹²)/r² · d.

use super::Paired;

/// The plain term and its derivative at r²: (V, dV/dr / r).
pub(crate) fn lj(eps: f64, sigma: f64, r2: f64) -> (f64, f64) {
    let inv = 1.0 / r2; // the one division
    let s2 = sigma * sigma * inv;
    let s6 = s2 * s2 * s2;
    (4.0 * eps * (s6 * s6 - s6), 24.0 * eps * (s6 - 2.0 * s6 * s6) * inv)
}

/// Within the cutoff, `inside(r²)` gives (V, dV/dr / r); beyond, nothing. (Computing both sides
/// and selecting without a branch was measured slower on lj_32k.)
pub(crate) fn cut(
    d: [f64; 3],
    rc: f64,
    inside: impl FnOnce(f64) -> (f64, f64),
) -> Result<([f64; 3], f64), &'static str> {
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if r2 >= rc * rc {
        return Ok(([0.0; 3], 0.0));
    }
    if r2 == 0.0 {
        return Err("at the same point, where the pair force is infinite");
    }
    let (v, s) = inside(r2);
    Ok((d.map(|c| c * s), v))
}

pub struct Plain;
pub struct Shifted;
pub struct ForceShifted;

impl Paired for Plain {
    fn eval(p: &[f64], d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        cut(d, p[2], |r2| lj(p[0], p[1], r2))
    }
}

impl Paired for Shifted {
    fn eval(p: &[f64], d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let vc = lj(p[0], p[1], p[2] * p[2]).0;
        cut(d, p[2], |r2| {
            let (v, s) = lj(p[0], p[1], r2);
            (v - vc, s)
        })
    }
}

impl Paired for ForceShifted {
    fn eval(p: &[f64], d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let rc = p[2];
        let (vc, sc) = lj(p[0], p[1], rc * rc);
        let slope = sc * rc; // V′(r_c)
        cut(d, rc, |r2| {
            let r = r2.sqrt();
            let (v, s) = lj(p[0], p[1], r2);
            (v - vc - (r - rc) * slope, s - slope / r)
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        /// Random bodies lie up to 11 apart: cutoffs from 2 to 12 test both sides of r_c.
        #[test]
        fn forces_are_minus_gradients(eps in 0.1f64..5.0, sigma in 0.5f64..2.0, rc in 2.0f64..12.0, seed in any::<u64>()) {
            for kind in [Kind::LennardJones, Kind::LennardJonesShifted, Kind::LennardJonesForceShifted] {
                assert_matches_definition(kind, &[eps, sigma, rc], seed, 1.0);
            }
        }

        #[test]
        fn close_contact_is_finite(eps in 0.1f64..5.0, sigma in 0.5f64..2.0, tiny in 0.05f64..0.5, seed in any::<u64>()) {
            assert_matches_definition(Kind::LennardJonesShifted, &[eps, sigma, 2.5], seed, tiny);
        }
    }

    #[test]
    fn shifted_variants_vanish_at_the_cutoff() {
        use super::{ForceShifted, Shifted};
        use crate::forces::Paired;
        let just_inside = [2.5f64.next_down(), 0.0, 0.0];
        let (f, v) = Shifted::eval(&[1.0, 1.0, 2.5], just_inside, [1.0; 4], 0.0).unwrap();
        assert!(v.abs() < 1e-15 && f[0].abs() > 1e-3, "energy continuous, force not: {v} {f:?}");
        let (f, v) = ForceShifted::eval(&[1.0, 1.0, 2.5], just_inside, [1.0; 4], 0.0).unwrap();
        assert!(v.abs() < 1e-15 && f[0].abs() < 1e-13, "both continuous: {v} {f:?}");
    }
}
