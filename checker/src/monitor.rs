//! The checker's side of a run: it is handed exact states, evaluates each declared claim's
//! quantity on them with interval arithmetic, and feeds the enclosures to the decision. A
//! checkpoint that binary64 intervals cannot decide is re-evaluated with MPFR intervals at rising
//! precision, up to a cap, before it is left undecided.

use crate::broad_phase::{Foreseen, FORESIGHT};
use crate::certificate::{Mark, Trail};
use crate::claims::{Claim, ClaimKind};
use crate::decision::{classify, decide_static, Breach, Class, Judge, Precision, Verdict, BINARY64, PARTS};
use crate::enclosure::Enclosure;
use crate::model::{Model, Snapshot};
use crate::mpfi::Mpfi;
use crate::outward::Outward;
use crate::quantities::{foresee, pair_reaches, Lifted, PairSum, Parts, Whole};
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
    /// Shared with the run that hands it states: a copy of 256,000 bodies' model was 20 ms of
    /// the run's set-up.
    model: Arc<Model>,
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
    parts: FromParts,
}

/// How often a run in domains had its energy and momentum judged from the ranks' parts
/// (`observe_with`), and why they were last refused.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FromParts {
    /// Checkpoints at which the parts stood for the whole.
    pub used: u64,
    /// Checkpoints at which they were refused (the whole state was evaluated instead).
    pub refused: u64,
    pub why: Option<String>,
}

/// What the checker concluded about a run.
pub struct Outcome {
    pub verdicts: Vec<Verdict>,
    pub trails: Vec<Trail>,
    /// Dissipative terms that removed energy (the energy claim was then a balance).
    pub dissipators: Vec<Kind>,
    pub parts: FromParts,
}

/// The components a claim keeps of a vector quantity.
fn axes<E>(c: &Claim, v: [E; 3]) -> Vec<E> {
    let keep = c.axes.unwrap_or([true; 3]);
    v.into_iter().zip(keep).filter(|p| p.1).map(|p| p.0).collect()
}

/// The quantity a dynamic claim is about, from the ranks' parts where they give it (energy,
/// with the thermostat's share added here, and momentum), else `None`.
fn from_parts(c: &Claim, w: &Whole, model: &Model, s: &Snapshot) -> Option<Vec<Outward>> {
    let zero = Outward::point(0.0);
    let links: Vec<[Outward; 2]> = s.chain.iter().map(|l| l.map(Outward::point)).collect();
    match c.kind {
        ClaimKind::EnergyConservation => {
            Some(vec![w.energy + model.thermostat.as_ref().map_or(zero, |t| t.energy(&links, &zero))])
        }
        ClaimKind::MomentumConservation => Some(axes(c, w.momentum)),
        _ => None,
    }
}

