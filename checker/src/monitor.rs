//! The checker's side of a run: it is handed exact states, evaluates each declared claim's
//! quantity on them with interval arithmetic, and feeds the enclosures to the decision. A
//! checkpoint that binary64 intervals cannot decide is re-evaluated with MPFR intervals at rising
//! precision, up to a cap, before it is left undecided.

use crate::broad_phase::{Foreseen, FORESIGHT};
use crate::certificate::{Mark, Trail};
use crate::claims::{Claim, ClaimKind};
use crate::decision::{classify, decide_static, Breach, Class, Judge, Precision, Verdict, BINARY64};
use crate::enclosure::Enclosure;
use crate::model::{Model, Snapshot};
use crate::mpfi::Mpfi;
use crate::outward::Outward;
use crate::quantities::{foresee, pair_reaches, Lifted, PairSum};
use crate::states::State;
use crate::terms::{Kind, Site};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Unit round-off of binary64.
const U: f64 = f64::EPSILON / 2.0;
/// Round-off budget per step and per unit of Σm|v| (resp. Σm|x||v|) for momentum claims given
/// without a tolerance: velocity Verlet conserves both exactly in exact arithmetic, so only
/// rounding can move them, by about 2u·Σm|v| per step; the budget leaves a factor 8 of margin.
const ROUNDOFF_BUDGET: f64 = 16.0 * U;
/// The MPFR precisions tried, in order, on a checkpoint binary64 intervals leave undecided.
pub const ESCALATION: [Precision; 4] = [128, 256, 512, 1024];

/// Why a run must stop.
#[derive(Debug, Clone, PartialEq)]
pub enum Halt {
    /// A claim is certainly violated at this checkpoint.
    Breach(Breach),
    /// The state cannot be evaluated (non-finite coordinates, wrong size).
    InvalidState(String),
}

impl std::fmt::Display for Halt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Halt::Breach(b) => write!(f, "halted at step {}: {} is certainly violated", b.step, b.claim.name()),
            Halt::InvalidState(m) => write!(f, "halted: {m}"),
        }
    }
}

/// Energy removed by dissipative terms, integrated by the trapezoid rule over every step.
struct Ledger {
    t: f64,
    power: Outward,
    dissipated: Outward,
}

struct Track {
    claim: Claim,
    judge: Judge,
    marks: Vec<Mark>,
    scale: f64,
    stopped: Option<Verdict>,
}

/// The first state handed in (a run's step 0), kept whole so that
/// it can be re-evaluated at any precision, and each claim's quantity on it in binary64
/// intervals (in the order of the claims). Re-evaluated, it keeps its own step number, which no
/// quantity reads.
struct Reference {
    state: State,
    measures: Vec<Vec<Outward>>,
}

/// What a monitor carries from one checkpoint to the next, for a restart file: the reference
/// state (its measures are evaluated again from it), each claim's running summary and
/// round-off scale, and the energy ledger (t, the power's and the dissipated energy's bounds).
/// Its numbers are bits, non-finite ones included (a summary's bound starts at −∞).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Carried {
    pub reference: Option<State>,
    pub judges: Vec<(Judge, f64)>,
    pub ledger: Option<[f64; 5]>,
}

/// Where a run's marks go as they are made (the claim's index, the mark) instead of its
/// trail in memory: to disk, or nowhere when no certificate is written, so that the memory of a
/// run does not grow with its length (the verdicts are the `Judge`'s running summaries).
pub type MarkSink = Box<dyn FnMut(usize, Mark) + Send>;

pub struct Monitor {
    model: Model,
    tracks: Vec<Track>,
    last_step: u64,
    reference: Option<Reference>,
    /// Whether energy is claimed on a model with dissipative terms (then it is a balance).
    balance: bool,
    ledger: Option<Ledger>,
    /// Threads a checkpoint's pair sums run on (the verdicts are the same bits for any count).
    threads: usize,
    /// The pair lists made ahead of the next checkpoint (`foresee`).
    ahead: Arc<[Foreseen]>,
    /// The last checkpoint's sites, whose memory the next one reuses (`Lifted::reusing`).
    sites: Vec<Site<Outward>>,
    /// Where the marks go (`None`: the trails, in memory).
    sink: Option<MarkSink>,
}

/// What the checker concluded about a run.
pub struct Outcome {
    pub verdicts: Vec<Verdict>,
    pub trails: Vec<Trail>,
    /// Dissipative terms that removed energy (the energy claim was then a balance).
    pub dissipators: Vec<Kind>,
}

