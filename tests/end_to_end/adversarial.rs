//! A certificate must be hard to fool: every edit below is rejected or FAILs, never PASSes, and
//! nothing panics. The adversary may re-seal checksums, so what catches a forgery is the
//! re-derivation from the states (and, for the scene itself, `--scene`).

use lagra_checker::certificate::Certificate;
use lagra_checker::checksum::{label, Fnv};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

struct Run {
    _dir: tempfile::TempDir,
    cert: PathBuf,
    states: PathBuf,
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh certificate and state file of the oscillator.
fn oscillator() -> Run {
    run("scenes/oscillator.lagra", &[])
}

/// A fresh certificate and state file of a shipped scene, run with `args` besides.
fn run(scene: &str, args: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let (cert, states) = (dir.path().join("run.cert"), dir.path().join("run.states"));
    let o = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["run", scene])
        .args(args)
        .arg("--certificate")
        .arg(&cert)
        .arg("--states")
        .arg(&states)
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stdout));
    Run { _dir: dir, cert, states }
}

/// Runs `lagra check` and `lagra-check` with the same arguments: they must agree exactly.
fn check(args: &[&Path]) -> (i32, String, String) {
    let standalone = Path::new(env!("CARGO_BIN_EXE_lagra")).with_file_name("lagra-check");
    let a: Output = Command::new(env!("CARGO_BIN_EXE_lagra")).arg("check").args(args).output().unwrap();
    let b: Output = Command::new(standalone).args(args).output().unwrap();
    let text =
        |o: &Output| (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned());
    assert_eq!((a.status.code(), text(&a)), (b.status.code(), text(&b)), "lagra check and lagra-check differ");
    let (out, err) = text(&a);
    assert!(!err.contains("panicked") && !out.contains("panicked"), "{err}");
    (a.status.code().unwrap(), out, err)
}

fn with_states(r: &Run) -> (i32, String, String) {
    check(&[&r.cert, Path::new("--states"), &r.states])
}

/// Edits the certificate; with `reseal` the checksum is recomputed as a forger would.
fn edit_cert(r: &Run, reseal: bool, f: impl FnOnce(&mut Certificate)) {
    let mut c: Certificate = serde_json::from_str(&std::fs::read_to_string(&r.cert).unwrap()).unwrap();
    f(&mut c);
    let c = if reseal { c.seal().unwrap() } else { c };
    std::fs::write(&r.cert, c.to_json()).unwrap();
}

/// Byte offset of body `b`'s velocity component `c` in state `k` of a 2-body state file.
fn velocity_at(k: usize, b: usize, c: usize) -> usize {
    24 + (16 + 48 * 2) * k + 16 + 24 * 2 + 8 * (3 * b + c)
}

/// Edits the state file; with `reseal` its checksum and the certificate's link to it are
/// recomputed as a forger would.
fn edit_states(r: &Run, reseal: bool, f: impl FnOnce(&mut Vec<u8>)) {
    let mut b = std::fs::read(&r.states).unwrap();
    f(&mut b);
    if reseal {
        let n = b.len();
        let sum = Fnv::of(&b[..n - 8]);
        b[n - 8..].copy_from_slice(&sum.to_le_bytes());
        edit_cert(r, true, |c| c.states_checksum = Some(label(sum)));
    }
    std::fs::write(&r.states, b).unwrap();
}

fn set_f64(b: &mut [u8], at: usize, x: f64) {
    b[at..at + 8].copy_from_slice(&x.to_le_bytes());
}

fn get_f64(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

#[test]
fn an_honest_certificate_is_re_derived_identically_every_time() {
    let r = oscillator();
    let (code, first, _) = with_states(&r);
    assert_eq!(code, 0, "{first}");
    assert!(first.contains("re-check    AGREES with the certificate"), "{first}");
    assert_eq!(with_states(&r).1, first, "not deterministic");
    let (code, out, _) = check(&[&r.cert]);
    assert_eq!(code, 0);
    assert!(out.contains("evidence    none"), "{out}");
}

#[test]
fn a_certificate_of_other_checker_arithmetic_is_told_apart() {
    // written before the revision was recorded (no `arithmetic` field): it still reads, and a
    // re-check from the states says why its bits cannot be compared
    let r = oscillator();
    edit_cert(&r, true, |c| c.arithmetic.clear());
    assert!(!std::fs::read_to_string(&r.cert).unwrap().contains("\"arithmetic\""));
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("DISAGREES with the certificate: the marks were computed in an earlier checker arithmetic"),
        "{out}"
    );
    edit_cert(&r, true, |c| c.arithmetic = "2020-01-01".into());
    let (_, out, _) = with_states(&r);
    assert!(out.contains("computed in checker arithmetic 2020-01-01, this checker's is"), "{out}");
    // the decision alone does not depend on the arithmetic
    let (code, out, _) = check(&[&r.cert]);
    assert_eq!(code, 0, "{out}");
}

