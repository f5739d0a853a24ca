use super::*;
use crate::model::{Body, TermInstance, UnitSystem};

/// A free particle and a spring-bound pair: energy ½·1·1² + ½·2·(1.5−1)² = 0.75.
fn model() -> Model {
    Model {
        units: UnitSystem::Reduced,
        cell: None,
        bodies: vec![
            Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
            Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
        ],
        terms: vec![TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![2.0, 1.0, 0.0] }],
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    }
}

fn claim(kind: ClaimKind, tol: Option<f64>, every: u64) -> Claim {
    Claim::new(kind, tol, every)
}

fn observe(m: &mut Monitor, step: u64, x1: f64, v0: f64) -> Result<(), Halt> {
    let x = [[0.0; 3], [x1, 0.0, 0.0]];
    let v = [[v0, 0.0, 0.0], [0.0; 3]];
    m.observe(&Snapshot { step, t: step as f64, x: &x, v: &v, chain: &[], spin: &[] })
}

/// The pair lists made ahead serve the pair sums, which only energy reads.
#[test]
fn only_an_energy_claim_on_pair_terms_lists_ahead() {
    let mut paired = model();
    paired.terms.push(TermInstance { kind: Kind::LennardJones, sites: vec![], params: vec![1.0, 1.0, 2.5] });
    let ahead = |m: &Model, kind| Monitor::new(m.clone(), vec![claim(kind, Some(1e-3), 1)], 3).unwrap().foresight();
    assert_eq!(ahead(&paired, ClaimKind::EnergyConservation), Some(FORESIGHT));
    assert_eq!(ahead(&paired, ClaimKind::MomentumConservation), None);
    assert_eq!(ahead(&model(), ClaimKind::EnergyConservation), None);
}

#[test]
fn an_unchanged_state_passes() {
    let mut m = Monitor::new(model(), vec![claim(ClaimKind::EnergyConservation, Some(1e-12), 1)], 3).unwrap();
    for step in 0..=3 {
        observe(&mut m, step, 1.5, 1.0).unwrap();
    }
    assert!(m.finish().verdicts[0].is_pass());
}

#[test]
fn a_state_moved_by_one_ulp_breaks_a_zero_tolerance_claim_at_that_step() {
    let tol = 1e-16;
    let mut m = Monitor::new(model(), vec![claim(ClaimKind::EnergyConservation, Some(tol), 1)], 3).unwrap();
    observe(&mut m, 0, 1.5, 1.0).unwrap();
    observe(&mut m, 1, 1.5, 1.0).unwrap();
    let nudged = f64::from_bits(1.5f64.to_bits() + 1);
    let err = observe(&mut m, 2, nudged, 1.0 + f64::EPSILON).unwrap_err();
    assert!(matches!(err, Halt::Breach(Breach { step: 2, .. })), "{err:?}");
    assert!(matches!(m.finish().verdicts[0], Verdict::Fail(_)));
}

#[test]
fn a_momentum_jump_fails_its_round_off_budget() {
    let mut m = Monitor::new(model(), vec![claim(ClaimKind::MomentumConservation, None, 1)], 2).unwrap();
    observe(&mut m, 0, 1.5, 1.0).unwrap();
    observe(&mut m, 1, 1.5, 1.0).unwrap();
    assert!(matches!(observe(&mut m, 2, 1.5, 1.0 + 1e-9), Err(Halt::Breach(_))));
}

#[test]
fn a_non_finite_state_halts_and_never_passes() {
    let mut m = Monitor::new(model(), vec![claim(ClaimKind::MomentumConservation, None, 1)], 2).unwrap();
    observe(&mut m, 0, 1.5, 1.0).unwrap();
    assert!(matches!(observe(&mut m, 1, f64::NAN, 1.0), Err(Halt::InvalidState(_))));
    assert!(!m.finish().verdicts[0].is_pass());
}

#[test]
fn every_thins_checkpoints_but_keeps_the_last() {
    let mut m = Monitor::new(model(), vec![claim(ClaimKind::EnergyConservation, Some(1e-9), 4)], 10).unwrap();
    for step in 0..=10 {
        observe(&mut m, step, 1.5, 1.0).unwrap();
    }
    let out = m.finish();
    let steps: Vec<u64> = out.trails[0].marks.iter().map(|k| k.step).collect();
    assert_eq!(steps, [4, 8, 10]);
}