/// The quantity a dynamic claim is about.
fn measure<E: Enclosure + PairSum>(c: &Claim, q: &Lifted<E>, model: &Model, s: &Snapshot) -> Vec<E> {
    let axes = |v: [E; 3]| -> Vec<E> {
        let keep = c.axes.unwrap_or([true; 3]);
        v.into_iter().zip(keep).filter(|p| p.1).map(|p| p.0).collect()
    };
    match c.kind {
        ClaimKind::EnergyConservation => vec![q.energy(model)],
        ClaimKind::MomentumConservation => axes(q.momentum(model)),
        ClaimKind::AngularMomentumConservation => axes(q.angular_momentum(model)),
        ClaimKind::Distance => {
            c.between.as_ref().map(|b| vec![q.distance(b.bodies[0], b.bodies[1])]).unwrap_or_default()
        }
        // each constraint's relative error | |xⱼ − xᵢ| − length | / length
        ClaimKind::ConstraintSatisfied => model
            .constraints
            .iter()
            .map(|k| {
                let d = q.distance(k.bodies[0], k.bodies[1]);
                let length = d.lift(k.length);
                (d - length.clone()).abs() / length
            })
            .collect(),
        ClaimKind::Resting => vec![q.fastest_point(model)],
        ClaimKind::NoPenetration => vec![q.penetration(model, s.x)],
        ClaimKind::JointSatisfied => q.pin_gaps(model),
        ClaimKind::DimensionalConsistency => vec![],
    }
}

/// How far the claimed quantity is from where it must be: |H + Q − H₀|/|H₀| for energy, the
/// largest claimed component of |X − X₀| for the momenta, max(min − d, d − max) for a distance
/// (at most 0 inside its bounds), the largest relative error of a constraint, the fastest point
/// (resting), the deepest overlap (no penetration), the widest gap of a joint's pins.
fn deviation<E: Enclosure>(c: &Claim, now: Vec<E>, reference: Vec<E>, dissipated: E) -> E {
    match (c.kind, &c.between) {
        (ClaimKind::EnergyConservation, _) => {
            let h0 = reference[0].clone();
            (now[0].clone() + dissipated - h0.clone()).abs() / h0.abs()
        }
        (ClaimKind::Distance, Some(b)) => {
            let d = now[0].clone();
            (d.lift(b.min) - d.clone()).max(d.clone() - d.lift(b.max))
        }
        (ClaimKind::ConstraintSatisfied | ClaimKind::JointSatisfied, _) => {
            now.into_iter().reduce(|m, d| m.max(d)).expect("a constraint or a pin")
        }
        (ClaimKind::Resting | ClaimKind::NoPenetration, _) => now[0].clone(),
        _ => now.into_iter().zip(reference).map(|(a, b)| (a - b).abs()).reduce(|m, d| m.max(d)).expect("a component"),
    }
}

impl Monitor {
    pub fn new(model: Model, claims: Vec<Claim>, last_step: u64) -> Result<Self, String> {
        model.validate()?;
        claims.iter().try_for_each(|c| c.validate(&model))?;
        let balance = is_balance(&model, &claims);
        let tracks = claims
            .into_iter()
            .map(|claim| Track { judge: Judge::new(claim.kind), claim, marks: vec![], scale: 0.0, stopped: None })
            .collect();
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let ahead = Arc::default();
        let (reference, ledger, sites, sink) = (None, None, vec![], None);
        Ok(Monitor { model, tracks, last_step, reference, balance, ledger, threads, ahead, sites, sink })
    }

    /// A monitor that goes on from where `carried` left one of the same model and claims (a
    /// restart). The reference's measures are evaluated again: the same bits as the first time.
    pub fn resumed(model: Model, claims: Vec<Claim>, last_step: u64, carried: Carried) -> Result<Self, String> {
        let mut m = Monitor::new(model, claims, last_step)?;
        let kinds = |j: &[(Judge, f64)]| j.iter().map(|j| j.0.claim()).collect::<Vec<_>>();
        if kinds(&carried.judges) != m.tracks.iter().map(|t| t.claim.kind).collect::<Vec<_>>() {
            return Err("its running summaries are of other claims than the scene's".into());
        }
        if let Some(r) = carried.reference {
            m.model.check_state(&r.snapshot())?;
            let q = Lifted::new(&m.model, &r.snapshot(), &Outward::NAN).on_threads(m.threads);
            let measures = m.tracks.iter().map(|t| measure(&t.claim, &q, &m.model, &r.snapshot())).collect();
            m.reference = Some(Reference { state: r, measures });
        }
        for (t, (judge, scale)) in m.tracks.iter_mut().zip(carried.judges) {
            (t.judge, t.scale) = (judge, scale);
        }
        m.ledger = carried.ledger.map(|[t, p, q, d, e]| Ledger {
            t,
            power: Outward::from_bounds(p, q),
            dissipated: Outward::from_bounds(d, e),
        });
        Ok(m)
    }

