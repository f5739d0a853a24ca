//! Weakly compressible smoothed particle hydrodynamics, from its Lagrangian
//! L = Σₐ mₐ(|vₐ|²/2 − u(ρₐ)) (Monaghan 2005, Rep. Prog. Phys. 68 1703; Price 2012, J. Comput.
//! Phys. 231 759). The density is a sum over the bodies within reach, ρₐ = Σ_b m_b W(|xₐ − x_b|)
//! (a's own share included), with a smoothing kernel W of support 2h (`smoothing`: Wendland's C²,
//! the term `Sph`, or the cubic spline, `SphCubicSpline`). The equation of state is Tait's,
//! P = B((ρ/ρ₀)^γ − 1), B = ρ₀c₀²/γ, held at zero
//! below ρ₀ (a free surface, where the sum lacks neighbours, would otherwise pull), and u is its
//! integral du/dρ = P/ρ²: for ρ > ρ₀, u = (B/ρ₀)((ρ/ρ₀)^(γ−1) − 1)/(γ − 1) + B(1/ρ − 1/ρ₀), zero
//! below — continuous with its derivative, so the forces −∂(Σ mu)/∂x are the familiar
//! −mₐm_b(Pₐ/ρₐ² + P_b/ρ_b²)∇W and energy and momentum are conserved by construction.
//!
//! Monaghan's artificial viscosity is a Rayleigh function of each pair approaching, s = v_ab·x_ab
//! < 0: F = mₐm_b g (α c₀ h s²/(2ρ₀D) − β h² s³/(3ρ₀D²)), g = −W′(r)/r, D = r² + 0.01h², whose
//! force −∂F/∂vₐ is Monaghan's −mₐm_b Π_ab ∇ₐW with μ = h s/D and Π = (−α c₀ μ + β μ²)/ρ₀. The
//! pair means of the density and the sound speed in Π are taken at rest, ρ₀ and c₀ (they differ
//! from them by about 1% where the flow is weakly compressible), so that Π is a function of the
//! pair alone and its heat is a pair sum like any damped bond's.

use super::smoothing::{Smoothing, WendlandC2};
use super::{Definition, Param, Shape, Site, Spec, Variant};
use crate::real::{dot3, norm2, select, sub3, Real};
use crate::units::Dim;
use std::marker::PhantomData;

pub use super::smoothing::SUPPORT;

/// A Tait fluid smoothed by the kernel `K`.
pub struct TaitFluid<K>(PhantomData<K>);

/// The fluid with Wendland's C² kernel, the one `sph { .. }` gives.
pub type Sph = TaitFluid<WendlandC2>;

/// h, ρ₀, c₀, γ, α, β, in `p`.
const H: usize = 0;
const RHO0: usize = 1;
const C0: usize = 2;
const GAMMA: usize = 3;
const ALPHA: usize = 4;
const BETA: usize = 5;

const PARAMS: &[Param] = &[
    Param::scalar("h", Dim::LENGTH).positive(),
    Param::scalar("rest_density", Dim::DENSITY).positive(),
    Param::scalar("sound_speed", Dim::VELOCITY).positive(),
    Param::scalar("gamma", Dim::NONE).or(7.0).positive(),
    Param::scalar("alpha", Dim::NONE).or(0.0),
    Param::scalar("beta", Dim::NONE).or(0.0),
];

/// `inside(r², q)` while q = r/h < 2, zero (as `zero()`, a value of its dimension) beyond.
fn within<R: Real>(p: &[R], a: &Site<R>, b: &Site<R>, zero: impl Fn() -> R, inside: impl FnOnce(R, R) -> R) -> R {
    let r2 = norm2(&sub3(&a.x, &b.x));
    let reach2 = (p[H].lift(SUPPORT) * p[H].clone()).powi(2);
    select(r2.lt(&reach2), || inside(r2.clone(), r2.clone().sqrt() / p[H].clone()), || zero().lift(0.0) * zero())
}

