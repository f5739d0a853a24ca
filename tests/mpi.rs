//! Under `mpirun` (built with `--features mpi`; `bash setup.sh --mpi` installs Open MPI): a
//! sweep's variants are dealt to the ranks and gathered on rank 0, with the certificates one
//! process writes, bit for bit; `lagra run` runs the scene on rank 0 alone and says so; bad input
//! is said once and ends the job. Every mpirun is under `timeout`: a hang fails, it does not stall.

mod common;
use common::{lagra, stderr, stdout};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn mpirun(ranks: usize, args: &[&str]) -> Output {
    Command::new("timeout")
        .args(["300", "mpirun", "-np", &ranks.to_string(), "--oversubscribe", env!("CARGO_BIN_EXE_lagra")])
        .args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("mpirun is installed (bash setup.sh --mpi)")
}

fn same_bits(a: &Path, b: &Path, n: usize) {
    for i in 0..n {
        let name = format!("v{i}.cert.json");
        assert!(std::fs::read(a.join(&name)).unwrap() == std::fs::read(b.join(&name)).unwrap(), "{name} differs");
    }
}

fn swept(ranks: usize, k: &str) -> (tempfile::TempDir, Value) {
    let dir = tempfile::tempdir().unwrap();
    let args = ["sweep", "scenes/oscillator.lagra", "--quiet", "--json", "--set", k, "--out"];
    let o = mpirun(ranks, &[&args[..], &[dir.path().to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let v: Value =
        serde_json::from_str(&stdout(&o)).unwrap_or_else(|e| panic!("one JSON document: {e}\n{}", stdout(&o)));
    (dir, v)
}

fn ranks_of(s: &Value) -> Vec<u64> {
    s["variants"].as_array().unwrap().iter().map(|v| v["rank"].as_u64().unwrap()).collect()
}

#[test]
fn two_ranks_share_a_sweep_and_write_what_one_process_writes() {
    let (dir, s) = swept(2, "harmonic.k=1,2,3");
    assert_eq!(s["ranks"], 2);
    assert_eq!(ranks_of(&s), [0, 1, 0]);
    assert_eq!(s["passed"], true);
    let alone = tempfile::tempdir().unwrap();
    let o = lagra(&[
        "sweep",
        "scenes/oscillator.lagra",
        "--quiet",
        "--set",
        "harmonic.k=1,2,3",
        "--out",
        alone.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    same_bits(dir.path(), alone.path(), 3);
}

#[test]
fn four_ranks_oversubscribed_deal_five_variants_in_turn_and_each_rechecks() {
    let (dir, s) = swept(4, "harmonic.k=1,1.5,2,2.5,3");
    assert_eq!(ranks_of(&s), [0, 1, 2, 3, 0]);
    for (i, k) in ["1", "1.5", "2", "2.5", "3"].iter().enumerate() {
        let cert = dir.path().join(format!("v{i}.cert.json"));
        let set = format!("harmonic.k={k}");
        let c = lagra(&["check", cert.to_str().unwrap(), "--scene", "scenes/oscillator.lagra", "--set", &set]);
        assert_eq!(c.status.code(), Some(0), "{}{}", stdout(&c), stderr(&c));
    }
}

#[test]
fn a_run_under_two_ranks_is_rank_zeros_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (two, one) = (dir.path().join("two.json"), dir.path().join("one.json"));
    let o = mpirun(2, &["run", "scenes/oscillator.lagra", "--json", "--certificate", two.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: Value = serde_json::from_str(&stdout(&o)).expect("one report, from rank 0");
    assert_eq!(report["passed"], true);
    assert_eq!(stderr(&o).matches("rank 0 of 2 runs the scene whole").count(), 1, "{}", stderr(&o));
    let alone = lagra(&["run", "scenes/oscillator.lagra", "--certificate", one.to_str().unwrap()]);
    assert_eq!(alone.status.code(), Some(0));
    assert!(std::fs::read(&two).unwrap() == std::fs::read(&one).unwrap());
}

#[test]
fn bad_input_under_mpirun_is_said_once_and_ends_the_job() {
    let o = mpirun(2, &["sweep", "scenes/oscillator.lagra", "--set", "harmonic.q=1,2", "--out", "/nonexistent/never"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("harmonic has no parameter `q`").count(), 1, "{}", stderr(&o));
}
