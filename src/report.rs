//! The run's report, as text for people and as JSON for machines (the same data).

use lagra_checker::decision::Verdict;
use lagra_checker::model::UnitSystem;
use lagra_checker::monitor::Halt;
use lagra_checker::render::{lines, sci, up};
use lagra_kernel::solvers::Iterations;
use lagra_lang::scene::Scene;
use lagra_run::observables::{Estimate, Observables};
use lagra_run::run::{Measured, Report, Stop};
use serde::Serialize;
use std::fmt::Write;

#[derive(Serialize)]
pub struct TermCount {
    pub kind: &'static str,
    pub count: usize,
    pub dissipative: bool,
}

#[derive(Serialize)]
pub struct ClaimLine {
    pub line: String,
    #[serde(flatten)]
    pub verdict: Verdict,
}

#[derive(Serialize)]
pub struct Summary {
    pub file: String,
    pub scene: String,
    pub description: Option<String>,
    pub bodies: usize,
    pub terms: Vec<TermCount>,
    pub integrator: &'static str,
    /// The thermostat, in words (`None` at constant energy).
    pub thermostat: Option<String>,
    pub dt: f64,
    /// The unit `dt` is in: " s" for SI scenes, nothing for reduced units.
    #[serde(skip)]
    time_unit: &'static str,
    pub steps: u64,
    pub wall_s: f64,
    /// The checker's time judging the states, on whichever thread (on one CPU, its cost).
    pub checker_s: f64,
    /// Of `wall_s`, the kernel's thread's time on the checker: judging inline, or waiting for a
    /// verdict from the second thread (on two CPUs, its cost).
    pub checker_wait_s: f64,
    /// Of `wall_s`, the kernel's thread's time outside every pass that spreads over threads and
    /// outside the checker (Amdahl's serial part; at one thread, the serial fraction's numerator).
    pub serial_s: f64,
    /// None for a run that took no step (no rate to give).
    pub steps_per_s: Option<f64>,
    pub ns_per_atom_step: Option<f64>,
    /// How the iterations inside the solver's steps went (RATTLE's sweeps, action windows).
    pub iterations: Option<Iterations>,
    pub threads: usize,
    /// How each term group visited its bodies: `[kind, plan]`.
    pub plan: Vec<(&'static str, String)>,
    /// Where the checker ran.
    pub checker: &'static str,
    /// The helper threads the checker started for its sums: 0 where no checkpoint was big enough
    /// to spread, else one pool for the whole run (never a thread per checkpoint).
    pub checker_helpers: usize,
    /// In domains, how the energy and momentum were judged: from the ranks' parts at how many
    /// checkpoints, and where the parts were refused, why (`None` outside domains).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checker_parts: Option<String>,
    /// Print the plan in the text report too (`--explain`).
    #[serde(skip)]
    explain: bool,
    pub claims: Vec<ClaimLine>,
    pub predictions: Vec<Measured>,
    /// Means and standard errors after `equilibrate`: `observables.<name>.mean`, `.stderr`.
    pub observables: Option<Observables>,
    /// Why the run stopped early, if it did.
    pub halted: Option<String>,
    /// How many claims `@expect noether` generated (they are among `claims`).
    pub generated: usize,
    /// What Noether's theorem says of a failed claim.
    pub notes: Vec<String>,
    pub passed: bool,
}

impl Summary {
    pub fn new(file: &str, scene: &Scene, r: &Report, threads: usize, explain: bool) -> Summary {
        let mut terms: Vec<TermCount> = vec![];
        for t in &scene.model.terms {
            match terms.iter_mut().find(|c| c.kind == t.kind.name()) {
                Some(c) => {
                    c.count += 1;
                    c.dissipative |= t.dissipates();
                }
                None => terms.push(TermCount { kind: t.kind.name(), count: 1, dissipative: t.dissipates() }),
            }
        }
        let lines = lines(&r.outcome.verdicts, &scene.claims, &r.outcome.dissipators, scene.model.thermostat.is_some());
        let claims: Vec<ClaimLine> =
            r.outcome.verdicts.iter().zip(lines).map(|(v, line)| ClaimLine { line, verdict: v.clone() }).collect();
        let halted = r.stop.as_ref().map(|s| match s {
            Stop::Checker(Halt::Breach(b)) => {
                format!("halted at step {}: {} is certainly violated", b.step, b.claim.name())
            }
            Stop::Checker(Halt::InvalidState(m)) => format!("halted: {m}"),
            Stop::Solver { step, message } => format!("halted at step {step}: {message}"),
            Stop::Cancelled { step } => format!("cancelled at step {step}: the claims were judged up to there"),
            Stop::Until { step } => {
                format!("stopped at step {step}, as --until asked: the claims were judged up to there")
            }
        });
        // a run stopped where it was asked to stop has not failed
        let paused = matches!(r.stop, Some(Stop::Until { .. }));
        let passed = (halted.is_none() || paused)
            && claims.iter().all(|c| c.verdict.is_pass())
            && r.predictions.iter().all(|p| p.agrees);
        let atom_steps = r.steps as f64 * scene.model.bodies.len() as f64;
        Summary {
            file: file.to_string(),
            scene: scene.name.clone(),
            description: scene.description.clone(),
            bodies: scene.model.bodies.len(),
            terms,
            integrator: scene.solver.integrator.name(),
            thermostat: thermostat(scene),
            dt: scene.solver.dt,
            time_unit: if scene.model.units == UnitSystem::Si { " s" } else { "" },
            steps: r.steps,
            wall_s: r.wall_s,
            checker_s: r.checker_s,
            checker_wait_s: r.checker_wait_s,
            serial_s: r.serial_s,
            steps_per_s: (r.steps > 0).then(|| r.steps as f64 / r.wall_s),
            ns_per_atom_step: (r.steps > 0).then(|| r.wall_s * 1e9 / atom_steps),
            iterations: r.iterations.clone(),
            threads,
            plan: r
                .plan
                .iter()
                .map(|(k, p)| (k.name(), p.clone()))
                .chain(r.solver_plan.iter().map(|p| ("solver", p.clone())))
                .collect(),
            checker: r.checker,
            checker_helpers: lagra_checker::helpers::started(),
            checker_parts: parts_said(&r.outcome.parts),
            explain,
            claims,
            predictions: r.predictions.clone(),
            observables: r.observables.clone(),
            halted,
            generated: 0,
            notes: vec![],
            passed,
        }
    }

