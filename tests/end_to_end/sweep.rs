//! `lagra sweep`: variants of a scene, each its own process and certificate; the settings reach
//! the runs, each certificate re-checks against the scene with its settings (and not without),
//! the bits do not depend on how many run at once, bad input stops the sweep before it runs,
//! and a stopped sweep reports no PASS it did not see.

use crate::common::{lagra, stderr, stdout};
use serde_json::Value;
use std::path::Path;

fn sweep_json(out: &Path, args: &[&str]) -> (Option<i32>, Value) {
    let o = lagra(&[&["sweep", "scenes/oscillator.lagra", "--json", "--out", out.to_str().unwrap()], args].concat());
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap_or_else(|e| panic!("{e}: {}{}", stdout(&o), stderr(&o)));
    (o.status.code(), v)
}

#[test]
fn each_variant_runs_its_settings_and_its_certificate_rechecks_with_them() {
    let dir = tempfile::tempdir().unwrap();
    let (code, s) = sweep_json(dir.path(), &["--set", "harmonic.k=1,8", "--dt", "0.002"]);
    // k = 8 breaks the energy claim at this time step: the sweep says so, and exits 1
    assert_eq!(code, Some(1), "{s}");
    let v = s["variants"].as_array().unwrap();
    assert_eq!(v.len(), 2);
    assert_eq!(v[0]["settings"], serde_json::json!(["harmonic.k=1", "dt=0.002"]));
    assert_eq!(v[0]["report"]["passed"], true);
    assert_eq!(v[1]["report"]["passed"], false);
    assert_eq!(s["passed"], false);
    // the damped period at k = 1: 2π/√(k/μ − (γ/2μ)²), μ = 1/2, γ = 0.04
    let period = v[0]["report"]["predictions"][0]["measured"].as_f64().unwrap();
    let expected = 2.0 * std::f64::consts::PI / (2.0f64 - 0.04f64.powi(2)).sqrt();
    assert!((period / expected - 1.0).abs() < 1e-4, "{period} against {expected}");
    let cert = dir.path().join("v0.cert.json");
    let with = lagra(&["check", cert.to_str().unwrap(), "--scene", "scenes/oscillator.lagra", "--set", "harmonic.k=1"]);
    assert_eq!(with.status.code(), Some(0), "{}{}", stdout(&with), stderr(&with));
    assert!(stdout(&with).contains("compiles to the certified model"));
    let without = lagra(&["check", cert.to_str().unwrap(), "--scene", "scenes/oscillator.lagra"]);
    assert_eq!(without.status.code(), Some(1));
    assert!(stdout(&without).contains("DISAGREES: the certified model"), "{}", stdout(&without));
    // the summary is on disk too, and the table names the axes and the measured period
    assert_eq!(
        serde_json::from_str::<Value>(&std::fs::read_to_string(dir.path().join("sweep.json")).unwrap()).unwrap(),
        s
    );
    let text = lagra(&[
        "sweep",
        "scenes/oscillator.lagra",
        "--quiet",
        "--set",
        "harmonic.k=1,8",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let table = stdout(&text);
    assert!(
        table.contains("harmonic.k") && table.contains("oscillator_period") && table.contains("1/2 variants PASS"),
        "{table}"
    );
    assert!(table.contains("(not: energy_conservation)"), "{table}");
}

#[test]
fn the_certificates_do_not_depend_on_how_many_run_at_once() {
    let (one, two) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let axes = ["--set", "harmonic.k=1,2,3", "--set", "body[0].velocity.x=0,0.1"];
    let (a, _) = sweep_json(one.path(), &[&axes[..], &["--jobs", "1"]].concat());
    let (b, _) = sweep_json(two.path(), &[&axes[..], &["--jobs", "3"]].concat());
    assert_eq!((a, b), (Some(0), Some(0)));
    for i in 0..6 {
        let name = format!("v{i}.cert.json");
        let (x, y) = (std::fs::read(one.path().join(&name)).unwrap(), std::fs::read(two.path().join(&name)).unwrap());
        assert!(x == y, "{name} differs between --jobs 1 and --jobs 3");
    }
    // the variants differ from each other: the settings reached them
    assert_ne!(
        std::fs::read(one.path().join("v0.cert.json")).unwrap(),
        std::fs::read(one.path().join("v1.cert.json")).unwrap()
    );
}

#[test]
fn bad_input_stops_the_sweep_before_any_variant_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    let o = out.to_str().unwrap();
    for (args, says) in [
        (vec!["--set", "spring.k=1,2"], "variant 0 (spring.k=1): `spring.k`: the scene has no term `spring`"),
        (vec!["--set", "harmonic.k=1,two"], "`two` is not a finite number"),
        (vec!["--set", "body[0].mass=1,0"], "variant 1 (body[0].mass=0): `body[0].mass=0`: a mass must be positive"),
        (
            vec!["--set", "harmonic.k=1", "--dt", "0.01,-1"],
            "variant 1 (harmonic.k=1 dt=-1): the time step must be positive",
        ),
        (vec!["--set", "harmonic.k=1", "--jobs", "0"], "--jobs"),
        (vec!["--set", "harmonic.k"], "write --set NAME=V1,V2"),
    ] {
        let r = lagra(&[&["sweep", "scenes/oscillator.lagra", "--out", o], &args[..]].concat());
        assert_eq!(r.status.code(), Some(2), "{args:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(says), "{args:?}: {}", stderr(&r));
        assert!(!out.exists(), "{args:?} made the folder");
    }
    let none = lagra(&["sweep", "scenes/oscillator.lagra"]);
    assert_eq!(none.status.code(), Some(2));
    assert!(stderr(&none).contains("an axis"), "{}", stderr(&none));
}

/// SIGTERM to the sweep (a batch system's limit) is passed on to the running variant, the ones
/// not started do not run, the summary is written, and nothing counts as a PASS.
#[test]
fn a_stopped_sweep_reports_what_it_saw_and_no_more() {
    let dir = tempfile::tempdir().unwrap();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["sweep", "scenes/oscillator.lagra", "--quiet", "--json", "--jobs", "1", "--steps", "1000000000"])
        .args(["--set", "harmonic.k=1,2", "--out"])
        .arg(dir.path())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // the first variant's report file is made just before its run starts
    let waited = std::time::Instant::now();
    while !dir.path().join("v0.json").exists() {
        assert!(waited.elapsed().as_secs() < 120, "the sweep never started its first variant");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    // SAFETY: kill only sends a signal to the child this test started
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(143));
    let s: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(s["passed"], false);
    assert!(s["stopped"].as_str().unwrap().contains("signal 15"), "{s}");
    let v = s["variants"].as_array().unwrap();
    assert_eq!(v[1]["failure"], "not run: the sweep was stopped");
    assert!(v[1]["report"].is_null());
    // the running one was told: it stopped with its certificate (or, if the signal came before
    // its handler was in place, died of it); either way not a PASS
    match v[0]["exit"].as_i64() {
        Some(143) => {
            assert!(v[0]["report"]["halted"].as_str().unwrap().contains("SIGTERM"), "{}", v[0]);
            assert!(dir.path().join("v0.cert.json").exists());
        }
        _ => assert_eq!(v[0]["failure"], "ended by signal 15", "{}", v[0]),
    }
}

/// A lagra built without MPI but started as one of several ranks would have every rank run the
/// whole sweep into the same folder: it refuses, saying how to build it.
#[cfg(not(feature = "mpi"))]
#[test]
fn without_mpi_a_rank_of_many_refuses() {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["sweep", "scenes/oscillator.lagra", "--set", "harmonic.k=1,2", "--out", "/nonexistent/never"])
        .env("OMPI_COMM_WORLD_SIZE", "2")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("one of 2 MPI ranks, but this lagra was built without MPI"), "{}", stderr(&o));
    assert!(stderr(&o).contains("--features mpi"), "{}", stderr(&o));
}
