//! The peak resident memory of a run does not follow its length. Alone in its test binary:
//! `getrusage(RUSAGE_CHILDREN)` reports the largest peak of any child this process has waited
//! for, so no other test may start one beside it.

mod common;
use common::stdout;
use std::process::Command;

/// The peak resident memory of a million checked steps is that of ten thousand, within 8 MiB
/// (the marks alone of the million would be 72 MB). `getrusage` gives the largest child's peak
/// so far, so the short run goes first.
#[test]
fn the_peak_memory_does_not_follow_the_steps() {
    let peak = || {
        let mut u = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage fills the struct it is handed, which is zeroed and the right type
        assert_eq!(unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, u.as_mut_ptr()) }, 0);
        unsafe { u.assume_init() }.ru_maxrss
    };
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("run.cert");
    let run = |steps: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_lagra"))
            .args(["run", "scenes/oscillator.lagra", "--quiet", "--steps", steps, "--certificate"])
            .arg(&cert)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(stdout(&out).contains("energy_conservation PASS"), "{}", stdout(&out));
        peak()
    };
    let short = run("10000");
    let long = run("1000000");
    assert!(long <= short + 8 * 1024, "peak RSS {short} KiB at 10⁴ steps, {long} KiB at 10⁶");
}