#[test]
fn dissipated_energy_enters_the_balance() {
    // The pair is moving apart at unit speed with damping 1: power γṙ² = 1 is dissipated.
    let mut damped = model();
    damped.terms[0].params[2] = 1.0;
    let mut m = Monitor::new(damped, vec![claim(ClaimKind::EnergyConservation, Some(1e-12), 1)], 1).unwrap();
    let x = [[0.0; 3], [1.5, 0.0, 0.0]];
    let v0 = [[0.0; 3], [1.0, 0.0, 0.0]];
    m.observe(&Snapshot { step: 0, t: 0.0, x: &x, v: &v0, chain: &[], spin: &[] }).unwrap();
    // One time unit later the kinetic energy ½ has become exactly the dissipated ½.
    let v1 = [[0.0; 3], [0.0, 0.0, 0.0]];
    let err = m.observe(&Snapshot { step: 1, t: 1.0, x: &x, v: &v1, chain: &[], spin: &[] });
    // The trapezoid saw power 1 then 0: Q = ½, so H + Q = H₀ holds exactly.
    assert_eq!(err, Ok(()));
    assert_eq!(m.finish().dissipators, [Kind::HarmonicBond]);
}

/// One body falling at 1414 units/s, 10⁵ units down: H = T + V ≈ 10⁶ − 10⁶ ≈ −1, so a
/// binary64 enclosure of H is about 10⁻¹⁰·|H| wide.
fn cancelling() -> (Model, [[f64; 3]; 1], [[f64; 3]; 1]) {
    let model = Model {
        units: UnitSystem::Reduced,
        cell: None,
        bodies: vec![Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None }],
        terms: vec![TermInstance { kind: Kind::UniformAcceleration, sites: vec![], params: vec![0.0, -10.0, 0.0] }],
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    };
    (model, [[0.0, -1e5, 0.0]], [[1414.2128, 0.0, 0.0]])
}

#[test]
fn binary64_intervals_cannot_decide_but_mpfr_can() {
    let (model, x, v) = cancelling();
    let mut m = Monitor::new(model, vec![claim(ClaimKind::EnergyConservation, Some(1e-12), 1)], 1).unwrap();
    for step in 0..=1 {
        m.observe(&Snapshot { step, t: step as f64, x: &x, v: &v, chain: &[], spin: &[] }).unwrap();
    }
    let out = m.finish();
    let Verdict::Pass(p) = &out.verdicts[0] else { panic!("{:?}", out.verdicts[0]) };
    assert_eq!(p.precision(), 128);
    // and binary64 intervals alone really could not: their enclosure straddles 1e-12
    let q =
        Lifted::new(&cancelling().0, &Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] }, &Outward::NAN);
    let h = q.energy(&cancelling().0);
    let energy = claim(ClaimKind::EnergyConservation, Some(1e-12), 1);
    let (lo, hi) = deviation(&energy, vec![h], vec![h], Outward::point(0.0)).bounds();
    assert_eq!(classify(lo, hi, 1e-12), Class::Straddles, "[{lo}, {hi}]");
}

#[test]
fn a_claim_no_precision_can_decide_is_undecided_at_the_cap() {
    // At rest with no potential, H₀ = 0: a relative tolerance has nothing to be relative to.
    let model = Model { terms: vec![], ..cancelling().0 };
    let (x, v) = ([[1.0, 2.0, 3.0]], [[0.0; 3]]);
    let mut m = Monitor::new(model, vec![claim(ClaimKind::EnergyConservation, Some(1e-3), 1)], 1).unwrap();
    for step in 0..=1 {
        m.observe(&Snapshot { step, t: step as f64, x: &x, v: &v, chain: &[], spin: &[] }).unwrap();
    }
    let out = m.finish();
    assert!(matches!(out.verdicts[0], Verdict::Undecided(Breach { precision: 1024, .. })), "{:?}", out.verdicts[0]);
    assert_eq!(out.trails[0].marks[0].precision, 1024);
}

#[test]
fn a_model_with_a_bad_body_is_rejected() {
    let mut bad = model();
    bad.bodies[0].mass = 0.0;
    assert!(Monitor::new(bad, vec![], 1).is_err());
}

