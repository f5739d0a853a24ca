//! `lagra run FILE`.

use crate::progress::{Progress, When};
use crate::{noether, report};
use lagra_checker::certificate::{self, Certificate};
use lagra_checker::checksum::label;
use lagra_checker::decision::Verdict;
use lagra_checker::model::Snapshot;
use lagra_checker::states::StateWriter;
use lagra_kernel::lang::compile;
use lagra_kernel::run::{run, Options};
use lagra_kernel::solvers::Integrator;
use sha2::{Digest, Sha256};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file.
    file: PathBuf,
    /// Print the report as one JSON document instead of text.
    #[arg(long)]
    json: bool,
    /// Write one JSON line per frame (step, t, energy witness, positions, velocities).
    #[arg(long, value_name = "FILE.jsonl")]
    trace: Option<PathBuf>,
    /// Write the certificate: scene digest, canonical graph, claims, per-checkpoint
    /// enclosures, verdicts (re-check it with `lagra check` or `lagra-check`).
    #[arg(long, value_name = "FILE")]
    certificate: Option<PathBuf>,
    /// Write every state the checker saw, exactly, so a re-check can evaluate every claim again.
    #[arg(long, value_name = "FILE")]
    states: Option<PathBuf>,
    /// Run this many steps instead of the scene's own run length.
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
    /// Threads for the forces. Any count gives the same bits; more help only on thousands of
    /// bodies with pair terms.
    #[arg(long, value_name = "N", default_value_t = 1)]
    threads: usize,
    /// Print how each term group visits its bodies (every pair, cell list, Verlet list, chunks).
    #[arg(long)]
    explain: bool,
    /// A progress line on stderr (step, elapsed, time left): `auto` shows it when stderr is a
    /// terminal and the run takes over a second.
    #[arg(long, value_name = "WHEN", default_value = "auto")]
    progress: When,
    /// Refuse (exit 2) a scene that declares a claim its symmetries cannot support (momentum
    /// along a floor's normal); without it that is a warning.
    #[arg(long)]
    strict: bool,
}

/// What `lagra run --help` says after the options: the integrators a scene's `solver` block
/// may name, and the exit status.
pub fn after_help() -> String {
    let mut s = String::from("Integrators (solver { integrator: \"NAME\", ... } in the scene):\n");
    for i in Integrator::ALL {
        let settings = match i.settings() {
            [] => String::new(),
            names => format!(" [settings: {}]", names.join(", ")),
        };
        s += &format!("  {:<17} {}{settings}\n", i.name(), i.about());
    }
    s + "Without one, a scene gets velocity_verlet, or rattle if it declares constraints.\n\n\
Exit status: 0 every claim PASSed and every prediction agreed; 1 a claim FAILed or was UNDECIDED, a prediction \
disagreed or could not be measured, or the run halted (a singular force, an iteration that did not converge, a \
non-finite state); 2 bad input (the scene, a file, an argument)."
}

/// Bad input: the message on stderr, exit code 2.
fn bad(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("lagra: {msg}");
    ExitCode::from(2)
}

pub fn main(a: Args) -> ExitCode {
    let path = a.file.display().to_string();
    let source = match std::fs::read_to_string(&a.file) {
        Ok(s) => s,
        Err(e) => return bad(format!("cannot read {path}: {e}")),
    };
    let mut scene = match compile(&source) {
        Ok(s) => s,
        Err(d) => {
            eprintln!("{}", d.render(&path, &source));
            return ExitCode::from(2);
        }
    };
    let (analysis, warnings, generated) = noether::apply(&mut scene, &path, &source);
    warnings.iter().for_each(|w| eprintln!("{w}"));
    if a.strict && !warnings.is_empty() {
        return bad("--strict: a declared claim contradicts the scene's symmetries (see above)");
    }
    if a.steps == Some(0) {
        return bad("--steps must be at least 1");
    }
    if a.threads == 0 {
        return bad("--threads must be at least 1");
    }
    let mut trace = match a.trace.as_ref().map(File::create).transpose() {
        Ok(f) => f.map(BufWriter::new),
        Err(e) => return bad(format!("cannot create the trace file: {e}")),
    };
    let mut states = match a
        .states
        .as_ref()
        .map(|p| File::create(p).and_then(|f| StateWriter::new(BufWriter::new(f), scene.x0.len())))
        .transpose()
    {
        Ok(w) => w,
        Err(e) => return bad(format!("cannot create the state file: {e}")),
    };
    let mut record = recorder(|s| states.as_mut().map_or(Ok(()), |w| w.push(s)));
    let mut progress = Progress::new(a.progress, a.steps.unwrap_or(scene.solver.steps));
    let shown = progress.is_some();
    let mut tick = |step: u64| progress.as_mut().into_iter().for_each(|p| p.at(step));
    let result = run(
        &scene,
        Options {
            steps: a.steps,
            trace: trace.as_mut().map(|w| w as &mut dyn Write),
            record: a.states.is_some().then_some(&mut record),
            threads: a.threads,
            progress: shown.then_some(&mut tick),
        },
    );
    progress.iter().for_each(Progress::done);
    let flushed = trace.map(|mut t| t.flush()).transpose();
    let rep = match (result, flushed) {
        (Ok(r), Ok(_)) => r,
        (Err(e), _) => return bad(e),
        (_, Err(e)) => return bad(format!("writing the trace: {e}")),
    };
    let states_checksum = match states.map(StateWriter::finish).transpose() {
        Ok(sum) => sum.map(label),
        Err(e) => return bad(format!("writing the state file: {e}")),
    };
    let mut summary = report::Summary::new(&path, &scene, &rep, a.threads, a.explain);
    summary.generated = generated;
    summary.notes = scene
        .claims
        .iter()
        .zip(&summary.claims)
        .filter(|(_, line)| matches!(line.verdict, Verdict::Fail(_)))
        .filter_map(|(c, _)| noether::note(&analysis, c))
        .collect();
    if let Some(c) = &a.certificate {
        let digest: String = Sha256::digest(source.as_bytes()).iter().map(|b| format!("{b:02x}")).collect();
        let cert = Certificate {
            format: certificate::FORMAT.into(),
            scene: scene.name.clone(),
            source_digest: format!("sha256:{digest}"),
            model: scene.model.clone(),
            claims: scene.claims.clone(),
            run: certificate::Run {
                integrator: scene.solver.integrator.name().into(),
                dt: scene.solver.dt,
                planned_steps: rep.planned_steps,
                steps: rep.steps,
            },
            trails: rep.outcome.trails.clone(),
            verdicts: summary.claims.iter().map(|c| c.line.clone()).collect(),
            states_checksum,
            checksum: String::new(),
        }
        .seal();
        if let Err(e) = std::fs::write(c, cert.to_json() + "\n") {
            return bad(format!("cannot write the certificate {}: {e}", c.display()));
        }
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&summary).expect("the summary is plain data"));
    } else {
        print!("{}", summary.text());
    }
    if summary.passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

/// Pins a closure to the signature `Options::record` takes (for every lifetime of the snapshot).
fn recorder<F: FnMut(&Snapshot) -> std::io::Result<()>>(f: F) -> F {
    f
}
