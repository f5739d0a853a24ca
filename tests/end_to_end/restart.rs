//! Restart files: a run cut into segments (`--until`, a signal, a kill after `--restart-every`)
//! and resumed from what each wrote (`--resume`) is the unbroken run to the bit, with its
//! verdicts; the segments' certificates re-check as one run, and a chain with a segment missing,
//! swapped or edited does not; a restart of another scene, truncated or edited, is refused.

use crate::common::{lagra, scene, stderr, stdout};
use lagra_run::restart::Restart;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The restart file's state as bits (every number), and its steps.
fn state_bits(p: &Path) -> (u64, Vec<u64>) {
    let r = Restart::read(p).unwrap_or_else(|e| panic!("{e}"));
    let s = &r.state;
    let numbers = s.x.iter().chain(&s.v).flatten().chain(s.chain.iter().flatten()).chain(s.spin.iter().flatten());
    (s.step, [s.t.to_bits()].into_iter().chain(numbers.map(|x| x.to_bits())).collect())
}

/// What a run's report says of its claims, predictions and observables.
fn judged(o: &Output) -> serde_json::Value {
    let doc: serde_json::Value = serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("{e}: {}", stderr(o)));
    let lines: Vec<_> = doc["claims"].as_array().unwrap().iter().map(|c| c["line"].clone()).collect();
    serde_json::json!([lines, doc["predictions"], doc["observables"]])
}

fn run(scene: &str, args: &[&str]) -> Output {
    let out = lagra(&[&["run", scene, "--quiet", "--json"], args].concat());
    assert!(matches!(out.status.code(), Some(0 | 1)), "{}{}", stdout(&out), stderr(&out));
    out
}

/// The scene run whole to `steps`, and in three segments cut at `cuts`, each resumed from the
/// restart file the one before wrote: the same last state, bit for bit (the restart files are
/// the same bytes), and the same verdicts, predictions and observables.
fn cut_in_three(scene: &str, steps: u64, cuts: [u64; 2]) {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let n = steps.to_string();
    let whole = run(scene, &["--steps", &n, "--restart", &file("whole")]);
    let (k1, k2) = (cuts[0].to_string(), cuts[1].to_string());
    run(scene, &["--steps", &n, "--until", &k1, "--restart", &file("r1")]);
    assert_eq!(state_bits(Path::new(&file("r1"))).0, cuts[0]);
    run(scene, &["--steps", &n, "--resume", &file("r1"), "--until", &k2, "--restart", &file("r2")]);
    let last = run(scene, &["--steps", &n, "--resume", &file("r2"), "--restart", &file("r3")]);
    assert_eq!(state_bits(Path::new(&file("r3"))), state_bits(Path::new(&file("whole"))), "{scene}");
    assert_eq!(std::fs::read(file("r3")).unwrap(), std::fs::read(file("whole")).unwrap(), "{scene}");
    assert_eq!(judged(&last), judged(&whole), "{scene}");
}

#[test]
fn velocity_verlet_with_a_neighbour_list_resumes_to_the_bit() {
    cut_in_three("scenes/lj_liquid.lagra", 300, [77, 190]);
}

#[test]
fn nose_hoover_resumes_to_the_bit() {
    cut_in_three("scenes/lj_nvt.lagra", 300, [50, 201]);
}

/// BAOAB's noise is drawn for (seed, step, body, axis): the step carries it; the observables'
/// and the predictions' samples go with the restart.
#[test]
fn langevin_resumes_to_the_bit() {
    cut_in_three("scenes/validation/lj_t085_rho0001.lagra", 200, [33, 120]);
}

/// Sequential impulses carry their warm starts; AVBD its multipliers and stiffnesses, its
/// joints' as well as its contacts'.
#[test]
fn contact_resumes_to_the_bit() {
    cut_in_three("scenes/hinged_chain.lagra", 600, [201, 402]);
    cut_in_three("scenes/block_stack.lagra", 300, [101, 202]);
    let dir = tempfile::tempdir().unwrap();
    // the pyramid's default is AVBD (its claims are rest and depth): sequential impulses named
    let impulses = dir.path().join("block_stack_impulses.lagra");
    let text = std::fs::read_to_string("scenes/block_stack.lagra").unwrap();
    std::fs::write(&impulses, text.replace("solver { dt", "solver { integrator: \"sequential_impulses\", dt")).unwrap();
    cut_in_three(impulses.to_str().unwrap(), 300, [101, 202]);
}

#[test]
fn boris_and_rigid_bodies_resume_to_the_bit() {
    cut_in_three("scenes/charged_particle_in_b_field_boris.lagra", 1000, [333, 777]);
    cut_in_three("scenes/spinning_top.lagra", 1000, [333, 777]);
}

