//! Lennard-Jones in its three cut variants, from r² (no square root inside the cutoff except
//! for the force-shifted one): V = 4ε(s¹² − s⁶), s = σ/r; the force on i is
//! 24ε(s⁶ − 2s¹²)/r² · d.

use super::Paired;

/// One instance's constants: 4ε, 24ε, σ², the cutoff r_c (and r_c²), and what is taken off
/// inside it: the energy shift, and for the force-shifted variant the slope V′(r_c).
#[derive(Clone, Copy)]
pub struct Lj {
    eps4: f64,
    eps24: f64,
    sigma2: f64,
    rc: f64,
    rc2: f64,
    shift: f64,
    slope: f64,
}

impl Lj {
    /// Cut at `rc`, with `shift` taken off the energy inside (WCA's −ε raises it).
    pub(crate) fn new(eps: f64, sigma: f64, rc: f64, shift: f64) -> Lj {
        Lj { eps4: 4.0 * eps, eps24: 24.0 * eps, sigma2: sigma * sigma, rc, rc2: rc * rc, shift, slope: 0.0 }
    }

    /// The term with its shift taken off, inside the cutoff.
    #[inline(always)]
    pub(crate) fn shifted(&self, d: [f64; 3]) -> Result<([f64; 3], f64), &'static str> {
        cut(d, self.rc2, |r2| self.shifted_at(r2))
    }

    #[inline(always)]
    pub(crate) fn shifted_at(&self, r2: f64) -> (f64, f64) {
        let (v, s) = self.at(r2);
        (v - self.shift, s)
    }

    /// The force-shifted form: V − V(r_c) − (r − r_c) V′(r_c), and its derivative.
    #[inline(always)]
    fn force_shifted_at(&self, r2: f64) -> (f64, f64) {
        let r = r2.sqrt();
        let (v, s) = self.at(r2);
        (v - self.shift - (r - self.rc) * self.slope, s - self.slope / r)
    }

    /// The plain term and its derivative at r²: (V, dV/dr / r).
    #[inline(always)]
    pub(crate) fn at(&self, r2: f64) -> (f64, f64) {
        let inv = 1.0 / r2; // the one division
        let s2 = self.sigma2 * inv;
        let s6 = s2 * s2 * s2;
        (self.eps4 * (s6 * s6 - s6), self.eps24 * (s6 - 2.0 * s6 * s6) * inv)
    }
}

/// Within the cutoff (r² < `rc2`), `inside(r²)` gives (V, dV/dr / r); beyond, nothing.
/// (Computing both sides and selecting without a branch was measured slower on lj_32k.)
#[inline(always)]
pub(crate) fn cut(
    d: [f64; 3],
    rc2: f64,
    inside: impl FnOnce(f64) -> (f64, f64),
) -> Result<([f64; 3], f64), &'static str> {
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if r2 >= rc2 {
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
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        Lj::new(p[0], p[1], p[2], 0.0)
    }
    #[inline(always)]
    fn eval(lj: &Lj, d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        lj.shifted(d)
    }
}

impl Paired for Shifted {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        let lj = Lj::new(p[0], p[1], p[2], 0.0);
        Lj { shift: lj.at(lj.rc2).0, ..lj } // V(r_c)
    }
    #[inline(always)]
    fn eval(lj: &Lj, d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        lj.shifted(d)
    }
}

impl Paired for ForceShifted {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        let lj = Lj::new(p[0], p[1], p[2], 0.0);
        let (vc, sc) = lj.at(lj.rc2);
        Lj { shift: vc, slope: sc * lj.rc, ..lj } // V′(r_c)
    }
    #[inline(always)]
    fn eval(lj: &Lj, d: [f64; 3], _: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        cut(d, lj.rc2, |r2| lj.force_shifted_at(r2))
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
        let p = [1.0, 1.0, 2.5];
        let (f, v) = Shifted::eval(&Shifted::row(&p), just_inside, [1.0; 4], 0.0).unwrap();
        assert!(v.abs() < 1e-15 && f[0].abs() > 1e-3, "energy continuous, force not: {v} {f:?}");
        let (f, v) = ForceShifted::eval(&ForceShifted::row(&p), just_inside, [1.0; 4], 0.0).unwrap();
        assert!(v.abs() < 1e-15 && f[0].abs() < 1e-13, "both continuous: {v} {f:?}");
    }
}
