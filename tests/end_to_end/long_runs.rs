//! Long runs: a run's memory does not grow with its length (the checker's marks go to disk as
//! they are made, or nowhere without a certificate), a signal stops a run with its files
//! written, and a halt on huge coordinates says what overflowed, with the numbers.

use crate::common::{lagra, scene, stderr, stdout};
use std::process::Command;

/// `lagra ARGS` with its address space capped at `kib` KiB (`ulimit -v`).
fn capped(kib: u64, args: &[&str]) -> std::process::Output {
    Command::new("bash")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_lagra"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

/// A million steps of the oscillator, both claims checked at every step and the certificate
/// written, in 64 MiB of address space: keeping every mark in memory, as Lagra did, needed about
/// 115 MB more than ten thousand steps and aborted under this cap. The certificate holds all
/// 2·10⁶ marks and re-checks.
#[test]
fn a_million_checked_steps_run_in_64_mib() {
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("run.cert");
    let c = cert.to_str().unwrap();
    let out =
        capped(64 << 10, &["run", "scenes/oscillator.lagra", "--steps", "1000000", "--quiet", "--certificate", c]);
    assert!(!stderr(&out).contains("memory allocation"), "{}", stderr(&out));
    // the period prediction may disagree this far out (the amplitude has decayed to round-off)
    assert!(stdout(&out).contains("energy_conservation PASS"), "{}{}", stdout(&out), stderr(&out));
    assert!(stdout(&out).contains("over 1000000 checkpoints"), "{}", stdout(&out));
    let read = lagra_checker::certificate::Certificate::read(&std::fs::read_to_string(&cert).unwrap()).unwrap();
    let marks: Vec<usize> = read.trails.iter().map(|t| t.marks.len()).collect();
    // both are conservation laws: nothing to compare at step 0
    assert_eq!(marks, [1_000_000, 1_000_000]);
    assert!(read.trails.iter().all(|t| t.marks.iter().zip(1..).all(|(m, step)| m.step == step)));
    let again = lagra(&["check", c]);
    assert!(stdout(&again).contains("AGREES"), "{}{}", stdout(&again), stderr(&again));
}

/// A body 10³⁰⁸ away on the oscillator's bond: the halt names what overflowed (the bond's force
/// or energy, not a near singularity) and how far apart the bodies are.
#[test]
fn a_huge_separation_is_named_with_its_value() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/oscillator.lagra")).unwrap();
    let far = scene(dir.path(), "far.lagra", &text.replace("[-1.35, 0, 0]", "[-1e308, 0, 0]"));
    let out = lagra(&["run", far.to_str().unwrap(), "--steps", "10", "--json"]);
    let said = stdout(&out) + &stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("HarmonicBond: bodies 0, 1: its force or energy overflows binary64"), "{said}");
    assert!(said.contains("the bodies 1e308 apart"), "{said}");
    assert!(!said.contains("close"), "{said}");
}

/// SIGTERM (a batch system's time limit) stops a long run at its next look: the exit status is
/// 143, the report and the certificate say where and why, the claims are judged up to there
/// and the certificate re-checks. The signal is sent once the run reports progress, so that its
/// handler is in place.
#[test]
fn sigterm_stops_a_run_with_its_certificate_written() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("run.cert");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["run", "scenes/oscillator.lagra", "--steps", "1000000000", "--progress", "always", "--certificate"])
        .arg(&cert)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut progress = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    progress.read_line(&mut line).unwrap();
    assert!(line.starts_with("lagra: step "), "{line}");
    // SAFETY: kill only sends a signal to the child this test started
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    std::thread::spawn(move || std::io::copy(&mut progress, &mut std::io::sink()));
    let out = child.wait_with_output().unwrap();
    let said = stdout(&out);
    assert_eq!(out.status.code(), Some(143), "{said}");
    assert!(said.contains("by a signal (SIGTERM): the claims were judged up to there"), "{said}");
    assert!(said.contains("energy_conservation PASS"), "{said}");
    let read = lagra_checker::certificate::Certificate::read(&std::fs::read_to_string(&cert).unwrap()).unwrap();
    let stopped = read.run.stopped.clone().unwrap();
    assert!(stopped.contains("SIGTERM") && read.run.steps < read.run.planned_steps, "{stopped}");
    assert_eq!(read.trails[1].marks.last().map(|m| m.step), Some(read.run.steps));
    let again = lagra(&["check", cert.to_str().unwrap()]);
    assert!(stdout(&again).contains("AGREES"), "{}{}", stdout(&again), stderr(&again));
}

/// Under an address-space cap (`ulimit -v`, as a batch system sets one) a lattice that would not
/// fit is refused before anything is allocated, at the line that asked for it; the same scene
/// with room compiles.
#[test]
fn a_lattice_beyond_the_memory_cap_is_refused_where_it_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bench/lj_32k.lagra")).unwrap();
    // 500,000 bodies: about 1.25 GB by the estimate, in a process capped at 512 MiB
    let big = scene(dir.path(), "big.lagra", &text.replace("[20, 20, 20]", "[50, 50, 50]"));
    let out = capped(512 << 10, &["run", big.to_str().unwrap(), "--steps", "1"]);
    let said = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(
        said.contains("big.lagra:10:") && said.contains("a lattice of 500000 bodies would need about 1.2 GB"),
        "{said}"
    );
    assert!(said.contains("this process may take 0.") && said.contains("GB more"), "{said}");
    let roomy = capped(4 << 20, &["run", big.to_str().unwrap(), "--steps", "1", "--quiet"]);
    assert_eq!(roomy.status.code(), Some(0), "{}{}", stdout(&roomy), stderr(&roomy));
}