impl<K: Smoothing> Definition for TaitFluid<K> {
    const SPEC: Spec = Spec { name: K::NAME, keyword: "sph", shape: Shape::Density, params: PARAMS };
    const VARIANT: Option<Variant> = Some(Variant { field: "kernel", value: K::KERNEL });

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        super::fluid_pair::<Self, R>(p, s)
    }

    /// m_b W(|xₐ − x_b|).
    fn density<R: Real>(p: &[R], a: &Site<R>, b: &Site<R>) -> Option<R> {
        let zero = || b.m.clone() / p[H].clone().powi(3);
        Some(within(p, a, b, zero, |_, q| K::weight(&p[H], b.m.clone(), q)))
    }

    /// mₐW(0), bit for bit what `density(p, a, a)` gives.
    fn own_density<R: Real>(p: &[R], a: &Site<R>) -> Option<R> {
        Some(K::own(&p[H], a.m.clone()))
    }

    /// mₐ u(ρ).
    fn internal<R: Real>(p: &[R], a: &Site<R>, rho: R) -> Option<R> {
        let (rho0, gamma) = (p[RHO0].clone(), p[GAMMA].clone());
        let b = rho0.clone() * p[C0].clone().powi(2) / gamma.clone();
        let up = gamma.lift(1.0);
        let squeezed = rho0.lt(&rho);
        let u = |rho: R| {
            let power = ((gamma.clone() - up.clone()) * (rho.clone() / rho0.clone()).ln()).exp();
            b.clone() / rho0.clone() * (power - up.clone()) / (gamma.clone() - up.clone())
                + b.clone() * (up.clone() / rho - up.clone() / rho0.clone())
        };
        // zero below ρ₀, as mₐB/ρ₀ (an energy) times 0: a small tree where u's would be large
        let scale = a.m.clone() * b.clone() / rho0.clone();
        Some(select(squeezed, || a.m.clone() * u(rho), || scale.lift(0.0) * scale.clone()))
    }

    fn rayleigh<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        Some(viscous::<K, R>(p, s, |k1, k2, v| k1 * v.lift(0.5) * v.clone().powi(2) - k2 * v.lift(1.0 / 3.0) * v.powi(3)))
    }

    /// v·∂F/∂v = s ∂F/∂s = k₁s² − k₂s³.
    fn power<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        Some(viscous::<K, R>(p, s, |k1, k2, v| k1 * v.clone().powi(2) - k2 * v.powi(3)))
    }

    /// u divides by γ − 1.
    fn accepts(p: &[f64]) -> Result<(), (&'static str, &'static str)> {
        if p[GAMMA] > 1.0 {
            Ok(())
        } else {
            Err(("gamma", "must exceed 1 (the internal energy divides by γ − 1)"))
        }
    }

    fn dissipates(p: &[f64]) -> bool {
        p[ALPHA] != 0.0 || p[BETA] != 0.0
    }

    fn reach(p: &[f64]) -> f64 {
        SUPPORT * p[H]
    }
}

