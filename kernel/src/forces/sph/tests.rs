//! SPH's fast force against its definition, and its threads against one.

use super::super::{group, Frame};
use crate::forces::dual::Rng;
use lagra_checker::model::{Body, Cell, Model, Snapshot, TermInstance, UnitSystem};
use lagra_checker::quantities::Lifted;
use lagra_checker::terms::Kind;
use proptest::prelude::*;

/// `n` bodies of random masses scattered about a cube 3h wide (jittered cubic lattice), with
/// random velocities; ρ₀ at `squeeze` times the bodies' mean density, so that some are above
/// it (pressed) and some below (no pressure); in a periodic box along z if `periodic`. The
/// seed's parity picks the kernel: Wendland's C² (`Sph`) or the cubic spline.
fn fluid(seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Fluid3 {
    block(5, seed, squeeze, alpha, beta, periodic)
}

/// `fluid` with `side`³ bodies.
fn block(side: usize, seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Fluid3 {
    let mut rng = Rng::new(seed);
    let h = 0.3;
    let x: Vec<[f64; 3]> = (0..side * side * side)
        .map(|k| {
            let ijk = [k % side, (k / side) % side, k / (side * side)];
            std::array::from_fn(|c| (ijk[c] as f64 + 0.5) * 0.2 + rng.uniform(-0.06, 0.06))
        })
        .collect();
    let v = (0..x.len()).map(|_| std::array::from_fn(|_| rng.uniform(-1.0, 1.0))).collect();
    let bodies: Vec<Body> = (0..x.len())
        .map(|_| Body {
            mass: rng.uniform(0.5, 1.5) * 0.008,
            charge: 0.0,
            colour: [0.0; 2],
            moments: None,
            solid: None,
        })
        .collect();
    let rho0 = squeeze * 1.0;
    let kind = if seed % 2 == 0 { Kind::Sph } else { Kind::SphCubicSpline };
    let term = TermInstance { kind, sites: vec![], params: vec![h, rho0, 10.0, 7.0, alpha, beta] };
    // one z period holds the five layers and more than twice the reach 2h = 0.6 (the nearest image
    // is the only one within reach: a shorter period would cut pairs at its half)
    let cell = periodic.then_some(Cell { size: [10.0, 10.0, 0.25 * side as f64], periodic: [false, false, true] });
    let model = Model {
        units: UnitSystem::Reduced,
        cell,
        bodies,
        terms: vec![term],
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    };
    (model, x, v)
}

type Fluid3 = (Model, Vec<[f64; 3]>, Vec<[f64; 3]>);

fn fast(model: &Model, x: &[[f64; 3]], v: &[[f64; 3]]) -> (Vec<[f64; 3]>, f64) {
    let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
    let (q, c) = (vec![0.0; x.len()], vec![[0.0; 2]; x.len()]);
    let mut f = vec![[0.0; 3]; x.len()];
    let e = group(model.terms[0].kind, &[(0, &model.terms[0])], model, &None)
        .accumulate(&Frame { x, v, m: &m, q: &q, c: &c }, &mut f, true)
        .unwrap();
    (f, e)
}

/// On threads each body adds its pairs' shares in the pairs' order: the forces, energy and
/// virial are the bits of one thread's loop over the pairs, at a first evaluation and at a
/// second at the same positions with other velocities (the pairs' fixed parts kept), for
/// 1,000 bodies (past `SPREAD_FROM`) on pools of 4 and 7 threads (past `SPREAD_THREADS`).
#[test]
fn threads_give_the_bits_of_one() {
    for (seed, periodic) in [(4, false), (7, true)] {
        let (model, x, v) = block(10, seed, 0.8, 0.5, 1.0, periodic);
        let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
        let (q, c) = (vec![0.0; x.len()], vec![[0.0; 2]; x.len()]);
        let w: Vec<[f64; 3]> = v.iter().map(|v| v.map(|c| -0.5 * c)).collect();
        let on = |threads: usize| {
            let pool = (threads > 1)
                .then(|| std::sync::Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()));
            let g = group(model.terms[0].kind, &[(0, &model.terms[0])], &model, &pool);
            [&v, &w].map(|v| {
                let s = Frame { x: &x, v, m: &m, q: &q, c: &c };
                let mut f = vec![[0.0; 3]; x.len()];
                let e = g.accumulate(&s, &mut f, true).unwrap();
                let virial = g.virial(&s).unwrap().unwrap();
                (f.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>(), e.to_bits(), virial.to_bits())
            })
        };
        let one = on(1);
        assert!(one[0].0 != one[1].0, "the velocities change the viscous forces");
        for threads in [4, 7] {
            assert!(on(threads) == one, "{threads} threads, periodic {periodic}");
        }
    }
}

/// A direction of the inputs: positions, velocities, masses, the six parameters.
struct Along {
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    m: Vec<f64>,
    p: Vec<f64>,
}

/// The fast forces and energy with every input moved by `h` along `d`.
fn moved(model: &Model, x: &[[f64; 3]], v: &[[f64; 3]], d: &Along, h: f64) -> (Vec<[f64; 3]>, f64) {
    let mut model = model.clone();
    for (p, dp) in model.terms[0].params.iter_mut().zip(&d.p) {
        *p += h * dp;
    }
    for (b, dm) in model.bodies.iter_mut().zip(&d.m) {
        b.mass += h * dm;
    }
    let shift = |a: &[[f64; 3]], b: &[[f64; 3]]| -> Vec<[f64; 3]> {
        a.iter().zip(b).map(|(a, b)| std::array::from_fn(|c| a[c] + h * b[c])).collect()
    };
    fast(&model, &shift(x, &d.x), &shift(v, &d.v))
}

fn snapshot<'a>(x: &'a [[f64; 3]], v: &'a [[f64; 3]]) -> Snapshot<'a> {
    Snapshot { step: 0, t: 0.0, x, v, chain: &[], spin: &[] }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// The fast pressure forces are −∂E/∂x of the definition's energy Σ m u(ρ) (central
    /// differences), the fast energy is that energy, and the forces sum to zero.
    #[test]
    fn pressure_forces_are_minus_the_gradient_of_the_definition(seed in any::<u64>(), squeeze in 0.3f64..1.2, periodic in any::<bool>()) {
        let (model, x, v) = fluid(seed, squeeze, 0.0, 0.0, periodic);
        let energy = |x: &[[f64; 3]]| Lifted::new(&model, &snapshot(x, &v), &0.0f64).potential(&model);
        let (f, e) = fast(&model, &x, &v);
        let e0 = energy(&x);
        // u(ρ) is two terms of size (B/ρ₀)(ρ/ρ₀ − 1) that cancel to second order near ρ₀: a
        // fluid barely pressed has an energy far below their round-off, so the bound has a
        // floor at round-off of the bodies' B/ρ₀ = c₀²/γ (c₀ = 10, γ = 7 in `fluid`)
        let mass: f64 = model.bodies.iter().map(|b| b.mass).sum();
        prop_assert!((e - e0).abs() <= 1e-12 * e0.abs() + 1e-14 * mass * 100.0 / 7.0, "{e} vs {e0}");
        let scale = f.iter().flatten().fold(0.0f64, |a, c| a.max(c.abs()));
        let eps = 1e-6;
        for b in (0..x.len()).step_by(7) {
            for c in 0..3 {
                let (mut up, mut down) = (x.clone(), x.clone());
                up[b][c] += eps;
                down[b][c] -= eps;
                let fd = -(energy(&up) - energy(&down)) / (2.0 * eps);
                prop_assert!((f[b][c] - fd).abs() <= 1e-6 * scale + 1e-12, "body {b} axis {c}: {} vs {fd}", f[b][c]);
            }
        }
        for c in 0..3 {
            let total: f64 = f.iter().map(|f| f[c]).sum();
            prop_assert!(total.abs() <= 1e-12 * scale * x.len() as f64);
        }
    }

    /// The viscous forces remove energy at the rate the definition's dissipated power gives:
    /// −Σ v·F_viscous = Σ over pairs of v·∂F/∂v (the checker's Q integrates that rate).
    #[test]
    fn viscous_forces_dissipate_the_definitions_power(seed in any::<u64>(), alpha in 0.0f64..1.0, beta in 0.0f64..2.0) {
        let (inviscid, x, v) = fluid(seed, 0.8, 0.0, 0.0, false);
        let (model, _, _) = fluid(seed, 0.8, alpha, beta, false);
        let (f_all, _) = fast(&model, &x, &v);
        let (f_pressure, _) = fast(&inviscid, &x, &v);
        let rate: f64 = (0..x.len()).map(|b| (0..3).map(|c| v[b][c] * (f_all[b][c] - f_pressure[b][c])).sum::<f64>()).sum();
        let power = Lifted::new(&model, &snapshot(&x, &v), &0.0f64).dissipated_power(&model);
        prop_assert!(power >= 0.0);
        prop_assert!((rate + power).abs() <= 1e-10 * power.abs().max(1e-300), "{rate} vs −{power}");
    }

    /// The derivatives from the definition (`density_derivative`) against the fast force.
    #[test]
    fn derivatives_are_the_fast_forces_differences_and_their_transposes(seed in any::<u64>(), squeeze in 0.5f64..1.0, alpha in 0.0f64..1.0, beta in 0.0f64..2.0, periodic in any::<bool>()) {
        derivatives_hold(seed, squeeze, alpha, beta, periodic)?;
    }
}

/// The tangent along a random direction of positions, velocities, masses and all six
/// parameters is the central difference of the fast force, the pullback is its transpose
/// (g·Ju = Jᵀg·u), and the potential's pullback is the central difference of the energy.
/// The fast force has switches — a pair's viscosity acts only while it approaches, the
/// pressure only above ρ₀ — where it has no derivative: a case with one within the
/// difference's step (the differences over h and h/4 disagree) is set aside, not judged.
fn derivatives_hold(seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Result<(), TestCaseError> {
    use crate::forces::derivative::{Adjoint, Direction, Wanted};
    let (model, x, v) = fluid(seed, squeeze, alpha, beta, periodic);
    let n = x.len();
    let mut rng = Rng::new(seed ^ 0x5eed);
    let mut vecs =
        |scale: f64| -> Vec<[f64; 3]> { (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-scale, scale))).collect() };
    let (dx, dv, g) = (vecs(0.05), vecs(1.0), vecs(1.0));
    let mut rng = Rng::new(seed ^ 0xd1);
    let dm: Vec<f64> = (0..n).map(|_| rng.uniform(-0.004, 0.004)).collect();
    let dp: Vec<f64> = [0.03, 0.2, 2.0, 1.0, 0.5, 0.5].iter().map(|s| rng.uniform(-s, *s)).collect();
    let along = Along { x: dx, v: dv, m: dm, p: dp };
    let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
    let (q, c) = (vec![0.0; n], vec![[0.0; 2]; n]);
    let frame = Frame { x: &x, v: &v, m: &m, q: &q, c: &c };
    let force = group(model.terms[0].kind, &[(0, &model.terms[0])], &model, &None);
    let params = vec![along.p.clone()];
    let dir = Direction { x: &along.x, v: &along.v, m: &along.m, q: &q, params: &params };
    let mut df = vec![[0.0; 3]; n];
    force.tangent(&frame, &dir, &mut df).unwrap();
    let h = 1e-6;
    let ((plus, e_plus), (minus, e_minus)) = (moved(&model, &x, &v, &along, h), moved(&model, &x, &v, &along, -h));
    let ((plus4, _), (minus4, _)) = (moved(&model, &x, &v, &along, h / 4.0), moved(&model, &x, &v, &along, -h / 4.0));
    let scale = df.iter().flatten().fold(1e-300f64, |a, c| a.max(c.abs()));
    for b in 0..n {
        for c in 0..3 {
            let fd = (plus[b][c] - minus[b][c]) / (2.0 * h);
            let fd4 = (plus4[b][c] - minus4[b][c]) / (h / 2.0);
            prop_assume!((fd - fd4).abs() <= 1e-6 * scale, "a switch within the difference step");
            prop_assert!(
                (fd - df[b][c]).abs() <= 1e-5 * scale,
                "body {b} axis {c}: tangent {} vs difference {fd}",
                df[b][c]
            );
        }
    }
    let dot3 = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
        a.iter().zip(b).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum()
    };
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(a, b)| a * b).sum() };
    let wanted = Wanted { params: vec![(0..6).collect()], masses: true, charges: false };
    let mut out = Adjoint::zero(n, &model.terms);
    force.pullback(&frame, &g, &wanted, &mut out).unwrap();
    let forward = dot3(&g, &df);
    let reverse =
        dot3(&out.x, &along.x) + dot3(&out.v, &along.v) + dot(&out.m, &along.m) + dot(&out.params[0], &along.p);
    prop_assert!((forward - reverse).abs() <= 1e-10 * (forward.abs() + scale), "g·Ju {forward} vs Jᵀg·u {reverse}");
    let mut out = Adjoint::zero(n, &model.terms);
    force.potential_pullback(&frame, &wanted, &mut out).unwrap();
    let slope = dot3(&out.x, &along.x) + dot(&out.m, &along.m) + dot(&out.params[0], &along.p);
    let fd = (e_plus - e_minus) / (2.0 * h);
    prop_assert!((slope - fd).abs() <= 1e-6 * (fd.abs() + e_plus.abs()), "dU {slope} vs difference {fd}");
    Ok(())
}

/// The case CI's run drew on 2026-11-28 (tangent 0.6533115 against a difference of
/// 0.6532184 at body 32, a switch within the step): set aside or held, never failed.
#[test]
fn the_case_ci_drew_is_not_failed() {
    let outcome =
        derivatives_hold(15674834107194876332, 0.73405433473918, 0.46391827199462843, 1.9973510973611344, false);
    assert!(!matches!(outcome, Err(TestCaseError::Fail(_))), "{outcome:?}");
}
