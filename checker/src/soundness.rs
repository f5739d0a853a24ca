//! Soundness of the trusted core, as properties over thousands of random cases:
//! every enclosure holds the 1024-bit MPFR value, the decision never PASSes a drift that the
//! 1024-bit value shows to exceed the tolerance, and the certificate reader never panics.
#![cfg(test)]

use crate::certificate::{Certificate, Run, ARITHMETIC, FORMAT};
use crate::claims::{Claim, ClaimKind};
use crate::decision::Verdict;
use crate::enclosure::Enclosure;
use crate::model::{Body, Model, Snapshot, TermInstance, UnitSystem};
use crate::monitor::Monitor;
use crate::mpfi::Mpfi;
use crate::outward::Outward;
use crate::quantities::Lifted;
use crate::real::Real;
use crate::terms::{Kind, Site};
use proptest::prelude::*;
use rug::Float;

const BITS: u32 = 1024;

fn inside(i: Outward, f: &Float) -> bool {
    Float::with_val(BITS, i.bounds().0) <= *f && *f <= Float::with_val(BITS, i.bounds().1)
}

fn site<R: Real>(proto: &R, x: [f64; 3], v: [f64; 3], m: f64, q: f64) -> Site<R> {
    // a colour charge that varies with the electric one, so colour terms see varied pairs
    let colour = [proto.lift(q / 2.0), proto.lift(1.0 / (2.0 * 3f64.sqrt()) - q / 10.0)];
    Site { x: x.map(|c| proto.lift(c)), v: v.map(|c| proto.lift(c)), m: proto.lift(m), q: proto.lift(q), colour }
}

type Body3 = ([f64; 3], [f64; 3], f64, f64);

fn body() -> impl Strategy<Value = Body3> {
    (prop::array::uniform3(-10.0f64..10.0), prop::array::uniform3(-5.0f64..5.0), 0.01f64..100.0, -3.0f64..3.0)
}

/// The term evaluated on `bodies` (as many as its shape takes) in `proto`'s arithmetic, from
/// the bare parameters, or with its constants worked out beforehand as `Lifted` does.
fn eval<R: Real>(kind: Kind, params: &[f64], bodies: &[Body3], proto: &R, prepared: bool) -> (R, [Option<R>; 2]) {
    let n = kind.spec().shape.arity();
    let sites: Vec<Site<R>> = bodies[..n].iter().map(|b| site(proto, b.0, b.1, b.2, b.3)).collect();
    let s: Vec<&Site<R>> = sites.iter().collect();
    let mut p: Vec<R> = params.iter().map(|&c| proto.lift(c)).collect();
    if prepared {
        p.extend(kind.constants(&p));
    }
    (kind.potential(&p, &s), [kind.rayleigh(&p, &s), kind.power(&p, &s)])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    /// Every term's energy (and dissipation function) enclosure holds the 1024-bit value: each
    /// case checks every term kind, so each kind sees all 4096 cases.
    #[test]
    fn every_term_enclosure_holds_the_mpfr_value(
        params in prop::collection::vec(0.01f64..100.0, 8),
        signs in prop::collection::vec(any::<bool>(), 8),
        bodies in prop::collection::vec(body(), 4),
    ) {
        for &kind in Kind::ALL {
            let w = kind.spec().width();
            // vector parameters (fields) may point anywhere; scalar ones are magnitudes
            let vector = kind.spec().params.iter().any(|q| q.len == 3);
            let params: Vec<f64> = params[..w].iter().zip(&signs).map(|(&p, &s)| if vector && s { -p } else { p }).collect();
            let (iv, iv_f) = eval(kind, &params, &bodies, &Outward::NAN, false);
            let (hp, hp_f) = eval(kind, &params, &bodies, &Float::new(BITS), false);
            // nothing known (NaN) only where binary64 itself overflows: an inner end past the
            // range makes the enclosure unknown (`outward::up`)
            let (point, _) = eval(kind, &params, &bodies, &0.0f64, false);
            let unknown_allowed = !point.is_finite();
            // constants worked out once give the same bits as worked out in the term
            let (prepared, _) = eval(kind, &params, &bodies, &Outward::NAN, true);
            let bits = |(lo, hi): (f64, f64)| (lo.to_bits(), hi.to_bits());
            prop_assert!(bits(prepared.bounds()) == bits(iv.bounds()), "{kind:?}");
            // where the definition is undefined (FENE past R₀) there is nothing to enclose
            prop_assert!(hp.is_nan() || inside(iv, &hp) || unknown_allowed && iv.bounds().0.is_nan(), "{kind:?}: {iv:?} does not hold {hp}");
            // the dissipation function, and the power whose integral is an energy balance's heat
            for (a, b) in iv_f.into_iter().zip(hp_f).filter_map(|(a, b)| a.zip(b)) {
                prop_assert!(b.is_nan() || inside(a, &b), "{kind:?} dissipation: {a:?} does not hold {b}");
            }
        }
    }
}

