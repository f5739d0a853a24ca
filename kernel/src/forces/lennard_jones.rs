//! Lennard-Jones in its three cut variants, from r² (no square root inside the cutoff except
//! for the force-shifted one): V = 4ε(s¹² − s⁶), s = σ/r; the force on i is
//! 24ε(s⁶ − 2s¹²)/r² · d.

use super::{Jet, Lane, Paired};

/// One instance's constants: 4ε, 24ε, σ², the cutoff r_c (and r_c²), and what is taken off
/// inside it: the energy shift, and for the force-shifted variant the slope V′(r_c).
#[derive(Clone, Copy)]
pub struct Lj {
    eps4: f64,
    eps24: f64,
    sigma2: f64,
    /// 24ε/σ²: s = s⁶ · 24ε(1 − 2s⁶) · s² / σ² needs no 1/r² of its own.
    f24: f64,
    rc: f64,
    rc2: f64,
    shift: f64,
    slope: f64,
}

impl Lj {
    /// Cut at `rc`, with `shift` taken off the energy inside (WCA's −ε raises it).
    pub(crate) fn new(eps: f64, sigma: f64, rc: f64, shift: f64) -> Lj {
        let (eps24, sigma2) = (24.0 * eps, sigma * sigma);
        Lj { eps4: 4.0 * eps, eps24, sigma2, f24: eps24 / sigma2, rc, rc2: rc * rc, shift, slope: 0.0 }
    }

    pub(crate) fn reach2(&self) -> f64 {
        self.rc2
    }

    /// The term with its shift taken off, inside the cutoff: (V, s) at r².
    #[inline(always)]
    pub(crate) fn shifted_at<L: Lane>(&self, r2: L) -> (L, L) {
        let (v, s) = self.at(r2);
        (v - self.shift, s)
    }

    /// The force-shifted form: V − V(r_c) − (r − r_c) V′(r_c), and its s.
    #[inline(always)]
    fn force_shifted_at<L: Lane>(&self, r2: L) -> (L, L) {
        let r = r2.sqrt();
        let (v, s) = self.at(r2);
        (v - self.shift - (r - self.rc) * self.slope, s - L::splat(self.slope) / r)
    }

    /// The plain term's radial derivatives at r² for parameters (ε, σ, ...): with u = (σ/r)⁶,
    /// s = 24ε(u − 2u²)/r², s_r = 96ε(7u² − 2u)/r⁴, ∂s/∂ε = 24(u − 2u²)/r², ∂s/∂σ =
    /// (144ε/σ)(u − 4u²)/r², ∂V/∂ε = 4(u² − u), ∂V/∂σ = (24ε/σ)(2u² − u). One division a row,
    /// as in the force (1/r²; 144ε/σ is a scalar of the instance): the pullback's rows waited
    /// on three.
    #[inline(always)]
    pub(crate) fn jet_at<L: Lane>(&self, p: &[f64], r2: L) -> Jet<L> {
        let (eps, sigma) = (p[0], p[1]);
        let inv = L::splat(1.0) / r2;
        let s2 = inv * self.sigma2;
        let u = s2 * s2 * s2;
        let attraction = (u - u * 2.0 * u) * inv;
        let s = attraction * self.eps24;
        let s_r = (u * 7.0 * u - u * 2.0) * (96.0 * eps) * inv * inv;
        let ds_sigma = (u - u * 4.0 * u) * (144.0 * eps / sigma) * inv;
        let dv = [(u * u - u) * 4.0, (u * 2.0 * u - u) * (24.0 * eps / sigma), L::splat(0.0)];
        Jet { s, s_r, ds: [attraction * 24.0, ds_sigma, L::splat(0.0)], dv }
    }

    /// The plain term and its derivative at r²: (V, dV/dr / r).
    #[inline(always)]
    pub(crate) fn at<L: Lane>(&self, r2: L) -> (L, L) {
        let s2 = L::splat(self.sigma2) / r2; // the one division
        let s6 = s2 * s2 * s2;
        // 4ε s⁶(s⁶ − 1) and s⁶ · (24ε/σ²)(1 − 2s⁶) · s², each with one product and sum fused:
        // five multiplies for the force, the division included (the multiply pipes are what a
        // cluster pair waits on)
        let v = s6.mul_add(s6 * self.eps4, -(s6 * self.eps4));
        (v, s6 * s6.mul_add(L::splat(-2.0 * self.f24), L::splat(self.f24)) * s2)
    }
}

pub struct Plain;
pub struct Shifted;
pub struct ForceShifted;

impl Paired for Plain {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        Lj::new(p[0], p[1], p[2], 0.0)
    }
    fn reach2(lj: &Lj) -> f64 {
        lj.rc2
    }
    #[inline(always)]
    fn radial<L: Lane>(lj: &Lj, r2: L, _: [L; 4], _colour: L) -> (L, L) {
        lj.shifted_at(r2)
    }
    #[inline(always)]
    fn jet<L: Lane>(lj: &Lj, p: &[f64], r2: L) -> Option<Jet<L>> {
        Some(lj.jet_at(p, r2))
    }
}

