//! End-to-end: the `lagra` binary on real scene files, through its exit codes and outputs.

mod common;
use common::{lagra, scene, stderr, stdout};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Writes `text` as a scene file in `dir`.
fn oscillator() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/oscillator.lagra")).unwrap()
}

fn json(args: &[&str]) -> (Output, Value) {
    let mut a = vec!["run", "--json"];
    a.extend_from_slice(args);
    let o = lagra(&a);
    let v = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(&o)));
    (o, v)
}

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
    let (o, v) = json(&["scenes/kepler.lagra"]);
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
        let text = oscillator().replace("dt: 0.002", &format!("dt: {dt}, steps: {steps}"));
        let p = scene(dir.path(), &format!("osc{dt}.lagra"), &text);
        let (o, v) = json(&[p.to_str().unwrap()]);
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
        let (o, v) = json(&[p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{v}");
        let line = v["claims"][1]["line"].as_str().unwrap().to_string();
        let checkpoints = v["claims"][1]["checkpoints"].as_u64().unwrap();
        (v["claims"][1]["bound"].as_f64().unwrap(), checkpoints, line)
    };
    let full = bound(&oscillator(), "full.lagra");
    let thin = bound(&oscillator().replace("{ tol: 1e-5 }", "{ tol: 1e-5, every: 50 }"), "thin.lagra");
    assert_eq!((full.1, thin.1), (5000, 100));
    assert!(thin.0 <= full.0 && thin.0 > 0.5 * full.0, "{full:?} {thin:?}");
}