/// Three segments of lj_nvt with their certificates and state files.
fn segments(dir: &Path) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let f = |name: String| dir.join(name);
    let (certs, states): (Vec<_>, Vec<_>) = (1..=3).map(|k| (f(format!("c{k}.json")), f(format!("s{k}")))).unzip();
    for (k, (until, resume)) in [(Some("100"), None), (Some("200"), Some("r1")), (None, Some("r2"))].iter().enumerate()
    {
        let mut args = vec!["--steps", "300", "--restart"];
        let restart = f(format!("r{}", k + 1));
        args.push(restart.to_str().unwrap());
        args.extend(["--certificate", certs[k].to_str().unwrap(), "--states", states[k].to_str().unwrap()]);
        let resumed = resume.map(|r| f(r.into()));
        if let Some(r) = &resumed {
            args.extend(["--resume", r.to_str().unwrap()]);
        }
        if let Some(u) = until {
            args.extend(["--until", u]);
        }
        run("scenes/lj_nvt.lagra", &args);
    }
    (certs, states)
}

fn check(certs: &[&PathBuf], states: &[&PathBuf]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lagra"));
    c.arg("check").args(certs);
    states.iter().for_each(|s| {
        c.arg("--states").arg(s);
    });
    c.current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

#[test]
fn a_chain_of_certificates_rechecks_as_one_run_and_only_whole_and_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let (c, s) = segments(dir.path());
    let all = check(&[&c[0], &c[1], &c[2]], &[&s[0], &s[1], &s[2]]);
    assert_eq!(all.status.code(), Some(0), "{}{}", stdout(&all), stderr(&all));
    assert!(stdout(&all).contains("3 segments, steps 0..=300") && stdout(&all).contains("AGREES"), "{}", stdout(&all));
    // the marks re-derived from the states are those of the unbroken run's certificate
    let whole = dir.path().join("whole.json");
    run("scenes/lj_nvt.lagra", &["--steps", "300", "--certificate", whole.to_str().unwrap()]);
    let read = |p: &Path| lagra_checker::certificate::Certificate::read(&std::fs::read_to_string(p).unwrap()).unwrap();
    let joined: Vec<Vec<_>> = (0..3)
        .map(|claim| c.iter().flat_map(|p| read(p).trails[claim].marks.clone()).map(|m| m.lo.to_bits()).collect())
        .collect();
    let unbroken: Vec<Vec<_>> =
        read(&whole).trails.iter().map(|t| t.marks.iter().map(|m| m.lo.to_bits()).collect()).collect();
    assert_eq!(joined, unbroken);
    assert_eq!(read(&c[2]).verdicts, read(&whole).verdicts);
    let refused = |o: &Output, says: &str| {
        assert_eq!(o.status.code(), Some(2), "{}{}", stdout(o), stderr(o));
        assert!(stderr(o).contains(says), "{}", stderr(o));
    };
    refused(&check(&[&c[1]], &[]), "it continues a run at step 100");
    refused(&check(&[&c[0], &c[2]], &[]), "certificate 2 does not follow certificate 1");
    refused(&check(&[&c[0], &c[2], &c[1]], &[]), "does not follow");
    refused(&check(&[&c[0], &c[1], &c[2]], &[&s[0], &s[2], &s[1]]), "segment 2: the state file is not the one");
    // a middle segment whose verdicts were edited and resealed: its verdicts are not the run's
    let mut forged = read(&c[1]);
    forged.verdicts[0] = forged.verdicts[0].replace("over 4 checkpoints", "over 5 checkpoints");
    let forged = forged.seal().unwrap();
    std::fs::write(&c[1], forged.to_json()).unwrap();
    let mut last = read(&c[2]);
    last.previous = Some(forged.checksum.clone());
    std::fs::write(&c[2], last.seal().unwrap().to_json()).unwrap();
    let edited = check(&[&c[0], &c[1], &c[2]], &[]);
    assert_eq!(edited.status.code(), Some(1), "{}{}", stdout(&edited), stderr(&edited));
    assert!(stdout(&edited).contains("segment 2, verdict 1: re-derived"), "{}", stdout(&edited));
}

