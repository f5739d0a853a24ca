//! End-to-end: the `lagra` binary on real scene files, through its exit codes and outputs.

use crate::common::{lagra, run_json, scene, shipped, stderr, stdout};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

#[test]
fn oscillator_passes_and_reports_its_period() {
    let o = lagra(&["run", "scenes/oscillator.lagra"]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    assert!(out.contains("energy_conservation PASS  max|H+Q−H₀|/|H₀| ≤ "), "{out}");
    assert!(
        out.contains("certified (interval) over 5000 checkpoints (tol 1e-05, Q dissipated by HarmonicBond)"),
        "{out}"
    );
    assert!(out.contains("momentum_conservation PASS"), "{out}");
    assert!(out.contains("oscillator_period agrees  measured 3.14"), "{out}");
}

/// Every scene shipped in `scenes/` passes its own claims and predictions, and its certificate
/// re-checks from the states to the same verdicts.
#[test]
fn every_scene_passes_its_own_expects_and_re_checks_to_the_same_verdicts() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut seen = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "lagra") {
            let tmp = tempfile::tempdir().unwrap();
            let (cert, states) = (tmp.path().join("c.json"), tmp.path().join("s.bin"));
            let (c, s) = (cert.to_str().unwrap(), states.to_str().unwrap());
            let o = lagra(&["run", p.to_str().unwrap(), "--certificate", c, "--states", s]);
            assert_eq!(o.status.code(), Some(0), "{}:\n{}{}", p.display(), stdout(&o), stderr(&o));
            // the re-check, without the kernel, reaches the same verdicts
            let re = lagra(&["check", c, "--states", s, "--scene", p.to_str().unwrap()]);
            assert_eq!(re.status.code(), Some(0), "{}", stdout(&re));
            let verdicts = |t: &str| t.lines().filter(|l| l.contains(" PASS  ")).map(String::from).collect::<Vec<_>>();
            assert_eq!(verdicts(&stdout(&re)), verdicts(&stdout(&o)));
            assert!(stdout(&re).contains("AGREES with the certificate"));
            seen += 1;
        }
    }
    assert!(seen >= 3, "only {seen} scenes found");
}

