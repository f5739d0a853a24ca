//! `lagra run FILE`.

use crate::{certificate, report};
use lagra_kernel::lang::compile;
use lagra_kernel::run::{run, Options};
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
    /// enclosures, verdicts.
    #[arg(long, value_name = "FILE")]
    certificate: Option<PathBuf>,
    /// Run this many steps instead of the scene's own run length.
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
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
    let scene = match compile(&source) {
        Ok(s) => s,
        Err(d) => {
            eprintln!("{}", d.render(&path, &source));
            return ExitCode::from(2);
        }
    };
    if a.steps == Some(0) {
        return bad("--steps must be at least 1");
    }
    let mut trace = match a.trace.as_ref().map(File::create).transpose() {
        Ok(f) => f.map(BufWriter::new),
        Err(e) => return bad(format!("cannot create the trace file: {e}")),
    };
    let result = run(&scene, Options { steps: a.steps, trace: trace.as_mut().map(|w| w as &mut dyn Write) });
    let flushed = trace.map(|mut t| t.flush()).transpose();
    let rep = match (result, flushed) {
        (Ok(r), Ok(_)) => r,
        (Err(e), _) => return bad(e),
        (_, Err(e)) => return bad(format!("writing the trace: {e}")),
    };
    let summary = report::Summary::new(&path, &scene, &rep);
    if let Some(c) = &a.certificate {
        if let Err(e) = certificate::write(c, &source, &scene, &rep, &summary) {
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