fn model() -> Model {
    Model {
        units: UnitSystem::Reduced,
        cell: None,
        bodies: vec![
            Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
            Body { mass: 2.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
            Body { mass: 0.5, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
        ],
        terms: vec![
            TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![3.0, 1.0, 0.0] },
            TermInstance { kind: Kind::Gravity, sites: vec![], params: vec![0.5] },
            TermInstance { kind: Kind::UniformAcceleration, sites: vec![], params: vec![0.0, -1.0, 0.0] },
        ],
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    }
}

fn drift(model: &Model, a: &Snapshot, b: &Snapshot) -> Float {
    let h = |s: &Snapshot| Lifted::new(model, s, &Float::new(BITS)).energy(model);
    let (h0, h1) = (h(a), h(b));
    Float::with_val(BITS, &h1 - &h0).abs() / h0.abs()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    /// Whatever the states and the tolerance, a PASS means the 1024-bit drift is within it.
    #[test]
    fn the_decision_never_passes_a_drift_beyond_the_tolerance(
        x0 in prop::array::uniform3(prop::array::uniform3(-3.0f64..3.0)),
        v0 in prop::array::uniform3(prop::array::uniform3(-2.0f64..2.0)),
        nudge in prop::array::uniform3(prop::array::uniform3(-1e-9f64..1e-9)),
        scale in 0.0f64..2.0,
    ) {
        let m = model();
        let x1: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|c| x0[i][c] + nudge[i][c]));
        let (a, b) = (Snapshot { step: 0, t: 0.0, x: &x0, v: &v0, chain: &[], spin: &[] }, Snapshot { step: 1, t: 1.0, x: &x1, v: &v0, chain: &[], spin: &[] });
        let exact = drift(&m, &a, &b);
        // a tolerance around the true drift, where the decision is hardest
        let tol = exact.to_f64() * scale;
        prop_assume!(tol > 0.0 && tol.is_finite());
        let claims = vec![Claim::new(ClaimKind::EnergyConservation, Some(tol), 1)];
        let mut mon = Monitor::new(m, claims, 1).unwrap();
        mon.observe(&a).unwrap();
        let _ = mon.observe(&b);
        let v = &mon.finish().verdicts[0];
        if let Verdict::Pass(_) = v {
            prop_assert!(exact <= tol, "PASS with drift {exact} > tol {tol}");
        }
        if let Verdict::Fail(_) = v {
            prop_assert!(exact > tol, "FAIL with drift {exact} ≤ tol {tol}");
        }
    }
}

/// A small, valid, sealed certificate.
fn certificate() -> String {
    let m = model();
    let claims = vec![Claim::new(ClaimKind::MomentumConservation, None, 1)];
    let mut mon = Monitor::new(m.clone(), claims.clone(), 1).unwrap();
    let x = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 2.0, 0.0]];
    let v = [[0.0; 3]; 3];
    for step in 0..=1 {
        mon.observe(&Snapshot { step, t: step as f64, x: &x, v: &v, chain: &[], spin: &[] }).unwrap();
    }
    let out = mon.finish();
    Certificate {
        format: FORMAT.into(),
        arithmetic: ARITHMETIC.into(),
        scene: "s".into(),
        source_digest: "sha256:0".into(),
        model: m,
        claims,
        run: Run {
            integrator: "velocity_verlet".into(),
            dt: 1.0,
            planned_steps: 1,
            steps: 1,
            stopped: None,
            first_step: 0,
        },
        trails: out.trails,
        verdicts: vec!["x".into()],
        states_checksum: None,
        previous: None,
        checksum: String::new(),
    }
    .seal()
    .expect("marks in memory")
    .to_json()
}