#[test]
fn kepler_passes_every_claim_and_the_third_law() {
    let (o, v) = run_json(&["scenes/kepler.lagra"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(v["passed"], true);
    let claims = v["claims"].as_array().unwrap();
    assert_eq!(claims.len(), 5);
    assert!(claims.iter().all(|c| c["status"] == "PASS"), "{claims:?}");
    let p = &v["predictions"][0];
    assert_eq!(p["name"], "kepler_period");
    assert!(p["rel_diff"].as_f64().unwrap() < 1e-5, "{p}");
}

/// The measured period converges to the closed form at second order in dt.
#[test]
fn oscillator_period_error_is_second_order_in_dt() {
    let dir = tempfile::tempdir().unwrap();
    let diff = |dt: &str, steps: &str| {
        let text = shipped("oscillator.lagra").replace("dt: 0.002", &format!("dt: {dt}, steps: {steps}"));
        let p = scene(dir.path(), &format!("osc{dt}.lagra"), &text);
        let (o, v) = run_json(&[p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{v}");
        v["predictions"][0]["rel_diff"].as_f64().unwrap()
    };
    let (coarse, fine) = (diff("0.002", "5000"), diff("0.001", "10000"));
    assert!(fine < 2e-7, "{fine}");
    assert!((3.5..4.5).contains(&(coarse / fine)), "error ratio {} for dt halved", coarse / fine);
}

/// Thinning checkpoints changes how often the balance is compared, not how well Q is integrated.
#[test]
fn thinned_checkpoints_certify_the_same_energy_balance() {
    let dir = tempfile::tempdir().unwrap();
    let bound = |text: &str, name: &str| {
        let p = scene(dir.path(), name, text);
        let (o, v) = run_json(&[p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{v}");
        let line = v["claims"][1]["line"].as_str().unwrap().to_string();
        let checkpoints = v["claims"][1]["checkpoints"].as_u64().unwrap();
        (v["claims"][1]["bound"].as_f64().unwrap(), checkpoints, line)
    };
    let full = bound(&shipped("oscillator.lagra"), "full.lagra");
    let thin = bound(&shipped("oscillator.lagra").replace("{ tol: 1e-5 }", "{ tol: 1e-5, every: 50 }"), "thin.lagra");
    assert_eq!((full.1, thin.1), (5000, 100));
    assert!(thin.0 <= full.0 && thin.0 > 0.5 * full.0, "{full:?} {thin:?}");
}

#[test]
fn a_time_step_far_too_large_fails_and_names_the_step() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(dir.path(), "big_dt.lagra", &shipped("oscillator.lagra").replace("dt: 0.002", "dt: 0.5"));
    let o = lagra(&["run", p.to_str().unwrap()]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    let line = out.lines().find(|l| l.starts_with("energy_conservation FAIL  at step ")).expect(&out);
    let step: u64 = line["energy_conservation FAIL  at step ".len()..].split(':').next().unwrap().parse().unwrap();
    assert!(out.contains(&format!("halted at step {step}: energy_conservation is certainly violated")), "{out}");
    assert!(line.contains("> tol 1e-05"), "{line}");
}

#[test]
fn bad_input_is_one_located_line_a_caret_and_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("k: 2.0", "k: 2.0 C", "units", "HarmonicBond.k expects M·T⁻² (energy/length²), found Q (charge)"),
        ("[0, 1]", "[0, 7]", "index", "body index 7 is out of range: the scene has 2 entities (0..1)"),
        ("mass: 1.0 }", "mass: 1.0, mass: 2 }", "duplicate", "duplicate field `mass`"),
        (
            "bond harmonic",
            "bond elastic",
            "keyword",
            "unknown bond `elastic`; known: harmonic, morse, fene, angle, dihedral, hbond",
        ),
        ("position: [-1.35", "position: [-1e400", "nonfinite", "non-finite number `-1e400`"),
    ];
    for (from, to, name, message) in cases {
        let text = shipped("oscillator.lagra").replacen(from, to, 1);
        let text =
            if name == "units" { text.replace("scene oscillator {", "scene oscillator {\n  units si") } else { text };
        let p = scene(dir.path(), &format!("{name}.lagra"), &text);
        let o = lagra(&["run", p.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        let head = format!("{}:", p.display());
        assert!(lines[0].starts_with(&head) && lines[0].ends_with(message), "{name}: {err}");
        let col: usize = lines[0][head.len()..].split(':').nth(1).unwrap().parse().unwrap();
        assert_eq!(lines[2].trim_end().chars().count(), col + 2, "{name}: caret under column {col}\n{err}");
        assert!(lines[2].trim_end().ends_with('^') && !err.contains("panicked"), "{err}");
        assert!(stdout(&o).is_empty());
    }
}

#[test]
fn missing_file_and_bad_arguments_exit_2() {
    let o = lagra(&["run", "scenes/no_such_scene.lagra"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("lagra: cannot read scenes/no_such_scene.lagra"), "{}", stderr(&o));
    assert_eq!(lagra(&["run", "scenes/oscillator.lagra", "--steps", "0"]).status.code(), Some(2));
    assert_eq!(lagra(&["run", "scenes/oscillator.lagra", "--steps", "many"]).status.code(), Some(2));
    assert_eq!(lagra(&["fly"]).status.code(), Some(2));
}

#[test]
fn coordinates_that_overflow_halt_the_run_never_pass() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("oscillator.lagra")
        .replace("[-1.35, 0, 0]", "[-1e308, 0, 0]")
        .replace("[ 1.35, 0, 0]", "[1e308, 0, 0]");
    let p = scene(dir.path(), "huge.lagra", &text);
    let o = lagra(&["run", p.to_str().unwrap()]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(!out.contains("PASS"), "{out}");
    // halted with a named cause: the force overflows at the start, or a state turns non-finite
    assert!(out.contains("overflows binary64") || out.contains("non-finite"), "{out}");
}

#[test]
fn certificate_holds_the_model_the_claims_and_every_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let c = dir.path().join("osc.cert.json");
    let o = lagra(&["run", "scenes/oscillator.lagra", "--certificate", c.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0));
    let v: Value = serde_json::from_slice(&std::fs::read(&c).unwrap()).unwrap();
    assert_eq!(v["format"], "lagra-certificate/1");
    assert!(v["source_digest"].as_str().unwrap().starts_with("sha256:"));
    assert!(v["checksum"].as_str().unwrap().starts_with("fnv1a64:"));
    assert_eq!(v["model"]["terms"][0]["kind"], "HarmonicBond");
    assert_eq!(v["model"]["terms"][0]["params"], serde_json::json!([2.0, 2.0, 0.04]));
    let trails = v["trails"].as_array().unwrap();
    assert_eq!(trails.len(), 2);
    for t in trails {
        let marks = t["marks"].as_array().unwrap();
        assert_eq!(marks.len(), 5000);
        assert_eq!(marks[4999][0], 5000);
        // [step, lo, hi, tol, precision]: lo ≤ hi ≤ tol, decided by binary64 intervals
        assert!(marks.iter().all(|m| m[1].as_f64().unwrap() <= m[2].as_f64().unwrap()));
        assert!(marks.iter().all(|m| m[2].as_f64().unwrap() <= m[3].as_f64().unwrap() && m[4] == 53));
    }
    assert!(v["verdicts"][1].as_str().unwrap().starts_with("energy_conservation PASS"));
}

#[test]
fn trace_has_a_line_per_frame_and_is_identical_across_runs() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.jsonl"), dir.path().join("b.jsonl"));
    for t in [&a, &b] {
        let o = lagra(&["run", "scenes/oscillator.lagra", "--steps", "3600", "--trace", t.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    }
    let text = std::fs::read_to_string(&a).unwrap();
    assert_eq!(text, std::fs::read_to_string(&b).unwrap());
    let lines: Vec<Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 301, "frames at steps 0, 12, ..., 3600");
    assert_eq!(lines[300]["step"], 3600);
    assert_eq!(lines[300]["x"].as_array().unwrap().len(), 2);
    assert!(lines.iter().all(|l| l["energy"].as_f64().unwrap().is_finite()));
}

#[test]
fn a_run_too_short_to_measure_the_period_does_not_pass() {
    let o = lagra(&["run", "scenes/oscillator.lagra", "--steps", "120"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains("oscillator_period NOT MEASURED"), "{}", stdout(&o));
}

#[test]
fn json_report_has_the_timing_fields() {
    let (o, v) = run_json(&["scenes/oscillator.lagra", "--steps", "3000"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(v["steps"], 3000);
    for k in ["wall_s", "steps_per_s", "ns_per_atom_step"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
    }
    // inline (two bodies), the checker's time judging is the kernel's time waiting for it
    let (judging, waiting) = (v["checker_s"].as_f64().unwrap(), v["checker_wait_s"].as_f64().unwrap());
    assert!(judging > 0.0 && judging == waiting && waiting < v["wall_s"].as_f64().unwrap());
    // one "claim" key per verdict: a flattened field must not repeat a key
    assert_eq!(stdout(&o).matches("\"claim\"").count(), v["claims"].as_array().unwrap().len());
}

/// Overlapped (32,000 atoms), the checker's CPU time and the kernel's wait are each its own,
/// the wait within the run; the text report gives both, and a scene without claims neither.
#[test]
fn the_checkers_time_is_reported_overlapped() {
    let (o, v) = run_json(&["scenes/bench/lj_32k_checked.lagra", "--steps", "2"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(v["checker"].as_str().unwrap().starts_with("on a second thread"));
    let (judging, waiting) = (v["checker_s"].as_f64().unwrap(), v["checker_wait_s"].as_f64().unwrap());
    assert!(judging > 0.0 && (0.0..v["wall_s"].as_f64().unwrap()).contains(&waiting), "{judging} {waiting}");
    let text = |scene: &str| stdout(&lagra(&["run", scene, "--steps", "1"]));
    assert!(text("scenes/bench/lj_32k_checked.lagra").contains("\nchecker     "));
    assert!(!text("scenes/bench/lj_32k_shifted.lagra").contains("\nchecker     "));
}

/// The kernel's thread's time outside every pass that spreads (Amdahl's serial part) is
/// measured and within the wall; on 32,000 LJ atoms it is a small share of it (the list's
/// cut, a few prefix sums), where a clock that missed the passes would give nearly all of it.
#[test]
fn the_serial_part_of_the_run_is_measured() {
    let (o, v) = run_json(&["scenes/bench/lj_32k.lagra", "--steps", "20", "--threads", "1"]);
    assert_eq!(o.status.code(), Some(0));
    let (wall, serial, waiting) =
        (v["wall_s"].as_f64().unwrap(), v["serial_s"].as_f64().unwrap(), v["checker_wait_s"].as_f64().unwrap());
    assert!(serial > 0.0 && serial + waiting <= wall, "{serial} + {waiting} of {wall}");
    assert!(serial < 0.25 * wall, "{serial} of {wall}");
    let explained = stdout(&lagra(&["run", "scenes/bench/lj_32k.lagra", "--steps", "2", "--explain"]));
    assert!(explained.contains("\nserial      "), "{explained}");
}

/// `--progress always` reports the steps on stderr and changes nothing in the report;
/// `never` (and `auto`, off a terminal) keeps stderr empty; anything else is a usage error.
#[test]
fn progress_goes_to_stderr_and_changes_nothing() {
    let run = |when: &str| lagra(&["run", "scenes/oscillator.lagra", "--steps", "3000", "--progress", when]);
    let (always, never, auto) = (run("always"), run("never"), run("auto"));
    assert_eq!(always.status.code(), Some(0));
    assert!(stderr(&always).starts_with("lagra: step 1/3000 (0%)"), "{}", stderr(&always));
    assert!(stderr(&never).is_empty() && stderr(&auto).is_empty());
    // the same report but for the lines that time the run (the wall clock, the checker's time)
    let timed = |l: &str| l.starts_with("wall") || l.starts_with("checker     ");
    let report = |o: &Output| stdout(o).lines().filter(|l| !timed(l)).collect::<Vec<_>>().join("\n");
    assert_eq!(report(&always), report(&never));
    let bad = run("sometimes");
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("possible values: auto, always, never"), "{}", stderr(&bad));
}

/// The language reference's table of terms is the one `lagra terms` prints from the checker.
#[test]
fn the_language_reference_lists_the_vocabulary_as_it_is() {
    let table = stdout(&lagra(&["terms"]));
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/language.md")).unwrap();
    assert!(doc.contains(&table), "docs/language.md is out of date: paste the output of `lagra terms`");
}

/// On a terminal (a pseudo-terminal from `script`), a run of over two seconds shows a progress
/// bar with the claims' state; `--quiet` shows none, and a pipe never gets one.
#[test]
fn a_long_run_on_a_terminal_shows_a_progress_bar() {
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("no `script` here to make a terminal: skipped");
        return;
    }
    let bin = env!("CARGO_BIN_EXE_lagra");
    let on_terminal = |extra: &str| {
        let cmd = format!("{bin} run scenes/lj_liquid.lagra --steps 40000 {extra}");
        let o = Command::new("script")
            .args(["-qec", &cmd, "/dev/null"])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let shown = on_terminal("");
    assert!(shown.contains("/40000 (") && shown.contains("no claim breached so far"), "{shown}");
    assert!(!on_terminal("--quiet").contains("no claim breached"));
    let piped = lagra(&["run", "scenes/lj_liquid.lagra", "--steps", "40000"]);
    assert!(!stderr(&piped).contains("breached"), "{}", stderr(&piped));
}
