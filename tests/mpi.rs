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

/// 6,912 Lennard-Jones atoms in a periodic box, energy and momentum certified every 20 steps.
fn liquid(dir: &Path) -> std::path::PathBuf {
    common::scene(
        dir,
        "liquid.lagra",
        "scene liquid { entity atom { mass: 1 }
           lattice { type: atom, kind: fcc, density: 0.8442, cells: [12, 12, 12], temperature: 2.5, seed: 5, velocities: uniform }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           @expect energy_conservation { tol: 1e-3, every: 20 }
           @expect momentum_conservation { every: 20 }
           solver { dt: 0.005, steps: 60 } }",
    )
}

#[test]
fn a_liquid_cut_into_domains_on_two_and_four_ranks_is_certified_and_rechecked_from_its_states() {
    let dir = tempfile::tempdir().unwrap();
    let scene = liquid(dir.path());
    for (ranks, grid) in [(2, "2x1x1"), (4, "2x2x1")] {
        let (cert, states) =
            (dir.path().join(format!("{ranks}.cert.json")), dir.path().join(format!("{ranks}.states")));
        let o = mpirun(
            ranks,
            &[
                "run",
                scene.to_str().unwrap(),
                "--json",
                "--explain",
                "--certificate",
                cert.to_str().unwrap(),
                "--states",
                states.to_str().unwrap(),
                "--grid",
                grid,
                "--trace",
                dir.path().join("t.jsonl").to_str().unwrap(),
            ],
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let report: Value = serde_json::from_str(&stdout(&o)).expect("one report, from rank 0");
        assert_eq!(report["passed"], true);
        let plan = report["plan"].to_string();
        assert!(plan.contains(&format!("domains: {} bricks on {ranks} ranks", grid.replace('x', "×"))), "{plan}");
        assert!(!stderr(&o).contains("runs the scene whole"), "{}", stderr(&o));
        // energy and momentum judged from the ranks' parts, none refused
        let parts = report["checker_parts"].as_str().unwrap_or_default();
        assert!(parts.contains("added outward at 4 checkpoint(s)") && !parts.contains("refused"), "{parts}");
        assert!(plan.contains("s enclosing its part of the energy and momentum"), "{plan}");
        let cert_text = std::fs::read_to_string(&cert).unwrap();
        assert!(cert_text.contains(",52]"), "marks from the parts, of precision PARTS");
        // every frame, its energy witness worked out on rank 0 from the gathered state
        let frames = std::fs::read_to_string(dir.path().join("t.jsonl")).unwrap();
        let energies: Vec<f64> =
            frames.lines().map(|l| serde_json::from_str::<Value>(l).unwrap()["energy"].as_f64().unwrap()).collect();
        assert_eq!(energies.len(), 7, "a frame every 10 steps (the default), and the first");
        assert!(energies.iter().all(|e| (e / energies[0] - 1.0).abs() < 1e-3), "{energies:?}");
        // every state within round-off of the one-process run's (the pair forces summed in
        // another order), the first the same
        let alone = dir.path().join("alone.states");
        let o = lagra(&["run", scene.to_str().unwrap(), "--quiet", "--states", alone.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let read = |p: &Path| lagra_checker::states::States::read(std::fs::read(p).unwrap()).unwrap();
        let (shared, one) = (read(&states), read(&alone));
        assert_eq!(shared.count, one.count);
        let off = shared
            .iter()
            .zip(one.iter())
            .flat_map(|(a, b)| {
                let (a, b): (Vec<f64>, Vec<f64>) = (a.x.concat(), b.x.concat());
                a.into_iter().zip(b).map(|(p, q)| (p - q).abs()).collect::<Vec<_>>()
            })
            .fold(0.0, f64::max);
        assert!(off > 0.0 && off < 1e-10, "{ranks} ranks: positions off by {off:e}");
        // re-checked by one process, every state's enclosures evaluated again
        let c = lagra(&[
            "check",
            cert.to_str().unwrap(),
            "--states",
            states.to_str().unwrap(),
            "--scene",
            scene.to_str().unwrap(),
        ]);
        assert_eq!(c.status.code(), Some(0), "{}{}", stdout(&c), stderr(&c));
        assert!(stdout(&c).contains("AGREES"), "{}", stdout(&c));
    }
}

#[test]
fn a_grid_that_does_not_fit_the_job_is_said_once_and_ends_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = liquid(dir.path());
    let o = mpirun(2, &["run", scene.to_str().unwrap(), "--grid", "3x1x1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("--grid 3x1x1 has 3 bricks, but the job has 2 ranks").count(), 1, "{}", stderr(&o));
    let o = lagra(&["run", scene.to_str().unwrap(), "--grid", "2x1x1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("under mpirun"), "{}", stderr(&o));
}

#[test]
fn a_run_stopped_on_two_ranks_resumes_on_four_and_its_segments_recheck_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let scene = liquid(dir.path());
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let s = scene.to_str().unwrap();
    let first =
        mpirun(2, &["run", s, "--quiet", "--until", "30", "--restart", &at("r.bin"), "--certificate", &at("c1.json")]);
    // (stopped at 30: the claim checked at 40 and 60 not yet due)
    assert!(matches!(first.status.code(), Some(0 | 1)), "{}", stderr(&first));
    assert!(!stderr(&first).contains("runs the scene whole"), "{}", stderr(&first));
    let second = mpirun(4, &["run", s, "--json", "--resume", &at("r.bin"), "--certificate", &at("c2.json")]);
    assert_eq!(second.status.code(), Some(0), "{}", stderr(&second));
    let report: Value = serde_json::from_str(&stdout(&second)).unwrap();
    assert_eq!(report["passed"], true);
    assert_eq!(report["steps"], 60);
    let c = lagra(&["check", &at("c1.json"), &at("c2.json"), "--scene", s]);
    assert_eq!(c.status.code(), Some(0), "{}{}", stdout(&c), stderr(&c));
    // and the same restart goes on in one process
    let alone = lagra(&["run", s, "--quiet", "--resume", &at("r.bin")]);
    assert_eq!(alone.status.code(), Some(0), "{}", stderr(&alone));
}

#[test]
fn a_liquid_in_a_nose_hoover_chain_on_two_ranks_is_certified_and_samples_what_one_process_samples() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene(
        dir.path(),
        "nvt.lagra",
        "scene nvt { entity atom { mass: 1 }
           lattice { type: atom, kind: fcc, density: 0.8442, cells: [12, 12, 12], temperature: 2.5, seed: 5, velocities: uniform }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           thermostat nose_hoover { T: 1.0, tau: 0.1 }
           @expect energy_conservation { tol: 5e-3, every: 20 }
           @expect momentum_conservation { every: 20 }
           solver { dt: 0.005, steps: 60 } }",
    );
    let (s, cert, states) = (scene.to_str().unwrap(), dir.path().join("c.json"), dir.path().join("s.states"));
    let args = ["run", s, "--json", "--explain", "--certificate", cert.to_str().unwrap()];
    let o = mpirun(2, &[&args[..], &["--states", states.to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("runs the scene whole"), "{}", stderr(&o));
    let two: Value = serde_json::from_str(&stdout(&o)).expect("one report, from rank 0");
    assert_eq!(two["passed"], true);
    assert!(two["plan"].to_string().contains("domains: "), "{}", two["plan"]);
    let alone = lagra(&["run", s, "--json"]);
    assert_eq!(alone.status.code(), Some(0), "{}", stderr(&alone));
    let one: Value = serde_json::from_str(&stdout(&alone)).unwrap();
    // the chain's kinetic energy summed over the ranks: the samples agree to round-off
    for what in ["kinetic_temperature", "potential_energy_per_body", "pressure"] {
        let [a, b] = [&two, &one].map(|r| r["observables"][what]["mean"].as_f64().unwrap());
        assert!((a - b).abs() < 1e-10 * b.abs(), "{what}: {a} on two ranks, {b} in one process");
    }
    let c = lagra(&["check", cert.to_str().unwrap(), "--states", states.to_str().unwrap(), "--scene", s]);
    assert_eq!(c.status.code(), Some(0), "{}{}", stdout(&c), stderr(&c));
    assert!(stdout(&c).contains("AGREES"), "{}", stdout(&c));
}

/// A rank killed in the middle of a run ends the job: no hang (mpirun's runtime takes the other
/// ranks down), a failing exit, and no certificate or report that says PASS.
#[test]
fn a_rank_killed_mid_run_ends_the_job_without_a_pass() {
    let dir = tempfile::tempdir().unwrap();
    let long = std::fs::read_to_string(liquid(dir.path())).unwrap().replace("steps: 60", "steps: 1000000");
    let scene = common::scene(dir.path(), "long.lagra", &long);
    let cert = dir.path().join("c.json");
    let s = scene.to_str().unwrap();
    let job = Command::new("timeout")
        .args(["300", "mpirun", "-np", "2", "--oversubscribe", env!("CARGO_BIN_EXE_lagra")])
        .args(["run", s, "--json", "--certificate", cert.to_str().unwrap()])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // rank 1, found by the scene it runs and the rank its launcher gave it
    let rank_one = || {
        std::fs::read_dir("/proc").unwrap().flatten().find_map(|p| {
            let cmd = std::fs::read(p.path().join("cmdline")).ok()?;
            let env = std::fs::read(p.path().join("environ")).ok()?;
            let has = |b: &[u8], s: &str| b.windows(s.len()).any(|w| w == s.as_bytes());
            (has(&cmd, s) && !has(&cmd, "mpirun") && has(&env, "OMPI_COMM_WORLD_RANK=1\0"))
                .then(|| p.file_name().to_string_lossy().into_owned())
        })
    };
    let pid = (0..600)
        .find_map(|_| {
            let found = rank_one();
            if found.is_none() {
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            found
        })
        .expect("rank 1 started");
    // let it step a while, then kill it as a node's failure would
    std::thread::sleep(std::time::Duration::from_secs(2));
    assert!(Command::new("kill").args(["-9", &pid]).status().unwrap().success());
    let o = job.wait_with_output().unwrap();
    assert_ne!(o.status.code(), Some(124), "the job hung until the timeout");
    assert!(!o.status.success(), "{}", stderr(&o));
    // the launcher names the rank that died ("process rank 1 ... exited on signal 9")
    assert!(stderr(&o).contains("rank 1"), "{}", stderr(&o));
    assert!(!stdout(&o).contains("\"passed\": true"), "{}", stdout(&o));
    // the certificate is written whole at the end (through a file renamed into place), or not
    assert!(!cert.exists(), "a certificate was written");
}