/// The quantity a dynamic claim is about.
fn measure<E: Enclosure + PairSum>(c: &Claim, q: &Lifted<E>, model: &Model, s: &Snapshot) -> Vec<E> {
    match c.kind {
        ClaimKind::EnergyConservation => vec![q.energy(model)],
        ClaimKind::MomentumConservation => axes(c, q.momentum(model)),
        ClaimKind::AngularMomentumConservation => axes(c, q.angular_momentum(model)),
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
        ClaimKind::NoPenetration => vec![q.penetration(model, s)],
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
    pub fn new(model: impl Into<Arc<Model>>, claims: Vec<Claim>, last_step: u64) -> Result<Self, String> {
        let model = model.into();
        model.validate()?;
        claims.iter().try_for_each(|c| c.validate(&model))?;
        let balance = is_balance(&model, &claims);
        let tracks = claims
            .into_iter()
            .map(|claim| Track { judge: Judge::new(claim.kind), claim, marks: vec![], scale: 0.0, stopped: None })
            .collect();
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let ahead = Arc::default();
        let (reference, ledger, sites, sink, parts) = (None, None, vec![], None, FromParts::default());
        Ok(Monitor { model, tracks, last_step, reference, balance, ledger, threads, ahead, sites, sink, parts })
    }

    /// A monitor that goes on from where `carried` left one of the same model and claims (a
    /// restart). The reference's measures are evaluated again: the same bits as the first time.
    pub fn resumed(
        model: impl Into<Arc<Model>>,
        claims: Vec<Claim>,
        last_step: u64,
        carried: Carried,
    ) -> Result<Self, String> {
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
    /// pair sums will look at, so that it need not bin its bodies; on the threads it is set to
    /// (`set_threads`). The verdicts are the same bits with or without it: a list that does not
    /// hold every pair the checkpoint needs is not used.
    pub fn foresee(&mut self, s: &Snapshot) {
        self.ahead = foresee(&self.model, s, self.threads).into();
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
        self.observe_with(s, None)
    }

    /// `observe`, with the energy and momentum enclosed by the ranks of a run in domains, each
    /// its part (`Parts`): used where they stand for the whole (`Parts::whole`), the whole
    /// state evaluated here where they do not, at the first state, and for the other claims. A
    /// checkpoint the parts' binary64 enclosure cannot decide is re-evaluated whole with MPFR.
    pub fn observe_with(&mut self, s: &Snapshot, parts: Option<&Parts>) -> Result<(), Halt> {
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
        let model = &self.model;
        let first_state = self.reference.is_none();
        let whole = match parts.map(|p| p.whole(model)) {
            Some(Ok(w)) => Some(w),
            Some(Err(why)) => {
                self.parts.refused += 1;
                self.parts.why = Some(why);
                None
            }
            None => None,
        };
        let given = |t: &Track| whole.as_ref().and_then(|w| from_parts(&t.claim, w, model, s));
        // the first state's measures are every claim's reference
        let wanted = |t: &Track| first_state || due(t);
        let evaluated = self.balance || self.tracks.iter().any(|t| wanted(t) && given(t).is_none());
        let q = evaluated.then(|| {
            Lifted::reusing(std::mem::take(&mut self.sites), model, s, &Outward::NAN)
                .on_threads(self.threads)
                .foreseeing(self.ahead.clone())
        });
        let lifted = || q.as_ref().expect("evaluated where a quantity is not given");
        if whole.is_some() {
            self.parts.used += 1;
        }
        if first_state {
            if self.balance {
                self.ledger =
                    Some(Ledger { t: s.t, power: lifted().dissipated_power(model), dissipated: Outward::point(0.0) });
            }
            let measures =
                self.tracks.iter().map(|t| given(t).unwrap_or_else(|| measure(&t.claim, lifted(), model, s))).collect();
            self.reference = Some(Reference { state: State::from(s), measures });
        } else if let Some(l) = &mut self.ledger {
            let power = lifted().dissipated_power(model);
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
            let (now, precision) = match given(t) {
                Some(now) => (now, PARTS),
                None => (measure(&t.claim, lifted(), model, s), BINARY64),
            };
            let mut mark = Mark { step: s.step, lo: 0.0, hi: 0.0, tol, precision };
            (mark.lo, mark.hi) = deviation(&t.claim, now, r.measures[n].clone(), dissipated).bounds();
            // the parts decide a pass; anything else is decided on the whole state, so that a
            // failure is re-derived to the bit from the states alone
            if precision == PARTS && classify(mark.lo, mark.hi, tol) != Class::Within {
                let whole = Lifted::new(model, s, &Outward::NAN).on_threads(self.threads);
                let now = measure(&t.claim, &whole, model, s);
                (mark.lo, mark.hi) = deviation(&t.claim, now, r.measures[n].clone(), dissipated).bounds();
                mark.precision = BINARY64;
            }
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
        if let Some(q) = q {
            self.sites = q.into_sites();
        }
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
        Outcome { verdicts, trails, dissipators, parts: self.parts }
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
mod tests;
