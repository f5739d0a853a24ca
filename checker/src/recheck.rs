//! Re-deriving a certificate's verdicts without the kernel: from the exact states when they are
//! given (every enclosure evaluated again), or else from the recorded enclosures (the decision
//! made again, the enclosures taken on trust).

use crate::certificate::{Certificate, Trail, ARITHMETIC};
use crate::checksum::label;
use crate::claims::ClaimKind;
use crate::decision::{decide_static, Judge, Verdict};
use crate::monitor::{balance_terms, dimensions, is_balance, Monitor};
use crate::render::lines;
use crate::states::States;

pub struct Recheck {
    /// The re-derived verdict lines, one per claim.
    pub lines: Vec<String>,
    /// Where the re-derivation and the certificate part ways; empty when they agree.
    pub disagreements: Vec<String>,
    pub all_pass: bool,
}

impl Recheck {
    /// Exit status: 0 agreed and every claim passed, 1 otherwise.
    pub fn passed(&self) -> bool {
        self.disagreements.is_empty() && self.all_pass
    }
}

/// Re-derives every verdict; an `Err` is a certificate and state file that do not fit together.
pub fn recheck(c: &Certificate, states: Option<&States>) -> Result<Recheck, String> {
    let mut disagreements = vec![];
    let verdicts = match states {
        Some(s) => {
            let (verdicts, trails) = replay(c, s)?;
            if c.arithmetic != ARITHMETIC {
                let theirs = match c.arithmetic.as_str() {
                    "" => "an earlier checker arithmetic (not recorded before 2026-11-26)".to_string(),
                    named => format!("checker arithmetic {named}"),
                };
                disagreements.push(format!(
                    "the marks were computed in {theirs}, this checker's is {ARITHMETIC}: enclosures re-derived \
                     in other arithmetic do not agree to the bit; re-check with the lagra-check that wrote it"
                ));
            }
            compare_trails(&c.trails, &trails, &mut disagreements);
            verdicts
        }
        None => redecide(c, &mut disagreements),
    };
    let dissipators = balance_terms(&c.model, is_balance(&c.model, &c.claims));
    let lines = lines(&verdicts, &c.claims, &dissipators, c.model.thermostat.is_some());
    if let Some((i, (a, b))) = lines.iter().zip(&c.verdicts).enumerate().find(|(_, (a, b))| a != b) {
        disagreements.push(format!("verdict {}: re-derived `{a}`, recorded `{b}`", i + 1));
    }
    Ok(Recheck { lines, disagreements, all_pass: verdicts.iter().all(Verdict::is_pass) })
}

/// Runs the monitor again over every state of the file.
fn replay(c: &Certificate, s: &States) -> Result<(Vec<Verdict>, Vec<Trail>), String> {
    if s.bodies != c.model.bodies.len() {
        return Err(format!("the state file has {} bodies, the model {}", s.bodies, c.model.bodies.len()));
    }
    if s.spins != c.model.rigid().count() {
        return Err(format!("the state file has {} rigid bodies, the model {}", s.spins, c.model.rigid().count()));
    }
    if s.links != c.model.links() {
        return Err(format!("the state file has {} thermostat links, the model {}", s.links, c.model.links()));
    }
    if c.states_checksum.as_ref().is_some_and(|sum| *sum != label(s.checksum)) {
        return Err("the state file is not the one written with this certificate (checksums differ)".into());
    }
    if s.count != c.run.steps + 1 {
        return Err(format!(
            "the state file holds {} states; a run of {} steps has {}",
            s.count,
            c.run.steps,
            c.run.steps + 1
        ));
    }
    let mut monitor = Monitor::new(c.model.clone(), c.claims.clone(), c.run.planned_steps)?;
    let mut halted = None;
    for (k, state) in s.iter().enumerate() {
        let clock = k as f64 * c.run.dt;
        if state.step != k as u64 || state.t.to_bits() != clock.to_bits() {
            return Err(format!(
                "state {k} is step {} at t = {}; the run's clock says step {k} at t = {clock}",
                state.step, state.t
            ));
        }
        if let Some(h) = halted {
            return Err(format!("the states go on after the run must have {h}"));
        }
        halted = monitor.observe(&state.snapshot()).err();
    }
    let out = monitor.finish();
    Ok((out.verdicts, out.trails))
}

/// The decision made again over the recorded enclosures.
fn redecide(c: &Certificate, disagreements: &mut Vec<String>) -> Vec<Verdict> {
    let mut verdicts = vec![];
    for (claim, trail) in c.claims.iter().zip(&c.trails) {
        if claim.kind == ClaimKind::DimensionalConsistency {
            verdicts.push(decide_static(claim.kind, dimensions(&c.model)));
            continue;
        }
        let mut judge = Judge::new(claim.kind);
        let mut failed = None;
        for m in &trail.marks {
            if failed.is_some() {
                disagreements.push(format!("{}: checkpoints recorded after the failure", claim.kind.name()));
                break;
            }
            if claim.tol.is_some_and(|t| t.to_bits() != m.tol.to_bits()) {
                disagreements.push(format!(
                    "{} at step {}: held to tol {}, but the claim says {:?}",
                    claim.kind.name(),
                    m.step,
                    m.tol,
                    claim.tol
                ));
            }
            if let Err(b) = judge.admit(m.step, (m.lo, m.hi), m.tol, m.precision) {
                failed = Some(Verdict::Fail(b));
            }
        }
        verdicts.push(failed.unwrap_or_else(|| judge.finish()));
    }
    verdicts
}

fn compare_trails(recorded: &[Trail], derived: &[Trail], out: &mut Vec<String>) {
    for (r, d) in recorded.iter().zip(derived) {
        let name = r.claim.name();
        if let Some((a, b)) = r.marks.iter().zip(&d.marks).find(|(a, b)| !a.same(b)) {
            out.push(format!(
                "{name} at step {}: recorded [{:e}, {:e}], re-derived [{:e}, {:e}] (step {})",
                a.step, a.lo, a.hi, b.lo, b.hi, b.step
            ));
        } else if r.marks.len() != d.marks.len() {
            out.push(format!("{name}: {} checkpoints recorded, {} re-derived", r.marks.len(), d.marks.len()));
        }
    }
}