    /// What `resumed` needs to go on from here, or why a run cannot: a claim already failed.
    pub fn carried(&self) -> Result<Carried, String> {
        if let Some(t) = self.tracks.iter().find(|t| t.stopped.is_some()) {
            return Err(format!("{} has failed: the run halted, and cannot go on", t.claim.kind.name()));
        }
        let ledger = self.ledger.as_ref().map(|l| {
            let ((p, q), (d, e)) = (l.power.bounds(), l.dissipated.bounds());
            [l.t, p, q, d, e]
        });
        let judges = self.tracks.iter().map(|t| (t.judge.clone(), t.scale)).collect();
        Ok(Carried { reference: self.reference.as_ref().map(|r| r.state.clone()), judges, ledger })
    }

    /// Hands every mark to `sink` as it is made: the outcome's trails are then empty.
    pub fn hand_marks_to(&mut self, sink: MarkSink) {
        self.sink = Some(sink);
    }

    /// Sums each checkpoint's pair terms on `n` threads (all the CPUs by default): one when
    /// the checker shares the machine with a kernel that is still stepping.
    pub fn set_threads(&mut self, n: usize) {
        self.threads = n.max(1);
    }

    /// The threads a checkpoint's pair sums run on.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// How many steps before a checkpoint `foresee` is worth calling (`None`: never, no claim
    /// sums pairs — only energy does — or no pair term has a reach).
    pub fn foresight(&self) -> Option<u64> {
        let sums_pairs = self.tracks.iter().any(|t| t.claim.kind == ClaimKind::EnergyConservation);
        (sums_pairs && !pair_reaches(&self.model).is_empty()).then_some(FORESIGHT)
    }

    /// Lists, from a state `foresight()` steps before a checkpoint, the pairs that checkpoint's
    /// pair sums will look at, so that it need not bin its bodies. The verdicts are the same
    /// bits with or without it: a list that does not hold every pair the checkpoint needs is
    /// not used.
    pub fn foresee(&mut self, s: &Snapshot) {
        self.ahead = foresee(&self.model, s).into();
    }

    /// The first step after `after` at which `observe` has anything to do (`u64::MAX`: none):
    /// every step until the reference is taken and while an energy balance is integrated,
    /// otherwise the next step a claim is due. The states in between may be left out.
    pub fn next_due(&self, after: u64) -> u64 {
        let next = |t: &Track| next_checkpoint(t.claim.every, self.last_step, after);
        let claims = self.tracks.iter().filter(|t| live(t)).map(next).min().unwrap_or(u64::MAX);
        claims.min(if self.reference.is_none() || self.balance { after.saturating_add(1) } else { u64::MAX })
    }

