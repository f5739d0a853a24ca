//! The re-check as a command: `lagra-check` and `lagra check` both print this.

use crate::certificate::Certificate;
use crate::recheck::recheck;
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

pub const USAGE: &str = "usage: lagra-check CERTIFICATE [--states FILE]

Re-derives every verdict of a Lagra certificate without the kernel. With --states (the exact
states `lagra run --states` wrote), every enclosure is evaluated again; without, the decision is
made again over the enclosures the certificate records.

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

pub fn check(cert: &Path, states: Option<&Path>) -> Report {
    let bad = |msg: String| Report { stdout: String::new(), stderr: format!("lagra-check: {msg}\n"), code: 2 };
    let text = match read(cert, "LAGRA_MAX_CERTIFICATE_BYTES", 1 << 30).map(String::from_utf8) {
        Ok(Ok(t)) => t,
        Ok(Err(_)) => return bad(format!("cannot read {}: not UTF-8 text", cert.display())),
        Err(e) => return bad(format!("cannot read {}: {e}", cert.display())),
    };
    let c = match Certificate::read(&text) {
        Ok(c) => c,
        Err(e) => return bad(format!("{}: {e}", cert.display())),
    };
    let s = match states.map(|p| read(p, "LAGRA_MAX_STATES_BYTES", 16 << 30).and_then(States::read).map(|s| (p, s))) {
        None => None,
        Some(Ok(s)) => Some(s),
        Some(Err(e)) => return bad(format!("{}: {e}", states.map(|p| p.display().to_string()).unwrap_or_default())),
    };
    let r = match recheck(&c, s.as_ref().map(|s| &s.1)) {
        Ok(r) => r,
        Err(e) => return bad(format!("{}: {e}", cert.display())),
    };
    let mut out = String::new();
    let _ = writeln!(out, "certificate {} ({}, scene {}, {})", cert.display(), c.format, c.scene, c.source_digest);
    let _ = match &s {
        Some((p, s)) => {
            writeln!(out, "evidence    {} states from {}: every enclosure re-evaluated", s.count, p.display())
        }
        None => writeln!(
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
