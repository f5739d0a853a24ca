//! The re-check as a command: `lagra-check` and `lagra check` both print this.

use crate::certificate::Certificate;
use crate::recheck::recheck_chain;
use crate::states::States;
use std::fmt::Write;
use std::io::Read;
use std::path::Path;

/// What the command prints and how it exits (0 agreed and passed, 1 not, 2 unreadable input).
pub struct Report {
    pub stdout: String,
    pub stderr: String,
    pub code: u8,
}

pub const USAGE: &str = "usage: lagra-check CERTIFICATE... [--states FILE]...

Re-derives every verdict of a Lagra certificate without the kernel. With --states (the exact
states `lagra run --states` wrote), every enclosure is evaluated again; without, the decision is
made again over the enclosures the certificate records.

A run cut into segments (`lagra run --resume`) is re-checked as one run: name every segment's
certificate in order, and with --states every segment's state file, in the same order. The
segments must link up: each names the checksum of the one before and starts where it stopped.

Exit status: 0 the re-derivation agrees with the certificate and every claim PASSed; 1 it
disagrees, or a claim did not PASS; 2 a file is missing, malformed, or does not fit the other.";

/// A regular file of at most `limit` bytes (or what the environment variable `var` says),
/// refused before it is opened if it is anything else: `/dev/zero` or a FIFO never hangs.
fn read(p: &Path, var: &str, limit: u64) -> Result<Vec<u8>, String> {
    let limit = std::env::var(var).ok().and_then(|v| v.trim().parse().ok()).unwrap_or(limit);
    let m = std::fs::metadata(p).map_err(|e| e.to_string())?;
    let (fits, mut out) = (m.is_file() && m.len() <= limit, vec![]);
    if fits {
        std::fs::File::open(p).and_then(|f| f.take(limit + 1).read_to_end(&mut out)).map_err(|e| e.to_string())?;
    }
    match fits && out.len() as u64 <= limit {
        true => Ok(out),
        false => Err(format!("not a regular file of at most {limit} bytes ({var} raises the limit)")),
    }
}

/// The re-check of one certificate, with its state file if given.
pub fn check(cert: &Path, states: Option<&Path>) -> Report {
    check_chain(&[cert], states.as_slice())
}

/// The re-check of the certificates of a run's segments, in order (one for a run in one
/// piece), with one state file each or none.
pub fn check_chain(certs: &[&Path], states: &[&Path]) -> Report {
    let bad = |msg: String| Report { stdout: String::new(), stderr: format!("lagra-check: {msg}\n"), code: 2 };
    let mut chain = vec![];
    for cert in certs {
        let text = match read(cert, "LAGRA_MAX_CERTIFICATE_BYTES", 1 << 30).map(String::from_utf8) {
            Ok(Ok(t)) => t,
            Ok(Err(_)) => return bad(format!("cannot read {}: not UTF-8 text", cert.display())),
            Err(e) => return bad(format!("cannot read {}: {e}", cert.display())),
        };
        match Certificate::read(&text) {
            Ok(c) => chain.push(c),
            Err(e) => return bad(format!("{}: {e}", cert.display())),
        }
    }
    let mut files = vec![];
    for p in states {
        match read(p, "LAGRA_MAX_STATES_BYTES", 16 << 30).and_then(States::read) {
            Ok(s) => files.push(s),
            Err(e) => return bad(format!("{}: {e}", p.display())),
        }
    }
    let named = certs.iter().map(|c| c.display().to_string()).collect::<Vec<_>>().join(", ");
    let r = match recheck_chain(&chain, (!states.is_empty()).then_some(files.as_slice())) {
        Ok(r) => r,
        Err(e) => return bad(format!("{named}: {e}")),
    };
    let Some(c) = chain.last() else { return bad("no certificate given".into()) };
    let mut out = String::new();
    let _ = writeln!(out, "certificate {named} ({}, scene {}, {})", c.format, c.scene, c.source_digest);
    if chain.len() > 1 {
        let _ = writeln!(
            out,
            "chain       {} segments, steps 0..={}, each continuing the one before",
            chain.len(),
            c.run.steps
        );
    }
    let count: u64 = files.iter().map(|s| s.count).sum();
    let from = states.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    let _ = match states.is_empty() {
        false => writeln!(out, "evidence    {count} states from {from}: every enclosure re-evaluated"),
        true => writeln!(
            out,
            "evidence    none: the decision re-derived from the recorded enclosures (--states re-evaluates them)"
        ),
    };
    for l in &r.lines {
        let _ = writeln!(out, "{l}");
    }
    let _ = match r.disagreements.first() {
        None => writeln!(out, "re-check    AGREES with the certificate"),
        Some(d) => {
            writeln!(out, "re-check    DISAGREES with the certificate: {d} ({} difference(s))", r.disagreements.len())
        }
    };
    Report { stdout: out, stderr: String::new(), code: if r.passed() { 0 } else { 1 } }
}
