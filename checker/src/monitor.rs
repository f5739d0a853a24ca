//! The checker's side of a run: it is handed exact states, evaluates each declared claim's
//! quantity on them with interval arithmetic, and feeds the enclosures to the decision.

use crate::claims::{Claim, ClaimKind};
use crate::decision::{decide_static, Breach, Judge, Verdict};
use crate::model::{Model, Snapshot};
use crate::quantities::Lifted;
use crate::real::point;
use crate::terms::Kind;
use inari::Interval;
use serde::Serialize;

/// Unit round-off of binary64.
const U: f64 = f64::EPSILON / 2.0;
/// Round-off budget per step and per unit of Σm|v| (resp. Σm|x||v|) for momentum claims given
/// without a tolerance: velocity Verlet conserves both exactly in exact arithmetic, so only
/// rounding can move them, by about 2u·Σm|v| per step; the budget leaves a factor 8 of margin.
const ROUNDOFF_BUDGET: f64 = 16.0 * U;

/// Why a run must stop.
#[derive(Debug, Clone, PartialEq)]
pub enum Halt {
    /// A claim is certainly violated at this checkpoint.
    Breach(Breach),
    /// The state cannot be evaluated (non-finite coordinates, wrong size).
    InvalidState(String),
}

/// One checkpoint's enclosure of a claim's deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    pub step: u64,
    pub deviation: Interval,
}

impl Serialize for Mark {
    /// `[step, lo, hi]`; the endpoints round-trip exactly (finite values as JSON numbers
    /// with serde_json's float_roundtrip, the infinities as the strings "inf"/"-inf").
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let exact = |x: f64| match x {
            x if x.is_finite() => serde_json::json!(x),
            x if x > 0.0 => serde_json::json!("inf"),
            x if x < 0.0 => serde_json::json!("-inf"),
            _ => serde_json::json!("nan"),
        };
        let mut t = s.serialize_tuple(3)?;
        t.serialize_element(&self.step)?;
        t.serialize_element(&exact(self.deviation.inf()))?;
        t.serialize_element(&exact(self.deviation.sup()))?;
        t.end()
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Trail {
    pub claim: ClaimKind,
    pub marks: Vec<Mark>,
}

/// Energy removed by dissipative terms, integrated by the trapezoid rule over every step.
struct Ledger {
    t: f64,
    power: Interval,
    dissipated: Interval,
}

struct Track {
    claim: Claim,
    judge: Judge,
    marks: Vec<Mark>,
    scale: f64,
    stopped: Option<Verdict>,
}

struct Reference {
    energy: Interval,
    momentum: [Interval; 3],
    angular: [Interval; 3],
}

pub struct Monitor {
    model: Model,
    tracks: Vec<Track>,
    last_step: u64,
    reference: Option<Reference>,
    /// Whether energy is claimed on a model with dissipative terms (then it is a balance).
    balance: bool,
    ledger: Option<Ledger>,
}

/// What the checker concluded about a run.
pub struct Outcome {
    pub verdicts: Vec<Verdict>,
    pub trails: Vec<Trail>,
    /// Dissipative terms that removed energy (the energy claim was then a balance).
    pub dissipators: Vec<Kind>,
}

impl Monitor {
    pub fn new(model: Model, claims: Vec<Claim>, last_step: u64) -> Result<Self, String> {
        model.validate()?;
        for c in &claims {
            if c.kind.needs_tol() && c.tol.is_none() {
                return Err(format!("{} needs a tolerance", c.kind.name()));
            }
            if c.every == 0 {
                return Err(format!("{}: every must be at least 1", c.kind.name()));
            }
        }
        let balance = claims.iter().any(|c| c.kind == ClaimKind::EnergyConservation)
            && model.terms.iter().any(|t| t.kind.dissipative());
        let tracks = claims
            .into_iter()
            .map(|claim| Track { judge: Judge::new(claim.kind), claim, marks: vec![], scale: 0.0, stopped: None })
            .collect();
        Ok(Monitor { model, tracks, last_step, reference: None, balance, ledger: None })
    }