    pub fn text(&self) -> String {
        let mut s = String::new();
        let desc = self.description.as_deref().map(|d| format!(" — {d}")).unwrap_or_default();
        let _ = writeln!(s, "scene       {}{desc}", self.scene);
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|t| format!("{} ×{}{}", t.kind, t.count, if t.dissipative { " (dissipative)" } else { "" }))
            .collect();
        let terms = if terms.is_empty() { "none (free particles)".to_string() } else { terms.join(", ") };
        let _ = writeln!(s, "bodies      {}", self.bodies);
        let _ = writeln!(s, "terms       {terms}");
        let _ = writeln!(s, "integrator  {}, dt {}{}, {} steps", self.integrator, self.dt, self.time_unit, self.steps);
        if let Some(t) = &self.thermostat {
            let _ = writeln!(s, "thermostat  {t}");
        }
        let rate = match (self.steps_per_s, self.ns_per_atom_step) {
            (Some(steps), Some(ns)) => format!("{steps:.0} steps/s, {ns:.1} ns/atom-step, "),
            _ => String::new(),
        };
        let threads = format!("{} thread{}", self.threads, if self.threads == 1 { "" } else { "s" });
        let _ = writeln!(s, "wall        {:.3} s ({rate}{threads})", self.wall_s);
        if !self.claims.is_empty() {
            let _ = writeln!(
                s,
                "checker     {:.3} s judging, the kernel {:.3} s waiting for it",
                self.checker_s, self.checker_wait_s
            );
        }
        if let Some(it) = &self.iterations.as_ref().filter(|it| it.solves > 0) {
            let _ = writeln!(
                s,
                "iterations  {}: {} solves, {:.1} rounds each on average, at most {}; worst final residual {}{}",
                it.what,
                it.solves,
                it.iterations as f64 / it.solves as f64,
                it.most_iterations,
                up(it.worst_residual),
                // a solver that sweeps a fixed number of times has no tolerance
                if it.tol > 0.0 { format!(" (tol {})", sci(it.tol)) } else { String::new() }
            );
        }
        if self.explain {
            for (kind, plan) in &self.plan {
                let _ = writeln!(s, "plan        {kind}: {plan}");
            }
            let _ = writeln!(s, "plan        checker: {}", self.checker);
            let _ = writeln!(
                s,
                "serial      {:.3} s, {:.2}% of the wall: the kernel's thread outside every pass that spreads over threads (the checker's time apart)",
                self.serial_s,
                100.0 * self.serial_s / self.wall_s.max(f64::MIN_POSITIVE)
            );
            if let Some(p) = &self.checker_parts {
                let _ = writeln!(s, "plan        checker: {p}");
            }
        }
        if self.generated > 0 {
            let _ = writeln!(
                s,
                "noether     {} claim(s) from the scene's symmetries (`lagra noether FILE` says which)",
                self.generated
            );
        }
        for c in &self.claims {
            let _ = writeln!(s, "{}", c.line);
        }
        for n in &self.notes {
            let _ = writeln!(s, "noether     {n}");
        }
        for p in &self.predictions {
            let verdict = if p.agrees { "agrees" } else { "DISAGREES" };
            let tol = p.tol.map(|t| format!(" (tol {})", sci(t))).unwrap_or_default();
            let _ = match (p.measured, p.predicted, p.rel_diff, &p.detail) {
                (Some(m), Some(want), Some(d), _) => {
                    writeln!(s, "{} {verdict}  measured {m:.6} predicted {want:.6} rel diff {}{tol}", p.name, up(d))
                }
                (Some(_), None, _, Some(detail)) => writeln!(s, "{} {verdict}  {detail}{tol}", p.name),
                _ => writeln!(s, "{} NOT MEASURED  the run saw too little of the motion", p.name),
            };
        }
        if let Some(o) = &self.observables {
            observables(&mut s, o);
        }
        if let Some(h) = &self.halted {
            let _ = writeln!(s, "{h}");
        }
        s
    }
}