proptest::proptest! {
    /// Handing in only the states `next_due` names gives the same outcome, marks and
    /// verdicts, as handing in every state: the states left out are ones `observe` ignores.
    #[test]
    fn the_states_next_due_skips_change_nothing(
        claims in proptest::collection::vec((0usize..4, 1u64..7), 0..4),
        damping in proptest::sample::select(vec![0.0, 0.5]),
        last in 0u64..30,
        wobble in 0.0f64..1e-9,
    ) {
        let kinds = [ClaimKind::EnergyConservation, ClaimKind::MomentumConservation,
            ClaimKind::AngularMomentumConservation, ClaimKind::DimensionalConsistency];
        let claims: Vec<Claim> = claims.iter().map(|&(k, every)| claim(kinds[k], (k < 3).then_some(1e-6), every)).collect();
        let mut damped = model();
        damped.terms[0].params[2] = damping;
        let state = |step: u64| ([[0.0; 3], [1.5 + wobble * step as f64, 0.0, 0.0]], [[1.0, 0.0, 0.0], [0.0; 3]]);
        let run = |skip: bool| {
            let mut m = Monitor::new(damped.clone(), claims.clone(), last).unwrap();
            let mut step = 0;
            let mut seen = vec![];
            while step <= last {
                let (x, v) = state(step);
                let verdict = m.observe(&Snapshot { step, t: step as f64, x: &x, v: &v, chain: &[], spin: &[] });
                seen.push(step);
                if verdict.is_err() {
                    break;
                }
                step = if skip { m.next_due(step).min(last.max(step + 1)) } else { step + 1 };
            }
            let out = m.finish();
            (out.verdicts, out.trails, seen)
        };
        let (every, skipping) = (run(false), run(true));
        proptest::prop_assert_eq!(format!("{:?}", every.0), format!("{:?}", skipping.0));
        proptest::prop_assert_eq!(&every.1, &skipping.1);
        // and it skips: only the checkpoints (every step for a balance)
        let balance = damping > 0.0 && claims.iter().any(|c| c.kind == ClaimKind::EnergyConservation);
        let due = |s: u64| s == 0 || balance || claims.iter().any(|c| c.kind.is_dynamic() && (s % c.every == 0 || s == last));
        proptest::prop_assert!(skipping.2.iter().all(|&s| due(s) || s == last), "{:?}", skipping.2);
    }
}

proptest::proptest! {
    /// A monitor cut at any step and resumed from what it carried makes the marks and verdicts of the one never cut: the
    /// reference's measures, the summaries, the round-off scales and the ledger come back.
    #[test]
    fn a_resumed_monitor_is_the_unbroken_one(
        claims in proptest::collection::vec((0usize..4, 1u64..7), 1..4),
        damping in proptest::sample::select(vec![0.0, 0.5]),
        last in 1u64..30,
        cut in 0u64..30,
    ) {
        let cut = cut % last;
        let kinds = [ClaimKind::EnergyConservation, ClaimKind::MomentumConservation,
            ClaimKind::AngularMomentumConservation, ClaimKind::DimensionalConsistency];
        let claims: Vec<Claim> = claims.iter().map(|&(k, every)| claim(kinds[k], (k == 0).then_some(1e-3), every)).collect();
        let mut damped = model();
        damped.terms[0].params[2] = damping;
        let show = |m: &mut Monitor, step: u64| {
            let (x, v) = ([[0.0; 3], [1.5 + 1e-3 * (step as f64).sin(), 0.0, 0.0]], [[1.0, 0.1, 0.0], [0.0; 3]]);
            let _ = m.observe(&Snapshot { step, t: 0.1 * step as f64, x: &x, v: &v, chain: &[], spin: &[] });
        };
        let mut whole = Monitor::new(damped.clone(), claims.clone(), last).unwrap();
        (0..=last).for_each(|k| show(&mut whole, k));
        let mut first = Monitor::new(damped.clone(), claims.clone(), last).unwrap();
        (0..=cut).for_each(|k| show(&mut first, k));
        let Ok(carried) = first.carried() else { return Ok(()) };
        let mut second = Monitor::resumed(damped, claims, last, carried).unwrap();
        (cut + 1..=last).for_each(|k| show(&mut second, k));
        let (a, b) = (whole.finish(), (first.finish(), second.finish()));
        let joined: Vec<Vec<Mark>> =
            b.0.trails.iter().zip(&b.1.trails).map(|(p, q)| [p.marks.clone(), q.marks.clone()].concat()).collect();
        let same = |x: &Mark, y: &Mark| x.same(y);
        for (t, j) in a.trails.iter().zip(&joined) {
            proptest::prop_assert!(t.marks.len() == j.len() && t.marks.iter().zip(j).all(|(x, y)| same(x, y)));
        }
        proptest::prop_assert_eq!(format!("{:?}", a.verdicts), format!("{:?}", b.1.verdicts));
    }
}

#[test]
fn next_checkpoint_is_the_next_on_a_small_domain() {
    for every in 1..=12 {
        for last in 0..=40 {
            for after in 0..=45 {
                let brute = (after + 1..=last.max(after + 1)).find(|s| s % every == 0 || *s == last);
                let n = next_checkpoint(every, last, after);
                assert_eq!(n, brute.unwrap_or((after / every + 1) * every), "{every} {last} {after}");
                assert!(next_checkpoint_is_the_next(every, last, after));
            }
        }
    }
    for after in [u64::MAX - 1, u64::MAX] {
        assert!(next_checkpoint_is_the_next(7, 3, after) && next_checkpoint_is_the_next(1, u64::MAX, after));
    }
}

proptest::proptest! {
    #[test]
    fn next_checkpoint_is_the_next_for_random_u64(every in 1u64.., last: u64, after: u64) {
        proptest::prop_assert!(next_checkpoint_is_the_next(every, last, after));
    }
}