    /// Checks the claims due at this state. The first state handed in is the reference. For an
    /// energy balance every step must be handed in: the dissipated energy is integrated over all
    /// of them, whatever the claim's `every`.
    pub fn observe(&mut self, s: &Snapshot) -> Result<(), Halt> {
        let last = self.last_step;
        let due = |t: &Track| {
            t.claim.kind.is_dynamic() && t.stopped.is_none() && (s.step.is_multiple_of(t.claim.every) || s.step == last)
        };
        if self.reference.is_some() && self.ledger.is_none() && !self.tracks.iter().any(due) {
            return Ok(());
        }
        if let Err(e) = self.model.check_state(s) {
            for t in self.tracks.iter_mut().filter(|t| t.claim.kind.is_dynamic()) {
                t.stopped = Some(Verdict::Refuted { claim: t.claim.kind, reason: e.clone() });
            }
            return Err(Halt::InvalidState(e));
        }
        let q = Lifted::new(&self.model, s, &Interval::EMPTY);
        let model = &self.model;
        let Some(r) = &self.reference else {
            if self.balance {
                self.ledger = Some(Ledger { t: s.t, power: q.dissipated_power(model), dissipated: point(0.0) });
            }
            self.reference =
                Some(Reference { energy: q.energy(model), momentum: q.momentum(), angular: q.angular_momentum() });
            return Ok(());
        };
        if let Some(l) = &mut self.ledger {
            let power = q.dissipated_power(model);
            l.dissipated += (point(s.t) - point(l.t)) * (l.power + power) * point(0.5);
            (l.t, l.power) = (s.t, power);
        }
        let dissipated = self.ledger.as_ref().map_or(point(0.0), |l| l.dissipated);
        for t in self.tracks.iter_mut().filter(|t| due(t)) {
            let (deviation, tol) = match t.claim.kind {
                ClaimKind::EnergyConservation => {
                    let balance = q.energy(model) + dissipated;
                    ((balance - r.energy).abs() / r.energy.abs(), t.claim.tol.unwrap_or(f64::NAN))
                }
                ClaimKind::MomentumConservation => {
                    t.scale = t.scale.max(weighted_speed(model, s, |_| point(1.0)));
                    (worst(q.momentum(), r.momentum), budget(t, s.step))
                }
                ClaimKind::AngularMomentumConservation => {
                    t.scale = t.scale.max(weighted_speed(model, s, norm1));
                    (worst(q.angular_momentum(), r.angular), budget(t, s.step))
                }
                ClaimKind::DimensionalConsistency => continue,
            };
            t.marks.push(Mark { step: s.step, deviation });
            if let Err(b) = t.judge.admit(s.step, deviation, tol) {
                t.stopped = Some(Verdict::Fail(b.clone()));
                return Err(Halt::Breach(b));
            }
        }
        Ok(())
    }

    pub fn finish(self) -> Outcome {
        let model = self.model;
        let dissipators = match self.ledger {
            Some(l) if l.dissipated.sup() > 0.0 => Kind::ALL
                .iter()
                .copied()
                .filter(|k| k.dissipative() && model.terms.iter().any(|t| t.kind == *k))
                .collect(),
            _ => vec![],
        };
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

/// Every term kind in the model has a homogeneous, energy-valued definition.
fn dimensions(model: &Model) -> Result<(), String> {
    model.terms.iter().try_for_each(|t| t.kind.check_dimensions())
}

/// max over components of |a − b|.
fn worst(a: [Interval; 3], b: [Interval; 3]) -> Interval {
    (0..3).map(|c| (a[c] - b[c]).abs()).fold(point(0.0), |m, d| m.max(d))
}

/// Upper bound of Σ m·w(x)·|v|₁, the scale that round-off in Σmv (w = 1) or Σm x×v (w = |x|₁)
/// is proportional to.
fn weighted_speed(model: &Model, s: &Snapshot, w: impl Fn(&[f64; 3]) -> Interval) -> f64 {
    let mut sum = point(0.0);
    for (b, (x, v)) in model.bodies.iter().zip(s.x.iter().zip(s.v)) {
        let speed = norm1(v);
        sum += point(b.mass) * w(x) * speed;
    }
    sum.sup()
}

/// |a|₁ as an interval.
fn norm1(a: &[f64; 3]) -> Interval {
    a.iter().fold(point(0.0), |s, &c| s + point(c).abs())
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
            bodies: vec![Body { mass: 1.0, charge: 0.0 }, Body { mass: 1.0, charge: 0.0 }],
            terms: vec![TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![2.0, 1.0, 0.0] }],
        }
    }

    fn claim(kind: ClaimKind, tol: Option<f64>, every: u64) -> Claim {
        Claim { kind, tol, every }
    }

    fn observe(m: &mut Monitor, step: u64, x1: f64, v0: f64) -> Result<(), Halt> {
        let x = [[0.0; 3], [x1, 0.0, 0.0]];
        let v = [[v0, 0.0, 0.0], [0.0; 3]];
        m.observe(&Snapshot { step, t: step as f64, x: &x, v: &v })
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
        m.observe(&Snapshot { step: 0, t: 0.0, x: &x, v: &v0 }).unwrap();
        // One time unit later the kinetic energy ½ has become exactly the dissipated ½.
        let v1 = [[0.0; 3], [0.0, 0.0, 0.0]];
        let err = m.observe(&Snapshot { step: 1, t: 1.0, x: &x, v: &v1 });
        // The trapezoid saw power 1 then 0: Q = ½, so H + Q = H₀ holds exactly.
        assert_eq!(err, Ok(()));
        assert_eq!(m.finish().dissipators, [Kind::HarmonicBond]);
    }

    #[test]
    fn a_model_with_a_bad_body_is_rejected() {
        let mut bad = model();
        bad.bodies[0].mass = 0.0;
        assert!(Monitor::new(bad, vec![], 1).is_err());
    }
}