fn thermostat(scene: &Scene) -> Option<String> {
    use lagra_lang::thermostat::Thermostat;
    let bath = scene.bath()?;
    Some(match (scene.thermostat.as_ref()?, &scene.model.thermostat) {
        (Thermostat::NoseHoover { tau }, Some(c)) => format!(
            "nose_hoover at kT {}, tau {tau}: a chain of {} link(s) over {} degrees of freedom (the energy claim is about H′ = H + the chain's energy)",
            bath.kt,
            c.masses.len(),
            c.dof
        ),
        (Thermostat::Langevin { gamma, seed, .. }, _) => {
            format!("langevin at kT {}, gamma {gamma}, seed {seed} (BAOAB; no energy or momentum claim can hold)", bath.kt)
        }
        _ => return None,
    })
}

fn observables(s: &mut String, o: &Observables) {
    let samples = o.potential_energy_per_body.samples;
    let _ = writeln!(
        s,
        "observed    after step {}, every {} steps: {samples} samples, errors from {} blocks of {}",
        o.from_step,
        o.every,
        o.blocks,
        samples / o.blocks as u64
    );
    let show = |e: &Estimate| match e.stderr {
        Some(err) => format!("{:.6} ± {:.6}", e.mean, err),
        None => format!("{:.6} (too few samples for an error)", e.mean),
    };
    let tail = |x: Option<f64>| x.map(|t| format!(" (tail {t:.6} included)")).unwrap_or_default();
    let _ = writeln!(
        s,
        "  potential_energy_per_body  {}{}",
        show(&o.potential_energy_per_body),
        tail(o.tail.map(|t| t.energy_per_body))
    );
    let _ = writeln!(s, "  kinetic_temperature        {}", show(&o.kinetic_temperature));
    if let Some(p) = &o.pressure {
        let _ = writeln!(s, "  pressure                   {}{}", show(p), tail(o.tail.map(|t| t.pressure)));
    }
    if let Some(d) = &o.diffusion {
        let _ = writeln!(s, "  diffusion                  {}", show(d));
    }
    if let Some((r, g)) = o.rdf.as_ref().and_then(|r| r.peak()) {
        let _ = writeln!(
            s,
            "  rdf                        highest peak g = {g:.3} at r = {r:.3} ({} samples; --json has g(r))",
            o.rdf.as_ref().map_or(0, |r| r.samples)
        );
    }
    for n in &o.notes {
        let _ = writeln!(s, "  ({n})");
    }
}

/// What `--explain` says of the checkpoints judged from the ranks' parts (`None`: none was
/// offered them, as outside domains).
fn parts_said(p: &lagra_checker::monitor::FromParts) -> Option<String> {
    (p.used + p.refused > 0).then(|| {
        let refused = match (&p.why, p.refused) {
            (Some(why), n) if n > 0 => format!("; refused at {n} (the whole state judged there instead): {why}"),
            _ => String::new(),
        };
        format!(
            "energy and momentum enclosed by each rank over its own atoms and added outward at {} checkpoint(s){refused}",
            p.used
        )
    })
}