    /// Checks the claims due at this state. The first state handed in is the reference. For an
    /// energy balance every step must be handed in: the dissipated energy is integrated over all
    /// of them, whatever the claim's `every`.
    pub fn observe(&mut self, s: &Snapshot) -> Result<(), Halt> {
        let last = self.last_step;
        // a resting claim speaks of the states from its time on
        let due = |t: &Track| {
            live(t)
                && (s.step.is_multiple_of(t.claim.every) || s.step == last)
                && t.claim.after.is_none_or(|a| s.t >= a)
        };
        if self.reference.is_some() && self.ledger.is_none() && !self.tracks.iter().any(due) {
            return Ok(());
        }
        if let Err(e) = self.model.check_state(s) {
            for t in self.tracks.iter_mut().filter(|t| t.claim.kind.is_dynamic()) {
                t.stopped.get_or_insert(Verdict::Refuted { claim: t.claim.kind, reason: e.clone() });
            }
            return Err(Halt::InvalidState(e));
        }
        let q = Lifted::reusing(std::mem::take(&mut self.sites), &self.model, s, &Outward::NAN)
            .on_threads(self.threads)
            .foreseeing(self.ahead.clone());
        let model = &self.model;
        let first_state = self.reference.is_none();
        if first_state {
            if self.balance {
                self.ledger =
                    Some(Ledger { t: s.t, power: q.dissipated_power(model), dissipated: Outward::point(0.0) });
            }
            let measures = self.tracks.iter().map(|t| measure(&t.claim, &q, model, s)).collect();
            self.reference = Some(Reference { state: State::from(s), measures });
        } else if let Some(l) = &mut self.ledger {
            let power = q.dissipated_power(model);
            l.dissipated =
                l.dissipated + (Outward::point(s.t) - Outward::point(l.t)) * (l.power + power) * Outward::point(0.5);
            (l.t, l.power) = (s.t, power);
        }
        let r = self.reference.as_ref().expect("set above");
        let dissipated = self.ledger.as_ref().map_or(Outward::point(0.0), |l| l.dissipated);
        // Every claim due here is judged before the run halts on the first breach; a
        // conservation law has nothing to compare at its own reference state.
        let mut first = None;
        for (n, t) in self.tracks.iter_mut().enumerate() {
            if !due(t) || (first_state && t.claim.kind.is_conservation()) {
                continue;
            }
            let tol = match (t.claim.fixed_tol(), t.claim.kind) {
                (Some(tol), _) => tol,
                (None, ClaimKind::MomentumConservation) => {
                    t.scale = t.scale.max(weighted_speed(model, s, |_| Outward::point(1.0)));
                    budget(t, s.step)
                }
                (None, _) => {
                    t.scale = t.scale.max(weighted_speed(model, s, norm1) + spun(s));
                    budget(t, s.step)
                }
            };
            let mut mark = Mark { step: s.step, lo: 0.0, hi: 0.0, tol, precision: BINARY64 };
            (mark.lo, mark.hi) =
                deviation(&t.claim, measure(&t.claim, &q, model, s), r.measures[n].clone(), dissipated).bounds();
            if classify(mark.lo, mark.hi, tol) == Class::Straddles {
                mark = escalate(model, r, s, &t.claim, self.threads, dissipated, tol);
            }
            match self.sink.as_mut() {
                Some(sink) => sink(n, mark),
                None => t.marks.push(mark),
            }
            if let Err(b) = t.judge.admit(s.step, (mark.lo, mark.hi), tol, mark.precision) {
                t.stopped = Some(Verdict::Fail(b.clone()));
                first.get_or_insert(Halt::Breach(b));
            }
        }
        self.sites = q.into_sites();
        first.map_or(Ok(()), Err)
    }

    pub fn finish(self) -> Outcome {
        let model = self.model;
        let dissipators = balance_terms(&model, self.balance);
        let mut verdicts = vec![];
        let mut trails = vec![];
        for t in self.tracks {
            verdicts.push(match (t.stopped, t.claim.kind) {
                (Some(v), _) => v,
                (None, ClaimKind::DimensionalConsistency) => {
                    decide_static(ClaimKind::DimensionalConsistency, dimensions(&model))
                }
                (None, _) => t.judge.finish(),
            });
            trails.push(Trail { claim: t.claim.kind, marks: t.marks });
        }
        Outcome { verdicts, trails, dissipators }
    }
}

/// Re-evaluates one checkpoint with MPFR intervals at rising precision: the first enclosure
/// that decides, or the one at the cap. The dissipated energy, integrated in binary64
/// intervals, enters as it is.
fn escalate(model: &Model, r: &Reference, s: &Snapshot, claim: &Claim, threads: usize, q: Outward, tol: f64) -> Mark {
    let r0 = r.state.snapshot();
    let at = |precision: Precision| {
        let proto = Mpfi::point(precision, 0.0);
        let now = measure(claim, &Lifted::new(model, s, &proto).on_threads(threads), model, s);
        let then = measure(claim, &Lifted::new(model, &r0, &proto).on_threads(threads), model, &r0);
        let (lo, hi) = deviation(claim, now, then, Mpfi::from_bounds(precision, q.bounds())).bounds();
        Mark { step: s.step, lo, hi, tol, precision }
    };
    let mut mark = at(ESCALATION[0]);
    for &p in &ESCALATION[1..] {
        if classify(mark.lo, mark.hi, tol) != Class::Straddles {
            break;
        }
        mark = at(p);
    }
    mark
}

/// A dynamic claim is judged at its cadence and at the last step, until it has failed.
fn live(t: &Track) -> bool {
    t.claim.kind.is_dynamic() && t.stopped.is_none()
}