#[test]
fn a_state_moved_by_one_ulp_is_caught() {
    let r = oscillator();
    edit_states(&r, false, |b| {
        let at = velocity_at(2500, 0, 0);
        let x = get_f64(b, at);
        set_f64(b, at, f64::from_bits(x.to_bits() + 1));
    });
    let (code, _, err) = with_states(&r);
    assert_eq!(code, 2);
    assert!(err.contains("checksum does not match"), "{err}");
    // re-sealed: the re-evaluated enclosure at that step is not the recorded one
    edit_states(&r, true, |_| {});
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("DISAGREES with the certificate: momentum_conservation at step 2500"), "{out}");
}

#[test]
fn a_state_changed_so_that_the_claim_breaks_fails() {
    let r = oscillator();
    edit_states(&r, true, |b| {
        let at = velocity_at(5000, 1, 0);
        let v = get_f64(b, at);
        set_f64(b, at, v * 1.01 + 1e-3);
    });
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("energy_conservation FAIL  at step 5000"), "{out}");
    assert!(out.contains("momentum_conservation FAIL  at step 5000"), "{out}");
    assert!(!out.contains("PASS"), "{out}");
}

#[test]
fn an_edited_enclosure_is_caught() {
    let r = oscillator();
    edit_cert(&r, false, |c| c.trails[1].marks[100].hi *= 2.0);
    assert_eq!(with_states(&r).0, 2, "checksum");
    edit_cert(&r, true, |_| {});
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("DISAGREES with the certificate: energy_conservation at step 101"), "{out}");
    // an enclosure pushed past the tolerance fails even the decision-only re-check
    edit_cert(&r, true, |c| (c.trails[1].marks[100].lo, c.trails[1].marks[100].hi) = (1.0, 1.0));
    let (code, out, _) = check(&[&r.cert]);
    assert_eq!(code, 1);
    assert!(out.contains("energy_conservation FAIL  at step 101"), "{out}");
    // and an upside-down one is not an enclosure at all
    edit_cert(&r, true, |c| c.trails[1].marks[100].lo = 2.0);
    let (code, _, err) = check(&[&r.cert]);
    assert_eq!(code, 2);
    assert!(err.contains("enclosure [2, 1] is upside down"), "{err}");
}

#[test]
fn a_loosened_tolerance_is_caught() {
    let r = oscillator();
    edit_cert(&r, false, |c| c.claims[1].tol = Some(1e-3));
    assert_eq!(with_states(&r).0, 2, "checksum");
    edit_cert(&r, true, |_| {});
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("DISAGREES"), "{out}");
    // and a forger who also rewrites every recorded tolerance and line is stopped by the scene
    edit_cert(&r, true, |c| {
        c.trails[1].marks.iter_mut().for_each(|m| m.tol = 1e-3);
        c.verdicts[1] = c.verdicts[1].replace("tol 1e-05", "tol 1e-03");
    });
    assert_eq!(with_states(&r).0, 0, "a consistent forgery re-checks on its own");
    let o = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["check", r.cert.to_str().unwrap(), "--scene", "scenes/oscillator.lagra"])
        .current_dir(root())
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("scene       DISAGREES: the certified claims are not the ones the source declares"), "{out}");
}

#[test]
fn a_changed_parameter_in_the_graph_is_caught() {
    let r = oscillator();
    edit_cert(&r, true, |c| c.model.terms[0].params[0] = 2.0000001);
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("DISAGREES with the certificate: energy_conservation"), "{out}");
}

#[test]
fn truncated_and_wrong_version_certificates_are_rejected() {
    let r = oscillator();
    let text = std::fs::read_to_string(&r.cert).unwrap();
    std::fs::write(&r.cert, &text[..text.len() / 2]).unwrap();
    let (code, _, err) = with_states(&r);
    assert_eq!(code, 2);
    assert!(err.contains("not JSON") && err.contains("truncated?"), "{err}");
    std::fs::write(&r.cert, text.replace("lagra-certificate/1", "lagra-certificate/9")).unwrap();
    let (code, _, err) = with_states(&r);
    assert_eq!(code, 2);
    assert!(err.contains("format `lagra-certificate/9` is not supported"), "{err}");
    std::fs::write(&r.cert, "{}").unwrap();
    assert!(with_states(&r).2.contains("no `format` field"));
}

