//! Re-deriving a certificate's verdicts without the kernel: from the exact states when they are
//! given (every enclosure evaluated again), or else from the recorded enclosures (the decision
//! made again, the enclosures taken on trust).

use crate::certificate::{Certificate, Trail, ARITHMETIC};
use crate::checksum::label;
use crate::claims::ClaimKind;
use crate::decision::{decide_static, Judge, Verdict, PARTS};
use crate::monitor::{balance_terms, dimensions, is_balance, Monitor};
use crate::render::lines;
use crate::states::{State, States};

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

/// Re-derives every verdict of a run from its start; an `Err` is a certificate and state file
/// that do not fit together, or a segment of a resumed run given alone.
pub fn recheck(c: &Certificate, states: Option<&States>) -> Result<Recheck, String> {
    recheck_chain(std::slice::from_ref(c), states.map(std::slice::from_ref))
}

/// Re-derives the verdicts of a run cut into segments, each resumed from the restart file the
/// one before wrote, as one run: the segments must link up (each names the checksum of the one
/// before and starts at the step it stopped at, with the same model, claims, time step and
/// plan); their marks, or states, are judged in order as one run's; the last segment's verdicts
/// must be the re-derived ones, and each earlier segment's those of the run up to its end.
pub fn recheck_chain(chain: &[Certificate], states: Option<&[States]>) -> Result<Recheck, String> {
    links(chain)?;
    let c = chain.last().expect("links: at least one");
    let mut disagreements = vec![];
    let verdicts = match states {
        Some(s) => {
            let (verdicts, trails) = replay(chain, s)?;
            if let Some(c) = chain.iter().find(|c| c.arithmetic != ARITHMETIC) {
                let theirs = match c.arithmetic.as_str() {
                    "" => "an earlier checker arithmetic (not recorded before 2026-11-26)".to_string(),
                    named => format!("checker arithmetic {named}"),
                };
                disagreements.push(format!(
                    "the marks were computed in {theirs}, this checker's is {ARITHMETIC}: enclosures re-derived \
                     in other arithmetic do not agree to the bit; re-check with the lagra-check that wrote it"
                ));
            }
            let recorded = joined(chain);
            compare_trails(&recorded, &trails, &mut disagreements);
            match recorded.iter().flat_map(|t| &t.marks).any(|m| m.precision == PARTS) {
                // marks added up from a run's ranks' parts: each met its whole re-derivation
                // (`Mark::meets`); the verdicts follow from them, and the whole states must
                // reach the same ones
                true => {
                    let decided = redecide(chain, &mut disagreements);
                    for (i, (a, b)) in verdicts.iter().zip(&decided).enumerate() {
                        if a.is_pass() != b.is_pass() {
                            disagreements.push(format!(
                                "verdict {}: the whole states give {}, the ranks' parts {}",
                                i + 1,
                                if a.is_pass() { "a PASS" } else { "no PASS" },
                                if b.is_pass() { "a PASS" } else { "no PASS" }
                            ));
                        }
                    }
                    decided
                }
                false => verdicts,
            }
        }
        None => redecide(chain, &mut disagreements),
    };
    let dissipators = balance_terms(&c.model, is_balance(&c.model, &c.claims));
    let lines = lines(&verdicts, &c.claims, &dissipators, c.model.thermostat.is_some());
    if let Some((i, (a, b))) = lines.iter().zip(&c.verdicts).enumerate().find(|(_, (a, b))| a != b) {
        disagreements.push(format!("verdict {}: re-derived `{a}`, recorded `{b}`", i + 1));
    }
    Ok(Recheck { lines, disagreements, all_pass: verdicts.iter().all(Verdict::is_pass) })
}

/// The segments of one run, in order: each names the one before and starts where it stopped.
fn links(chain: &[Certificate]) -> Result<(), String> {
    let first = chain.first().ok_or("no certificate to re-check")?;
    if let Some(before) = &first.previous {
        return Err(format!(
            "it continues a run at step {} (the segment before: certificate {before}): re-check the whole \
             chain, every segment's certificate in order",
            first.run.first_step
        ));
    }
    if first.run.first_step != 0 {
        return Err(format!("it starts at step {} and names no segment before it", first.run.first_step));
    }
    for (n, (a, b)) in chain.iter().zip(&chain[1..]).enumerate().map(|(k, p)| (k + 2, p)) {
        if b.previous.as_ref() != Some(&a.checksum) {
            let named = b.previous.as_deref().unwrap_or("none");
            return Err(format!("certificate {n} does not follow certificate {}: it names {named} before it", n - 1));
        }
        if b.run.first_step != a.run.steps {
            return Err(format!(
                "certificate {n} starts at step {}, certificate {} stopped at step {}",
                b.run.first_step,
                n - 1,
                a.run.steps
            ));
        }
        let run = |c: &Certificate| (c.run.integrator.clone(), c.run.dt.to_bits(), c.run.planned_steps);
        if (&a.source_digest, &a.model, &a.claims, run(a)) != (&b.source_digest, &b.model, &b.claims, run(b)) {
            return Err(format!(
                "certificate {n} is of another scene, model, claims, integrator, time step or run length than \
                 certificate {}",
                n - 1
            ));
        }
    }
    Ok(())
}

/// Each claim's marks over the whole chain, in order.
fn joined(chain: &[Certificate]) -> Vec<Trail> {
    let mut trails = chain[0].trails.clone();
    for c in &chain[1..] {
        trails.iter_mut().zip(&c.trails).for_each(|(t, more)| t.marks.extend_from_slice(&more.marks));
    }
    trails
}