impl Paired for Shifted {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        let lj = Lj::new(p[0], p[1], p[2], 0.0);
        Lj { shift: lj.at(lj.rc2).0, ..lj } // V(r_c)
    }
    fn reach2(lj: &Lj) -> f64 {
        lj.rc2
    }
    #[inline(always)]
    fn radial<L: Lane>(lj: &Lj, r2: L, _: [L; 4], _colour: L) -> (L, L) {
        lj.shifted_at(r2)
    }
    /// The shift is a constant: the force's derivatives are the plain term's. The energy's
    /// lose the shift's, ∂V(r_c)/∂p, and ∂V(r_c)/∂r_c = V′(r_c) = r_c s(r_c).
    #[inline(always)]
    fn jet<L: Lane>(lj: &Lj, p: &[f64], r2: L) -> Option<Jet<L>> {
        let (here, at_rc) = (lj.jet_at(p, r2), lj.jet_at(p, lj.rc2));
        let dv = [here.dv[0] - at_rc.dv[0], here.dv[1] - at_rc.dv[1], L::splat(-lj.rc * at_rc.s)];
        Some(Jet { dv, ..here })
    }
}

impl Paired for ForceShifted {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        let lj = Lj::new(p[0], p[1], p[2], 0.0);
        let (vc, sc) = lj.at(lj.rc2);
        Lj { shift: vc, slope: sc * lj.rc, ..lj } // V′(r_c)
    }
    fn reach2(lj: &Lj) -> f64 {
        lj.rc2
    }
    #[inline(always)]
    fn radial<L: Lane>(lj: &Lj, r2: L, _: [L; 4], _colour: L) -> (L, L) {
        lj.force_shifted_at(r2)
    }
    /// With V′(r_c) = r_c s(r_c) taken off the force: s − V′(r_c)/r, s_r + V′(r_c)/r³, and the
    /// slope's own derivatives, ∂V′(r_c)/∂σ = r_c ∂s/∂σ(r_c), ∂V′(r_c)/∂r_c = V″(r_c). The
    /// energy V(r) − V(r_c) − (r − r_c)V′(r_c): ∂/∂p of each part, and ∂/∂r_c = −(r − r_c)V″(r_c).
    #[inline(always)]
    fn jet<L: Lane>(lj: &Lj, p: &[f64], r2: L) -> Option<Jet<L>> {
        let (here, at_rc) = (lj.jet_at(p, r2), lj.jet_at(p, lj.rc2));
        let r = r2.sqrt();
        let curvature = at_rc.s + lj.rc2 * at_rc.s_r;
        let slope = L::splat(lj.slope);
        let out = r - L::splat(lj.rc);
        let dv = std::array::from_fn(|k| match k {
            2 => out * -curvature,
            _ => here.dv[k] - at_rc.dv[k] - out * (lj.rc * at_rc.ds[k]),
        });
        Some(Jet {
            dv,
            s: here.s - slope / r,
            s_r: here.s_r + slope / (r2 * r),
            ds: [
                (here.s - slope / r) / L::splat(p[0]),
                here.ds[1] - L::splat(lj.rc * at_rc.ds[1]) / r,
                L::splat(-curvature) / r,
            ],
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

    /// The hand-derived jets are the definition's own radial derivatives, of the force and of the
    /// energy.
    #[test]
    fn jets_are_the_definitions_derivatives() {
        use super::{ForceShifted, Plain, Shifted};
        use crate::derivatives::exact::{radial, radial_potential, radial_sensitivities};
        use crate::forces::dual::Rng;
        use crate::forces::{Jet, Paired};
        fn holds<T: Paired>(kind: Kind, p: &[f64], r: f64) {
            let jet: Jet = T::jet(&T::row(p), p, r * r).unwrap();
            let exact = radial(kind, p, [1.0; 4], [[0.0; 2]; 2], r);
            let ds = radial_sensitivities(kind, p, [1.0; 4], [[0.0; 2]; 2], r, &(0..p.len()).collect::<Vec<_>>());
            let near = |a: f64, b: f64, scale: f64, what: &str| {
                assert!((a - b).abs() <= 1e-12 * scale.max(1e-8), "{kind:?} r {r} {what}: {a} vs {b}")
            };
            let close = |a: f64, b: f64, what: &str| near(a, b, b.abs(), what);
            close(jet.s, exact.s, "s");
            close(jet.s_r, exact.s_r, "s_r");
            for (k, d) in ds.iter().enumerate() {
                close(jet.ds[k], *d, &format!("ds[{k}]"));
            }
            // the cut variants' energies take off their values at r_c, which near r_c leaves a
            // small difference of large parts: the plain term's ∂V/∂p is their size
            let plain = super::Lj::new(p[0], p[1], 1.0, 0.0).jet_at(p, r * r);
            let (_, dv) = radial_potential(kind, p, [1.0; 4], [[0.0; 2]; 2], r, &(0..p.len()).collect::<Vec<_>>());
            for (k, d) in dv.iter().enumerate() {
                near(jet.dv[k], *d, d.abs().max(plain.dv[k].abs()), &format!("dv[{k}]"));
            }
        }
        let mut rng = Rng::new(3);
        for _ in 0..200 {
            let p = [rng.uniform(0.1, 5.0), rng.uniform(0.5, 2.0), rng.uniform(2.0, 6.0)];
            let r = rng.uniform(0.7, 0.999) * p[2];
            holds::<Plain>(Kind::LennardJones, &p, r);
            holds::<Shifted>(Kind::LennardJonesShifted, &p, r);
            holds::<ForceShifted>(Kind::LennardJonesForceShifted, &p, r);
            holds::<crate::forces::wca::Fast>(Kind::Wca, &p[..2], rng.uniform(0.8, 1.12) * p[1]);
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