#[test]
fn a_time_step_far_too_large_fails_and_names_the_step() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(dir.path(), "big_dt.lagra", &oscillator().replace("dt: 0.002", "dt: 0.5"));
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
        let text = oscillator().replacen(from, to, 1);
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
    let text = oscillator().replace("[-1.35, 0, 0]", "[-1e308, 0, 0]").replace("[ 1.35, 0, 0]", "[1e308, 0, 0]");
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
    let (o, v) = json(&["scenes/oscillator.lagra", "--steps", "3000"]);
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
    let (o, v) = json(&["scenes/bench/lj_32k_checked.lagra", "--steps", "2"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(v["checker"].as_str().unwrap().starts_with("on a second thread"));
    let (judging, waiting) = (v["checker_s"].as_f64().unwrap(), v["checker_wait_s"].as_f64().unwrap());
    assert!(judging > 0.0 && (0.0..v["wall_s"].as_f64().unwrap()).contains(&waiting), "{judging} {waiting}");
    let text = |scene: &str| stdout(&lagra(&["run", scene, "--steps", "1"]));
    assert!(text("scenes/bench/lj_32k_checked.lagra").contains("\nchecker     "));
    assert!(!text("scenes/bench/lj_32k_shifted.lagra").contains("\nchecker     "));
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

/// Every integrator runs the Kepler orbit and passes its claims; at the same dt the fourth-order
/// ones measure the period far more accurately than Verlet.
#[test]
fn fourth_order_integrators_beat_verlet_at_equal_dt() {
    let dir = tempfile::tempdir().unwrap();
    let kepler = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kepler.lagra")).unwrap();
    let period_error = |integrator: &str| {
        let p = scene(dir.path(), &format!("{integrator}.lagra"), &kepler.replace("velocity_verlet", integrator));
        let (o, v) = json(&[p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{integrator}: {v}");
        v["predictions"][0]["rel_diff"].as_f64().unwrap()
    };
    let verlet = period_error("velocity_verlet");
    for integrator in ["yoshida4", "rk4"] {
        let e = period_error(integrator);
        assert!(e < verlet / 1000.0, "{integrator}: {e} against Verlet's {verlet}");
    }
}

/// `--threads` changes nothing but the speed: the trace is the same bytes, and `--explain`
/// names the plan the planner chose.
#[test]
fn threads_give_the_same_trajectory_and_explain_shows_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(
        dir.path(),
        "melt.lagra",
        "scene melt { entity atom { mass: 1 }
           lattice { type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 1.44, seed: 3 }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           @expect momentum_conservation { every: 5 }
           solver { dt: 0.005, steps: 10, steps_per_frame: 5 } }",
    );
    let scene = scene.to_str().unwrap();
    let mut traces = vec![];
    for threads in ["1", "2"] {
        let trace = dir.path().join(format!("t{threads}.jsonl"));
        let o = lagra(&["run", scene, "--threads", threads, "--explain", "--trace", trace.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
        assert!(stdout(&o).contains("plan        LennardJonesShifted: cluster-pair list"), "{}", stdout(&o));
        assert!(stdout(&o).contains("piece(s) by size"), "{}", stdout(&o));
        // where the time went: four parts of the pair term's, together within the wall time
        let out = stdout(&o);
        let seconds = |after: &str| -> f64 {
            let at = out.find(after).unwrap_or_else(|| panic!("no `{after}` in {out}")) + after.len();
            out[at..].split(' ').next().unwrap().parse().unwrap()
        };
        let parts: Vec<f64> = ["time: builds ", "updates ", "pieces ", "sums "].iter().map(|p| seconds(p)).collect();
        assert!(parts[0] > 0.0 && parts[2] > 0.0, "{parts:?}");
        assert!(parts.iter().sum::<f64>() <= seconds("wall        ") + 0.002, "{parts:?}\n{out}");
        traces.push(std::fs::read(trace).unwrap());
    }
    assert!(traces[0].len() > 100_000);
    assert!(traces[0] == traces[1], "the trajectories differ between 1 and 2 threads");
    let o = lagra(&["run", scene, "--threads", "0"]);
    assert_eq!((o.status.code(), stderr(&o).trim()), (Some(2), "lagra: --threads must be at least 1"));
}

/// The work-precision study writes its CSV, plot and table, and even its two-step smoke run
/// shows the oscillator's orders: 2 for velocity Verlet, 4 for Yoshida.
#[test]
fn bench_precision_writes_csv_plot_and_orders() {
    let dir = tempfile::tempdir().unwrap();
    let o = lagra(&["bench", "precision", "--quick", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let csv = std::fs::read_to_string(dir.path().join("precision.csv")).unwrap();
    // five integrators on four conservative problems, four on the cyclotron, RATTLE on the rotor
    assert_eq!(csv.lines().count(), 1 + (5 * 4 + 4 + 1) * 2, "{csv}");
    let svg = std::fs::read_to_string(dir.path().join("precision.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("yoshida4") && svg.contains("boris"));
    let table = std::fs::read_to_string(dir.path().join("precision.md")).unwrap();
    let header: Vec<String> = table.lines().next().unwrap().split('|').map(|c| c.trim().to_string()).collect();
    let order = |problem: &str, integrator: &str| -> f64 {
        let row = table.lines().find(|l| l.starts_with(&format!("| {problem} "))).expect(problem);
        let column = header.iter().position(|h| h == integrator).expect(integrator);
        row.split('|').nth(column).unwrap().trim().parse().unwrap_or(f64::NAN)
    };
    for (integrator, p) in [("velocity_verlet", 2.0), ("yoshida4", 4.0), ("action_descent", 2.0)] {
        let measured = order("oscillator", integrator);
        assert!((measured - p).abs() < 0.3, "{integrator}: {measured}\n{table}");
    }
    // first order, still short of its asymptote at the smoke run's two large steps (1.38)
    assert!((0.8..1.6).contains(&order("oscillator", "symplectic_euler")), "{table}");
    assert!((order("cyclotron", "boris") - 2.0).abs() < 0.3, "{table}");
    assert!((order("rigid_rotor", "rattle") - 2.0).abs() < 0.3, "{table}");
}

#[test]
fn bench_overhead_reports_a_ratio() {
    let o = lagra(&["bench", "overhead", "--steps", "2000", "--repeats", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["ratio"].as_f64().unwrap() > 0.0);
    assert!(v["final_position_difference"].as_f64().unwrap() < 1e-9, "the engine and the hand loop agree");
}

/// On the 32,000-atom benchmark the compensated sums are the exact sums of the same terms to
/// within an ulp, and the plain sums are not: at step 0 plain summation's momentum error
/// exceeds the momentum's true change over a step (round-off that would look like drift).
#[test]
fn bench_summation_shows_what_compensation_buys() {
    let o = lagra(&["bench", "summation", "--steps", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let get = |at: &str, w: &str, how: &str| v[at][w][how].as_f64().unwrap();
    assert!(v["start"]["terms"].as_u64().unwrap() > 800_000);
    for at in ["start", "end"] {
        for w in ["energy", "momentum_x"] {
            let exact = get(at, w, "exact");
            let ulp = f64::EPSILON * exact.abs();
            assert!((get(at, w, "compensated") - exact).abs() <= ulp, "{at} {w}");
        }
    }
    let plain_error = (get("start", "energy", "plain") - get("start", "energy", "exact")).abs();
    assert!(plain_error > 1e-12 * get("start", "energy", "exact").abs(), "plain summation loses bits here");
    let true_change = (get("end", "momentum_x", "exact") - get("start", "momentum_x", "exact")).abs();
    assert!((get("start", "momentum_x", "plain") - get("start", "momentum_x", "exact")).abs() > true_change);
}

/// The Lean definitions and invariance theorems in lean/Lagra are what the checker's term
/// definitions print today (lean/check.sh then has Lean check them).
#[test]
fn lean_definitions_are_current() {
    let dir = tempfile::tempdir().unwrap();
    let o = lagra(&["lean", "--definitions", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for f in ["Terms.lean", "Invariance.lean"] {
        let fresh = std::fs::read_to_string(dir.path().join(f)).unwrap();
        let shipped =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("lean/Lagra").join(f)).unwrap();
        assert!(fresh == shipped, "lean/Lagra/{f} is stale: run `lagra lean --definitions lean/Lagra`");
    }
}

/// `lagra lean CERT` writes one theorem per certified claim, with the checkpoints' binary64
/// values as exact rationals, the same bytes every time; a damaged certificate is refused.
#[test]
fn lean_obligations_are_exact_and_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("o.cert");
    let o = lagra(&["run", "scenes/oscillator.lagra", "--steps", "3000", "--certificate", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let a = lagra(&["lean", cert.to_str().unwrap()]);
    let b = lagra(&["lean", cert.to_str().unwrap()]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    assert!(a.stdout == b.stdout);
    let lean = stdout(&a);
    for t in [
        "theorem energy_conservation_holds",
        "theorem momentum_conservation_holds",
        "by decide +kernel",
        "Mark.flatten_ok",
    ] {
        assert!(lean.contains(t), "{t}");
    }
    // tol 1e-5 is the dyadic 5902958103587057 · 2^-69, written exactly
    assert!(lean.contains(", 5902958103587057, -69⟩"), "{lean}");
    let text = std::fs::read_to_string(&cert).unwrap();
    std::fs::write(&cert, &text[..text.len() / 2]).unwrap();
    let o = lagra(&["lean", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
}

/// Every shipped scene, with `@expect noether` added, PASSes the conservation claims its
/// symmetries imply (a shortened run), and its certificate re-checks against the scene, whose
/// `@expect noether` the re-check expands to the same claims.
#[test]
fn every_scene_passes_the_claims_noether_derives() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let tmp = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_none_or(|e| e != "lagra") {
            continue;
        }
        // the predictions need whole runs; the claims are the point here
        let text: String = std::fs::read_to_string(&p)
            .unwrap()
            .replacen("\n  solver", "\n  @expect noether\n  solver", 1)
            .lines()
            .filter(|l| !l.contains("@predict"))
            .map(|l| format!("{l}\n"))
            .collect();
        let file = scene(tmp.path(), p.file_name().unwrap().to_str().unwrap(), &text);
        let cert = tmp.path().join("c.json");
        let o = lagra(&["run", file.to_str().unwrap(), "--steps", "400", "--certificate", cert.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}:\n{}{}", p.display(), stdout(&o), stderr(&o));
        let re = lagra(&["check", cert.to_str().unwrap(), "--scene", file.to_str().unwrap()]);
        assert_eq!(re.status.code(), Some(0), "{}: {}{}", p.display(), stdout(&re), stderr(&re));
    }
}

/// What `@expect noether` adds to a scene with a floor and gravity: the energy balance and the
/// one momentum both leave alone, nothing the floor breaks.
#[test]
fn noether_claims_follow_the_symmetries() {
    let dir = tempfile::tempdir().unwrap();
    let f = scene(
        dir.path(),
        "drop.lagra",
        "scene drop {
  entity { position: [0, 1, 0], velocity: [0.3, 0, 0], mass: 1 }
  entity { position: [1, 1.2, 0], velocity: [0.3, 0, 0], mass: 1 }
  bond harmonic [0, 1] { k: 50, r0: 1 }
  gravity { g: [0, -9.8, 0] }
  floor { k: 10000, damping: 5 }
  @expect noether { tol: 1e-3 }
  solver { dt: 0.0005, steps: 2000 }
}",
    );
    let (o, v) = json(&[f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let labels: Vec<&str> = v["claims"].as_array().unwrap().iter().map(|c| c["line"].as_str().unwrap()).collect();
    assert_eq!(v["generated"], 3, "{labels:?}");
    assert!(
        labels[0].starts_with("energy_conservation PASS") && labels[0].contains("Q dissipated by ContactFloor"),
        "{labels:?}"
    );
    // the floor is frictionless: x and z survive its damping (along y) but not gravity's pull
    assert!(labels[1].starts_with("momentum_conservation(x, z) PASS"), "{labels:?}");
    // gravity and the floor's normal are both along y: rotations about y leave both alone
    assert!(labels[2].starts_with("angular_momentum_conservation(y) PASS"), "{labels:?}");
    let n = lagra(&["noether", f.to_str().unwrap()]);
    let out = stdout(&n);
    assert!(out.contains("momentum_y           broken by UniformAcceleration, ContactFloor"), "{out}");
    assert!(out.contains("angular_momentum_y   conserved"), "{out}");
    assert!(out.contains("energy               a balance H + Q = H₀: dissipated by ContactFloor"), "{out}");
    let j: Value = serde_json::from_slice(&lagra(&["noether", "--json", f.to_str().unwrap()]).stdout).unwrap();
    assert_eq!(j["laws"][1]["by"], serde_json::json!(["UniformAcceleration", "ContactFloor"]));
}

/// A fluid whose kernel's support holds a few particles is a warning at its `sph`, and an error
/// under --strict; one that holds dozens is not.
#[test]
fn a_fluid_too_sparse_for_its_kernel_is_a_warning_or_with_strict_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let fluid = |h: f64| {
        let mut text = String::from("scene s {\n");
        for k in 0..64 {
            let p = [k % 4, (k / 4) % 4, k / 16].map(|c| c as f64 * 0.1);
            text += &format!("  entity {{ mass: 0.001, position: [{}, {}, {}] }}\n", p[0], p[1], p[2]);
        }
        text + &format!(
            "  sph {{ h: {h}, rest_density: 1000, sound_speed: 10 }}\n  solver {{ dt: 1e-4, steps: 10 }}\n}}\n"
        )
    };
    let sparse = scene(dir.path(), "sparse.lagra", &fluid(0.06));
    let o = lagra(&["run", sparse.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "a warning does not stop the run: {}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("sparse.lagra:66:3: warning: the median particle has 5 neighbours within the kernel's support (2h = 0.12), fewest 3"), "{err}");
    let s = lagra(&["run", sparse.to_str().unwrap(), "--strict"]);
    assert_eq!(s.status.code(), Some(2), "{}", stderr(&s));
    assert!(stderr(&s).contains("--strict: the warnings above are errors"), "{}", stderr(&s));
    let dense = scene(dir.path(), "dense.lagra", &fluid(0.15));
    let d = lagra(&["run", dense.to_str().unwrap(), "--strict"]);
    assert_eq!(d.status.code(), Some(0), "{}", stderr(&d));
    assert!(!stderr(&d).contains("warning"), "{}", stderr(&d));
}

/// A declared claim the symmetries cannot support is a warning at its `file:line:col`, and an
/// error under --strict; `@expect noether` is checked like any claim.
#[test]
fn a_claim_against_the_symmetries_is_a_warning_or_with_strict_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = oscillator().replace(
        "  @expect momentum_conservation\n",
        "  gravity { g: [0, -1, 0] }\n  @expect momentum_conservation { axes: \"xy\" }\n",
    );
    let text: String = text.lines().filter(|l| !l.contains("@predict")).map(|l| format!("{l}\n")).collect();
    let f = scene(dir.path(), "o.lagra", &text);
    let o = lagra(&["run", f.to_str().unwrap(), "--steps", "100"]);
    let err = stderr(&o);
    assert!(err.contains("o.lagra:9:11: warning: momentum_conservation(x, y) is not implied by the scene's symmetries: momentum_y: broken by UniformAcceleration"), "{err}");
    assert_eq!(o.status.code(), Some(1), "the claim is judged, and fails: {}", stdout(&o));
    let s = lagra(&["run", f.to_str().unwrap(), "--strict"]);
    assert_eq!(s.status.code(), Some(2), "{}", stderr(&s));
    for (bad, msg) in [
        ("@expect noether @expect noether", "noether is declared twice"),
        ("@expect noether { tol: -1 }", "noether.tol"),
        ("@expect noether { axes: \"x\" }", "axes"),
    ] {
        let f = scene(
            dir.path(),
            "b.lagra",
            &oscillator().replace("  @expect momentum_conservation\n", &format!("  {bad}\n")),
        );
        let o = lagra(&["run", f.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stdout(&o));
        assert!(stderr(&o).contains("b.lagra:") && stderr(&o).contains(msg), "{bad}: {}", stderr(&o));
    }
}

/// A claim the symmetries support that FAILs points at the integrator: the report says so.
#[test]
fn a_failure_the_symmetries_forbid_is_blamed_on_the_integrator() {
    let dir = tempfile::tempdir().unwrap();
    // ωdt = 2.4, past velocity Verlet's stability limit
    let f = scene(dir.path(), "o.lagra", &oscillator().replace("dt: 0.002", "dt: 1.2"));
    let o = lagra(&["run", f.to_str().unwrap(), "--steps", "50"]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("noether     energy_conservation: the scene's symmetries conserve it (Noether), so its failure points at the integrator or a force"), "{out}");
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