/// `f(k₁, k₂, s)` for a pair approaching (s = v_ab·x_ab < 0) within reach, with
/// k₁ = mₐm_b g α c₀ h/(ρ₀D) and k₂ = mₐm_b g β h²/(ρ₀D²); zero (as a power) otherwise. The
/// approach is asked first: a pair moving apart (about half of them) costs its closing speed
/// alone, not the kernel's slope it would be multiplied by.
fn viscous<K: Smoothing, R: Real>(p: &[R], s: &[&Site<R>], f: impl FnOnce(R, R, R) -> R) -> R {
    let (a, b) = (s[0], s[1]);
    let closing = dot3(&sub3(&a.v, &b.v), &sub3(&a.x, &b.x));
    let h = p[H].clone();
    // a power's dimension, for the zero branches: m v² / t
    let zero = || a.m.clone() * norm2(&a.v) * p[C0].clone() / h.clone();
    let approaching = closing.lt(&closing.lift(0.0));
    let near = || {
        within(p, a, b, zero, |r2, q| {
            let g = K::g(&h, q);
            let d = r2 + h.lift(0.01) * h.clone().powi(2);
            let mm = a.m.clone() * b.m.clone() * g / p[RHO0].clone();
            let k1 = mm.clone() * p[ALPHA].clone() * p[C0].clone() * h.clone() / d.clone();
            let k2 = mm * p[BETA].clone() * h.clone().powi(2) / d.powi(2);
            f(k1, k2, closing.clone())
        })
    };
    select(approaching, near, || zero().lift(0.0) * zero())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::smoothing::CubicSpline;
    use crate::terms::Kind;
    use proptest::prelude::*;

    fn body(x: [f64; 3], m: f64) -> Site<f64> {
        Site { x, v: [0.0; 3], m, q: 0.0, colour: [0.0; 2] }
    }

    proptest! {
        /// u′(ρ) = P/ρ² with Tait's P above ρ₀ and none below (central differences), and u is
        /// continuous at ρ₀ where the pressure starts.
        #[test]
        fn internal_energy_is_the_integral_of_the_pressure(rho in 0.5f64..2.0, gamma in 1.5f64..8.0, c0 in 0.5f64..20.0) {
            let p = [0.1, 1.0, c0, gamma, 0.0, 0.0];
            let a = body([0.0; 3], 1.0);
            let u = |r: f64| Sph::internal(&p, &a, r).unwrap();
            let pressure = if rho > 1.0 { c0 * c0 / gamma * (rho.powf(gamma) - 1.0) } else { 0.0 };
            let eps = 1e-6;
            let slope = (u(rho + eps) - u(rho - eps)) / (2.0 * eps);
            prop_assume!((rho - 1.0).abs() > 2.0 * eps);
            prop_assert!((slope - pressure / (rho * rho)).abs() <= 1e-6 * (1.0 + c0 * c0), "{slope} vs {}", pressure / (rho * rho));
            prop_assert!(u(1.0 + 1e-9).abs() < 1e-12 * c0 * c0 && u(1.0) == 0.0);
        }
    }

    /// The fluid's kinds: one per smoothing kernel.
    const FLUIDS: [Kind; 2] = [Kind::Sph, Kind::SphCubicSpline];

    proptest! {
        /// The closed form of a body's own share is the pair form at zero distance, bit for bit.
        #[test]
        fn own_density_is_the_pair_form_at_zero_distance(h in 0.01f64..10.0, m in 0.01f64..100.0, x in -5.0f64..5.0) {
            let p = [h, 1.0, 1.0, 7.0, 0.0, 0.0];
            let a = body([x, -x, 2.0 * x], m);
            for k in FLUIDS {
                prop_assert_eq!(k.own_density(&p, &a).unwrap().to_bits(), k.density(&p, &a, &a).unwrap().to_bits());
            }
        }

        /// g = −W′(r)/r: the viscosity's g is the slope of the density's kernel (central
        /// differences), away from the cubic spline's seam at q = 1.
        #[test]
        fn g_is_the_kernels_slope_over_r(h in 0.05f64..5.0, q in 0.01f64..1.99) {
            let p = [h, 1.0, 1.0, 7.0, 0.0, 0.0];
            let (source, eps) = (body([0.0; 3], 1.0), 1e-6 * h);
            prop_assume!((q - 1.0).abs() > 1e-4);
            let w = |k: Kind, r: f64| k.density(&p, &body([r, 0.0, 0.0], 1.0), &source).unwrap();
            let r = q * h;
            let g = [WendlandC2::g(&h, q), CubicSpline::g(&h, q)];
            for (k, g) in FLUIDS.into_iter().zip(g) {
                let slope = (w(k, r + eps) - w(k, r - eps)) / (2.0 * eps);
                prop_assert!((g + slope / r).abs() <= 1e-6 * g.abs().max(1.0 / h.powi(5)), "{k:?}: g {g} vs {}", -slope / r);
            }
        }
    }

    /// The cubic spline's two pieces meet at q = 1 with their value and slope.
    #[test]
    fn the_cubic_splines_pieces_meet() {
        let (h, source) = (0.7, body([0.0; 3], 1.0));
        let p = [h, 1.0, 1.0, 7.0, 0.0, 0.0];
        let w = |r: f64| Kind::SphCubicSpline.density(&p, &body([r, 0.0, 0.0], 1.0), &source).unwrap();
        let w0 = 1.0 / (std::f64::consts::PI * h.powi(3));
        assert!((w(h) - w0 / 4.0).abs() < 1e-15 * w0);
        assert!((w(h * (1.0 - 1e-9)) - w(h * (1.0 + 1e-9))).abs() < 1e-8 * w0);
        let g = |q: f64| CubicSpline::g(&h, q);
        assert!((g(1.0 - 1e-12) - g(1.0)).abs() < 1e-9 * g(1.0) && (g(1.0) * h.powi(5) * std::f64::consts::PI - 0.75).abs() < 1e-12);
    }

    /// A model (a certificate's) whose fluid or wall means nothing is refused with the reason.
    #[test]
    fn a_model_with_a_meaningless_fluid_is_refused() {
        use crate::model::{Body, Model, TermInstance, UnitSystem};
        let refused = |kind: Kind, params: Vec<f64>| {
            let body = Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
            let model = Model {
                units: UnitSystem::Reduced,
                cell: None,
                bodies: vec![body.clone(), body],
                terms: vec![TermInstance { kind, sites: vec![], params }],
                constraints: vec![],
                thermostat: None,
                floor: None,
                pins: vec![],
            };
            model.validate().err()
        };
        assert_eq!(refused(Kind::Sph, vec![0.1, 1.0, 1.0, 7.0, 0.0, 0.0]), None);
        assert_eq!(refused(Kind::Sph, vec![0.0, 1.0, 1.0, 7.0, 0.0, 0.0]).unwrap(), "term 0 (Sph): h must be positive");
        assert_eq!(
            refused(Kind::Sph, vec![0.1, 1.0, -1.0, 7.0, 0.0, 0.0]).unwrap(),
            "term 0 (Sph): sound_speed must be positive"
        );
        assert!(refused(Kind::Sph, vec![0.1, 1.0, 1.0, 1.0, 0.0, 0.0]).unwrap().contains("gamma must exceed 1"));
        assert!(refused(Kind::Wall, vec![0.0, 0.0, 0.0, 0.0, 1.0]).unwrap().contains("normal must not be zero"));
    }

    /// W integrates to one: the density a body of mass m spreads over a fine lattice of points
    /// sums, times the cell volume, to m. And W vanishes at its support 2h, with its slope.
    #[test]
    fn each_kernel_is_normalised_and_vanishes_at_its_support() {
        let (h, step) = (1.0, 0.05);
        let p = [h, 1.0, 1.0, 7.0, 0.0, 0.0];
        let n = (SUPPORT * h / step).ceil() as i32 + 1;
        let source = body([0.0; 3], 2.0);
        for k in FLUIDS {
            let mut total = 0.0;
            for i in -n..=n {
                for j in -n..=n {
                    for l in -n..=n {
                        let at = body([i as f64 * step, j as f64 * step, l as f64 * step], 1.0);
                        total += k.density(&p, &at, &source).unwrap() * step.powi(3);
                    }
                }
            }
            assert!((total - 2.0).abs() < 1e-4, "{k:?}: {total}");
            let edge = |r: f64| k.density(&p, &body([r, 0.0, 0.0], 1.0), &source).unwrap();
            assert_eq!(edge(SUPPORT * h), 0.0);
            assert!(edge(SUPPORT * h * (1.0 - 1e-4)) < 1e-11, "{k:?}");
            assert_eq!(k.reach(&p), 2.0);
        }
    }
}