#[test]
fn nan_infinite_subnormal_and_huge_coordinates_never_pass() {
    // A tiny velocity where there was none leaves the claims true but the states are not the
    // certified ones: the momentum's enclosure, re-derived, moves. (One below 2⁻⁵¹¹ ≈ 1.5e-154,
    // the least step outward of the checker's arithmetic, can leave every enclosure the same to
    // the bit: the certificate then still tells the truth about the states it is checked
    // against.)
    let r = oscillator();
    edit_states(&r, true, |b| set_f64(b, velocity_at(3000, 0, 1), 1e-150));
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("DISAGREES with the certificate: momentum_conservation at step 3000"), "{out}");
    for (x, what) in [(f64::NAN, "NaN"), (f64::INFINITY, "inf"), (f64::NEG_INFINITY, "-inf"), (1e308, "huge")] {
        let r = oscillator();
        edit_states(&r, true, |b| set_f64(b, velocity_at(3000, 0, 1), x));
        // The run would have halted at step 3000, but the forged states go on: rejected.
        let (code, out, err) = with_states(&r);
        assert_eq!(code, 2, "{what}: {out}{err}");
        assert!(err.contains("the states go on after the run must have halted"), "{what}: {err}");
        if x.is_finite() {
            assert!(err.contains("at step 3000: momentum_conservation is certainly violated"), "{what}: {err}");
        } else {
            assert!(err.contains("step 3000: body 0 has a non-finite coordinate"), "{what}: {err}");
        }
    }
}

#[test]
fn a_non_finite_last_state_fails_every_claim() {
    let r = oscillator();
    edit_states(&r, true, |b| set_f64(b, velocity_at(5000, 1, 2), f64::NAN));
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 1);
    assert!(out.contains("momentum_conservation FAIL  step 5000: body 1 has a non-finite coordinate"), "{out}");
    assert!(out.contains("energy_conservation FAIL  step 5000: body 1 has a non-finite coordinate"), "{out}");
}

#[test]
fn an_empty_scene_is_rejected() {
    let r = oscillator();
    edit_cert(&r, true, |c| c.model.bodies.clear());
    let (code, _, err) = with_states(&r);
    assert_eq!(code, 2);
    assert!(err.contains("the scene has no bodies"), "{err}");
}

#[test]
fn a_million_body_header_with_no_data_is_rejected() {
    let r = oscillator();
    let mut b = b"lagra-states/1\0\0".to_vec();
    b.extend(1_000_000u64.to_le_bytes());
    b.extend(0u64.to_le_bytes());
    b.extend(Fnv::of(&b).to_le_bytes());
    std::fs::write(&r.states, b).unwrap();
    let (code, _, err) = with_states(&r);
    assert_eq!(code, 2);
    assert!(err.contains("the state file has 1000000 bodies, the model 2"), "{err}");
}

#[test]
fn states_of_another_run_are_rejected() {
    let (a, b) = (oscillator(), oscillator());
    std::fs::copy(&b.states, &a.states).unwrap();
    assert_eq!(with_states(&a).0, 0, "the same scene gives the same states, bit for bit");
    let o = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["run", "scenes/oscillator.lagra", "--steps", "4000", "--states"])
        .arg(&a.states)
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let (code, _, err) = with_states(&a);
    assert_eq!(code, 2);
    assert!(err.contains("not the one written with this certificate"), "{err}");
}

/// A forger who moves one of a hinge's pins by a centimetre in the model, and re-seals: the
/// re-check measures the gap of the pin as written against the states, finds it open from step
/// 0, where an honest run would have halted, and refuses the states that go on.
#[test]
fn a_joint_pin_moved_in_the_certificate_fails_its_claim() {
    let r = run("scenes/hinged_chain.lagra", &["--steps", "200", "--quiet"]);
    let (code, out, _) = with_states(&r);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("joint_satisfied PASS"), "{out}");
    edit_cert(&r, true, |c| c.model.pins[5].on_b[1] += 0.01);
    let (code, out, err) = with_states(&r);
    assert_eq!(code, 2, "{out}");
    assert!(err.contains("must have halted at step 0: joint_satisfied is certainly violated"), "{out}{err}");
}
