//! The standalone binary: usage and exit codes (the adversarial suite in the root package runs
//! it on real certificates).

use std::process::Command;

fn lagra_check(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_lagra-check")).args(args).output().unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into(), String::from_utf8_lossy(&o.stderr).into())
}

#[test]
fn help_says_what_it_does_and_how_it_exits() {
    let (code, out, _) = lagra_check(&["--help"]);
    assert_eq!(code, Some(0));
    assert!(out.starts_with("usage: lagra-check CERTIFICATE... [--states FILE]...") && out.contains("Exit status"));
    assert!(out.contains("re-checked as one run"), "{out}");
}

#[test]
fn bad_invocations_exit_2() {
    assert_eq!(lagra_check(&[]).0, Some(2));
    assert_eq!(lagra_check(&["a", "b"]).0, Some(2));
    let (code, _, err) = lagra_check(&["a", "b", "--states", "s"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("1 state files for 2 certificates"), "{err}");
    assert_eq!(lagra_check(&["--frobnicate"]).0, Some(2));
    assert_eq!(lagra_check(&["x.cert", "--states"]).0, Some(2));
    let (code, _, err) = lagra_check(&["/no/such/file.cert"]);
    assert_eq!(code, Some(2));
    assert!(err.starts_with("lagra-check: cannot read /no/such/file.cert"), "{err}");
}