#[test]
fn the_sample_certificate_reads() {
    Certificate::read(&certificate()).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    /// The reader returns an error or a certificate for any input: it never panics.
    #[test]
    fn the_certificate_reader_never_panics_on_noise(text in ".{0,300}") {
        let _ = Certificate::read(&text);
    }

    /// Nor on a real certificate cut short or with one byte changed.
    #[test]
    fn the_certificate_reader_never_panics_on_damage(cut in 0usize..2000, at in 0usize..2000, byte in any::<u8>()) {
        let mut b = certificate().into_bytes();
        let n = b.len();
        b[at % n] = byte;
        b.truncate(n - cut % n);
        let _ = Certificate::read(&String::from_utf8_lossy(&b));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    /// A term with a finite reach is exactly zero beyond it (the broad phase of the quantities
    /// skips such pairs): evaluated in MPFR intervals, which keep an exact zero exact, the
    /// enclosure is the point 0 (binary64 intervals step every end outward, so they give
    /// ±2⁻⁵¹¹, the floor of a step, around 0 instead, and enclose 0).
    #[test]
    fn beyond_its_reach_a_term_is_exactly_zero(
        params in prop::collection::vec(0.01f64..5.0, 8),
        dir in prop::array::uniform3(-1.0f64..1.0),
        extra in 1e-6f64..10.0,
    ) {
        // (a density term's potential holds a body's own share, which no distance removes; the
        // shares its pairs give vanish beyond reach: `terms::sph`'s tests)
        for &kind in Kind::ALL.iter().filter(|k| k.spec().shape != crate::terms::Shape::Density) {
            let params = &params[..kind.spec().width()];
            let reach = kind.reach(params);
            if reach.is_infinite() {
                continue;
            }
            let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            prop_assume!(norm > 0.1);
            let r = reach * (1.0 + 1e-6) + extra;
            let far = [dir[0] / norm * r, dir[1] / norm * r, dir[2] / norm * r];
            let bodies: Vec<Body3> = vec![([0.0; 3], [0.0; 3], 1.0, 1.0), (far, [0.0; 3], 1.0, -1.0)];
            let (v, _) = eval(kind, params, &bodies, &Mpfi::point(128, 0.0), false);
            prop_assert!(v.bounds() == (0.0, 0.0), "{kind:?} at {r} beyond reach {reach}: {v:?}");
            let (w, _) = eval(kind, params, &bodies, &Outward::NAN, false);
            let (lo, hi) = w.bounds();
            prop_assert!(lo <= 0.0 && hi >= 0.0 && hi - lo < 1e-153, "{kind:?}: {w:?}");
        }
    }
}

/// Which symmetries each term's potential has (the `noether` crate will derive this; here it is
/// the expectation): translation of every body, and rotation about the origin (terms with a
/// centre are tested with it at the origin).
fn symmetric(kind: Kind) -> (bool, bool) {
    use crate::terms::Shape;
    match kind {
        Kind::UniformAcceleration | Kind::ElectricField | Kind::ContactFloor | Kind::Wall => (false, false),
        Kind::GravityWell | Kind::HarmonicTrap => (false, true),
        Kind::Drag | Kind::MagneticField => (true, true),
        k => {
            assert!(k.spec().shape != Shape::External, "{k:?}: say which symmetries it has");
            (true, true)
        }
    }
}

/// The definition's potential in binary64 at positions `x`.
fn potential_at(kind: Kind, params: &[f64], x: &[[f64; 3]]) -> f64 {
    let bodies: Vec<Body3> = x
        .iter()
        .enumerate()
        .map(|(i, x)| (*x, [0.1, -0.2, 0.3], 1.0 + i as f64, if i % 2 == 0 { 1.0 } else { -0.7 }))
        .collect();
    eval(kind, params, &bodies, &0.0f64, false).0
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn each_term_has_exactly_its_symmetries(
        params in prop::collection::vec(0.5f64..2.0, 8),
        x in prop::collection::vec(prop::array::uniform3(-2.0f64..2.0), 4),
        shift in prop::array::uniform3(0.5f64..2.0),
        angle in 0.3f64..2.8,
    ) {
        let (c, s) = (angle.cos(), angle.sin());
        for &kind in Kind::ALL {
            let spec = kind.spec();
            let mut p = params[..spec.width()].to_vec();
            // centred terms at the origin; cutoffs beyond every distance here; a floor above
            for (q, at) in spec.params.iter().scan(0, |at, q| { let a = *at; *at += q.len; Some((q, a)) }) {
                match q.name {
                    "center" => p[at..at + 3].fill(0.0),
                    "cutoff" => p[at] = 50.0,
                    "R0" => p[at] = 50.0,
                    "y" => p[at] = 5.0,
                    // every body behind the wall, where it pushes
                    "offset" => p[at] = 50.0,
                    _ => {}
                }
            }
            let v0 = potential_at(kind, &p, &x);
            let moved: Vec<[f64; 3]> = x.iter().map(|x| std::array::from_fn(|k| x[k] + shift[k])).collect();
            let turned: Vec<[f64; 3]> = x.iter().map(|x| [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]]).collect();
            let (vt, vr) = (potential_at(kind, &p, &moved), potential_at(kind, &p, &turned));
            prop_assume!(v0.is_finite() && vt.is_finite() && vr.is_finite());
            // relative, with a floor: a fluid's energy near the edge of its kernels' support is a
            // difference of near neighbours (5.5e-10 differing by 4e-17 was seen), where every
            // term that lacks a symmetry changes by far more under these moves
            let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (a.abs() + b.abs()) + 1e-14;
            let (translation, rotation) = symmetric(kind);
            prop_assert_eq!(same(v0, vt), translation, "{:?} translation: {} vs {}", kind, v0, vt);
            prop_assert_eq!(same(v0, vr), rotation, "{:?} rotation: {} vs {}", kind, v0, vr);
        }
    }
}