/// The first step after `after` that is a multiple of `every` or is `last` (`u64::MAX`: none).
pub fn next_checkpoint(every: u64, last: u64, after: u64) -> u64 {
    let cadence = (after / every).saturating_add(1).saturating_mul(every);
    cadence.min(if last > after { last } else { u64::MAX })
}

/// What the kernel skipping to [`next_checkpoint`] rests on, one property body run by proptest
/// over all of u64, by exhaustive enumeration of a small domain (the tests below) and by Kani
/// (`proofs`): for `every` ≥ 1 the answer n is after `after`, is a checkpoint (a multiple of
/// `every`, or `last`) or `u64::MAX` when none is left, and no checkpoint lies strictly between.
#[cfg(any(test, kani, kani_typecheck))]
pub fn next_checkpoint_is_the_next(every: u64, last: u64, after: u64) -> bool {
    let n = next_checkpoint(every, last, after);
    let checkpoint = |s: u64| s.is_multiple_of(every) || s == last;
    // the multiple of `every` before n (if n is the last step, the last multiple before it)
    let previous = n.saturating_sub(1) / every * every;
    let none_left = after.checked_add(every - after % every).is_none() && last <= after;
    every == 0
        || (n > after || (n == u64::MAX && none_left))
            && (checkpoint(n) || n == u64::MAX)
            && previous <= after
            && (last <= after || last >= n)
}

#[cfg(any(kani, kani_typecheck))]
mod proofs {
    // Under kani_typecheck nothing calls the harnesses; under kani, Kani does.
    #![cfg_attr(kani_typecheck, allow(dead_code))]
    use crate::any;

    /// For every cadence, last step and step.
    #[cfg_attr(kani, kani::proof)]
    pub fn next_checkpoint_is_the_next_for_every_u64() {
        assert!(super::next_checkpoint_is_the_next(any(), any(), any()));
    }
}

/// Whether energy is claimed on a model with a dissipating term: then the claim is a balance.
pub fn is_balance(model: &Model, claims: &[Claim]) -> bool {
    claims.iter().any(|c| c.kind == ClaimKind::EnergyConservation) && model.terms.iter().any(|t| t.dissipates())
}

/// The kinds of the dissipating terms, when energy is claimed as a balance.
pub fn balance_terms(model: &Model, balance: bool) -> Vec<Kind> {
    let dissipating = |k: &Kind| model.terms.iter().any(|t| t.kind == *k && t.dissipates());
    if balance {
        Kind::ALL.iter().copied().filter(dissipating).collect()
    } else {
        vec![]
    }
}

/// Every term kind in the model has a homogeneous, energy-valued definition.
pub fn dimensions(model: &Model) -> Result<(), String> {
    model.terms.iter().try_for_each(|t| t.kind.check_dimensions())
}

/// |a|₁ as an interval.
fn norm1(a: &[f64; 3]) -> Outward {
    a.iter().fold(Outward::point(0.0), |s, &c| s + Outward::point(c).abs())
}

/// Upper bound of Σ m·w(x)·|v|₁, the scale that round-off in Σmv (w = 1) or Σm x×v (w = |x|₁)
/// is proportional to.
fn weighted_speed(model: &Model, s: &Snapshot, w: impl Fn(&[f64; 3]) -> Outward) -> f64 {
    let mut sum = Outward::point(0.0);
    for (b, (x, v)) in model.bodies.iter().zip(s.x.iter().zip(s.v)) {
        sum = sum + Outward::point(b.mass) * w(x) * norm1(v);
    }
    sum.bounds().1
}

/// Upper bound of Σ |π|₁ over the rigid bodies: the scale of the round-off a free rotation
/// step puts into their angular momentum (a few u·|π| a step; measured ~0.1u for the spinning
/// top, far under the budget's 16u).
fn spun(s: &Snapshot) -> f64 {
    s.spin.iter().fold(Outward::point(0.0), |sum, r| sum + norm1(&[r[4], r[5], r[6]])).bounds().1
}

/// The declared tolerance, or the round-off budget after `step` steps.
fn budget(t: &Track, step: u64) -> f64 {
    t.claim.tol.unwrap_or(ROUNDOFF_BUDGET * step.max(1) as f64 * t.scale)
}

#[cfg(test)]
mod tests {
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
        let q = Lifted::new(
            &cancelling().0,
            &Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] },
            &Outward::NAN,
        );
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
}