#[test]
fn a_restart_of_another_scene_or_damaged_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("r");
    let rs = r.to_str().unwrap();
    run("scenes/oscillator.lagra", &["--steps", "100", "--until", "50", "--restart", rs]);
    let resume = |scene: &str, file: &str| lagra(&["run", scene, "--resume", file, "--quiet"]);
    let refused = |o: Output, says: &str| {
        assert_eq!(o.status.code(), Some(2), "{}{}", stdout(&o), stderr(&o));
        assert!(stderr(&o).starts_with("lagra: --resume: ") && stderr(&o).contains(says), "{}", stderr(&o));
    };
    refused(resume("scenes/kepler.lagra", rs), "it belongs to another scene (source sha256:");
    let text = std::fs::read_to_string("scenes/oscillator.lagra").unwrap();
    let touched = scene(dir.path(), "o.lagra", &format!("{text}\n// edited\n"));
    refused(resume(touched.to_str().unwrap(), rs), "another scene");
    let bytes = std::fs::read(&r).unwrap();
    let damaged = dir.path().join("d");
    let ds = damaged.to_str().unwrap();
    for (cut, says) in [(10, "not a lagra restart file"), (20, "truncated"), (bytes.len() - 1, "digest")] {
        std::fs::write(&damaged, &bytes[..cut]).unwrap();
        refused(resume("scenes/oscillator.lagra", ds), says);
    }
    // the same source run with another parameter or time step is another run
    for (flag, value) in [("--set", "harmonic.k=2.5"), ("--dt", "0.001")] {
        let o = lagra(&["run", "scenes/oscillator.lagra", "--resume", rs, flag, value, "--quiet"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let says = "lagra: the restart does not fit this scene: it was made with another model, claims, integrator or \
                    time step (--set, --dt)";
        assert!(stderr(&o).starts_with(says), "{}", stderr(&o));
    }
    let mut edited = bytes.clone();
    edited[40] ^= 0x10;
    std::fs::write(&damaged, &edited).unwrap();
    refused(resume("scenes/oscillator.lagra", ds), "its digest does not match its contents");
    // and one that does not go on is not written: a solver that cannot be cut says so
    let descent = scene(
        dir.path(),
        "d.lagra",
        "scene d { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.2, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 2.0, r0: 1.0 } solver { integrator: \"action_descent\", dt: 0.01, steps: 20 } }",
    );
    let out = lagra(&["run", descent.to_str().unwrap(), "--steps", "20", "--until", "10", "--restart", ds, "--quiet"]);
    assert!(
        stderr(&out).contains("no restart file written") && stderr(&out).contains("action descent"),
        "{}",
        stderr(&out)
    );
}

/// The oscillator run whole, to compare a cut run with.
fn whole_oscillator(dir: &Path, steps: &str) -> (u64, Vec<u64>) {
    let whole = dir.join("whole");
    run("scenes/oscillator.lagra", &["--steps", steps, "--restart", whole.to_str().unwrap()]);
    state_bits(&whole)
}

/// SIGTERM stops the run with a restart file written where it stopped; the run resumed from it
/// ends where the unbroken run ends, to the bit.
#[test]
fn sigterm_leaves_a_restart_that_resumes_to_the_unbroken_run() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("r");
    let steps = "2000000";
    let mut child = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["run", "scenes/oscillator.lagra", "--steps", steps, "--progress", "always", "--restart"])
        .arg(&r)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut progress = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    progress.read_line(&mut line).unwrap();
    // SAFETY: kill only sends a signal to the child this test started
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    std::thread::spawn(move || std::io::copy(&mut progress, &mut std::io::sink()));
    assert_eq!(child.wait().unwrap().code(), Some(143));
    let (stopped, _) = state_bits(&r);
    assert!(0 < stopped && stopped < 2_000_000, "stopped at {stopped}");
    let again = dir.path().join("again");
    run(
        "scenes/oscillator.lagra",
        &["--steps", steps, "--resume", r.to_str().unwrap(), "--restart", again.to_str().unwrap()],
    );
    assert_eq!(state_bits(&again), whole_oscillator(dir.path(), steps));
}

/// A run killed outright (SIGKILL: nothing of it runs) leaves the restart file it wrote last
/// (`--restart-every`), whole; resumed from it, the run ends where the unbroken run ends.
#[test]
fn a_killed_run_resumes_from_its_last_periodic_restart() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("r");
    let steps = "2000000";
    let mut child = Command::new(env!("CARGO_BIN_EXE_lagra"))
        .args(["run", "scenes/oscillator.lagra", "--steps", steps, "--quiet", "--restart-every", "200000", "--restart"])
        .arg(&r)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !r.exists() {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let (at, _) = state_bits(&r);
    assert!(at > 0 && at % 200_000 == 0, "the restart is at step {at}");
    let again = dir.path().join("again");
    run(
        "scenes/oscillator.lagra",
        &["--steps", steps, "--resume", r.to_str().unwrap(), "--restart", again.to_str().unwrap()],
    );
    assert_eq!(state_bits(&again), whole_oscillator(dir.path(), steps));
}