/// Runs the monitor again over every state of the files, one per segment; a segment's first
/// state is the one the segment before stopped at (judged there), to the bit.
fn replay(chain: &[Certificate], files: &[States]) -> Result<(Vec<Verdict>, Vec<Trail>), String> {
    if files.len() != chain.len() {
        return Err(format!("{} state files for {} certificates: one per segment, in order", files.len(), chain.len()));
    }
    let c0 = &chain[0];
    let mut monitor = Monitor::new(c0.model.clone(), c0.claims.clone(), c0.run.planned_steps)?;
    let mut halted = None;
    let mut before: Option<State> = None;
    for (n, (c, s)) in chain.iter().zip(files).enumerate().map(|(k, p)| (k + 1, p)) {
        let of = |e: String| if chain.len() > 1 { format!("segment {n}: {e}") } else { e };
        fits(c, s).map_err(of)?;
        for (k, state) in s.iter().enumerate() {
            let step = c.run.first_step + k as u64;
            let clock = step as f64 * c.run.dt;
            if state.step != step || state.t.to_bits() != clock.to_bits() {
                return Err(of(format!(
                    "state {k} is step {} at t = {}; the run's clock says step {step} at t = {clock}",
                    state.step, state.t
                )));
            }
            if k == 0 && n > 1 {
                if !before.as_ref().is_some_and(|b| bits(b) == bits(&state)) {
                    return Err(of(format!("its first state is not the state segment {} stopped at", n - 1)));
                }
                continue;
            }
            if let Some(h) = halted {
                return Err(of(format!("the states go on after the run must have {h}")));
            }
            halted = monitor.observe(&state.snapshot()).err();
        }
        before = s.iter().last();
    }
    let out = monitor.finish();
    Ok((out.verdicts, out.trails))
}

/// A state file that can be a certificate's: its sizes, checksum and number of states.
fn fits(c: &Certificate, s: &States) -> Result<(), String> {
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
    let want = c.run.steps - c.run.first_step + 1;
    if s.count != want {
        return Err(format!(
            "the state file holds {} states; a run of steps {}..={} has {want}",
            s.count, c.run.first_step, c.run.steps
        ));
    }
    Ok(())
}

/// A state's every number, as bits.
fn bits(s: &State) -> Vec<u64> {
    let numbers = s.x.iter().chain(&s.v).flatten().chain(s.chain.iter().flatten()).chain(s.spin.iter().flatten());
    [s.step, s.t.to_bits()].into_iter().chain(numbers.map(|x| x.to_bits())).collect()
}

/// The decision made again over the recorded enclosures, segment after segment; each earlier
/// segment's recorded verdicts compared with the decision up to its end.
fn redecide(chain: &[Certificate], disagreements: &mut Vec<String>) -> Vec<Verdict> {
    let c0 = &chain[0];
    let mut judges: Vec<(Judge, Option<Verdict>)> = c0.claims.iter().map(|c| (Judge::new(c.kind), None)).collect();
    let verdicts = |judges: &[(Judge, Option<Verdict>)]| -> Vec<Verdict> {
        c0.claims
            .iter()
            .zip(judges)
            .map(|(claim, (judge, failed))| match claim.kind {
                ClaimKind::DimensionalConsistency => decide_static(claim.kind, dimensions(&c0.model)),
                _ => failed.clone().unwrap_or_else(|| judge.clone().finish()),
            })
            .collect()
    };
    for (n, c) in chain.iter().enumerate().map(|(k, c)| (k + 1, c)) {
        for ((claim, trail), (judge, failed)) in c.claims.iter().zip(&c.trails).zip(&mut judges) {
            if claim.kind == ClaimKind::DimensionalConsistency {
                continue;
            }
            for m in &trail.marks {
                if failed.is_some() {
                    disagreements.push(format!("{}: checkpoints recorded after the failure", claim.kind.name()));
                    break;
                }
                if m.step < c.run.first_step + u64::from(n > 1) || m.step > c.run.steps {
                    disagreements.push(format!(
                        "{} at step {}: outside the steps {}..={} of its segment",
                        claim.kind.name(),
                        m.step,
                        c.run.first_step,
                        c.run.steps
                    ));
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
                    *failed = Some(Verdict::Fail(b));
                }
            }
        }
        if n < chain.len() {
            let dissipators = balance_terms(&c.model, is_balance(&c.model, &c.claims));
            let lines = lines(&verdicts(&judges), &c.claims, &dissipators, c.model.thermostat.is_some());
            if let Some((i, (a, b))) = lines.iter().zip(&c.verdicts).enumerate().find(|(_, (a, b))| a != b) {
                disagreements.push(format!("segment {n}, verdict {}: re-derived `{a}`, recorded `{b}`", i + 1));
            }
        }
    }
    verdicts(&judges)
}

fn compare_trails(recorded: &[Trail], derived: &[Trail], out: &mut Vec<String>) {
    for (r, d) in recorded.iter().zip(derived) {
        let name = r.claim.name();
        if let Some((a, b)) = r.marks.iter().zip(&d.marks).find(|(a, b)| !a.same(b) && !a.meets(b)) {
            out.push(format!(
                "{name} at step {}: recorded [{:e}, {:e}], re-derived [{:e}, {:e}] (step {})",
                a.step, a.lo, a.hi, b.lo, b.hi, b.step
            ));
        } else if r.marks.len() != d.marks.len() {
            out.push(format!("{name}: {} checkpoints recorded, {} re-derived", r.marks.len(), d.marks.len()));
        }
    }
}
