//! End-to-end: every solver through the `lagra` binary — past its stability limit, in the
//! report, on any number of threads, and the scenes that show it.

use crate::common::{lagra, run_json, scene, stdout};
use serde_json::Value;

const INTEGRATORS: [&str; 7] =
    ["velocity_verlet", "symplectic_euler", "yoshida4", "rk4", "boris", "rattle", "action_descent"];

/// The harmonic pair of scenes/oscillator.lagra without its damping (ω = 2), with `solver`.
fn oscillator(solver: &str) -> String {
    format!(
        "scene o {{ entity {{ position: [-1.35, 0, 0], mass: 1 }} entity {{ position: [1.35, 0, 0], mass: 1 }}
           bond harmonic [0, 1] {{ k: 2, r0: 2 }}
           @expect energy_conservation {{ tol: 1e-5 }} @expect momentum_conservation
           solver {{ {solver} }} }}"
    )
}

/// Past its stability limit (ω·dt = 2.4) every solver ends in a certified FAIL naming its step;
/// action descent, whose midpoint rule is stable at any dt, cannot converge its window there and
/// halts naming the step. Never a PASS, never a NaN.
#[test]
fn every_solver_past_its_limit_fails_and_names_the_step() {
    let dir = tempfile::tempdir().unwrap();
    for name in INTEGRATORS {
        let p = scene(dir.path(), "o.lagra", &oscillator(&format!("integrator: \"{name}\", dt: 1.2, steps: 200")));
        let o = lagra(&["run", p.to_str().unwrap()]);
        let out = stdout(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {out}");
        assert!(!out.contains("NaN") && !out.contains(" PASS  max|ΔH|"), "{name}: {out}");
        let halt = out.lines().find(|l| l.starts_with("halted at step ")).unwrap_or_else(|| panic!("{name}: {out}"));
        if name == "action_descent" {
            assert!(halt.contains("the action window from step 0"), "{halt}");
        } else {
            let fail = out.lines().find(|l| l.starts_with("energy_conservation FAIL  at step ")).expect(&out);
            let step = fail["energy_conservation FAIL  at step ".len()..].split(':').next().unwrap();
            assert_eq!(halt, format!("halted at step {step}: energy_conservation is certainly violated"), "{name}");
        }
    }
}

/// Within its limit every solver PASSes the energy and momentum claims of the oscillator.
#[test]
fn every_solver_passes_the_oscillator_at_a_small_step() {
    let dir = tempfile::tempdir().unwrap();
    for name in INTEGRATORS {
        let dt = if name == "symplectic_euler" { "0.00002" } else { "0.002" };
        let p = scene(dir.path(), "o.lagra", &oscillator(&format!("integrator: \"{name}\", dt: {dt}, steps: 2000")));
        let o = lagra(&["run", p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stdout(&o));
    }
}

/// The report says how an iterating solver's iterations went; a run halted before its first
/// step has no rate to print.
#[test]
fn the_report_gives_the_iterations_and_no_rate_without_steps() {
    let run = |args: &[&str]| -> Value {
        let o = lagra(&[&["run", "--json"], args].concat());
        serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(&o)))
    };
    let v = run(&["scenes/pendulum_chain_rigid.lagra"]);
    let it = &v["iterations"];
    assert_eq!(it["what"], "SHAKE/RATTLE rounds per step");
    assert_eq!(it["solves"], v["steps"]);
    assert!(it["worst_residual"].as_f64().unwrap() <= it["tol"].as_f64().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let p =
        scene(dir.path(), "ad.lagra", &oscillator("integrator: \"action_descent\", dt: 0.01, window: 10, steps: 50"));
    let v = run(&[p.to_str().unwrap()]);
    let windows = v["iterations"]["windows"].as_array().unwrap();
    assert_eq!(windows.len(), 5);
    assert_eq!((windows[1]["first_step"].as_u64(), v["passed"].as_bool()), (Some(10), Some(true)));
    // halted before the first step: no rate, and the claims saw no checkpoint
    let far = scene(
        dir.path(),
        "far.lagra",
        "scene far { entity { position: [-1e308, 0, 0], mass: 1 } entity { position: [1e308, 0, 0], mass: 1 }
           interaction gravity { G: 1 } @expect energy_conservation { tol: 1e-5 } solver { dt: 0.01, steps: 10 } }",
    );
    let v = run(&[far.to_str().unwrap()]);
    assert_eq!((v["steps_per_s"].clone(), v["ns_per_atom_step"].clone()), (Value::Null, Value::Null));
    assert!(v["halted"].as_str().unwrap().contains("so far apart that their separation overflows binary64"), "{v}");
    let text = stdout(&lagra(&["run", far.to_str().unwrap()]));
    assert!(!text.contains("inf ns") && text.contains("no checkpoint was judged"), "{text}");
}

/// A constrained scene gives the same trajectory on any number of threads.
#[test]
fn rattle_gives_the_same_trajectory_on_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let traces: Vec<Vec<u8>> = ["1", "2"]
        .iter()
        .map(|threads| {
            let trace = dir.path().join(format!("t{threads}.jsonl"));
            let o = lagra(&[
                "run",
                "scenes/pendulum_chain_rigid.lagra",
                "--threads",
                threads,
                "--trace",
                trace.to_str().unwrap(),
            ]);
            assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
            std::fs::read(trace).unwrap()
        })
        .collect();
    assert!(traces[0] == traces[1] && traces[0].len() > 10_000);
}

#[test]
fn run_help_lists_every_integrator() {
    let help = stdout(&lagra(&["run", "--help"]));
    for name in INTEGRATORS {
        assert!(help.contains(name), "{name} missing from:\n{help}");
    }
}

/// A lattice too big for the machine is refused at its line before anything is allocated.
#[test]
fn a_lattice_too_big_for_the_machine_is_an_error_at_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(
        dir.path(),
        "huge.lagra",
        "scene huge { entity atom { mass: 1 }
  lattice { type: atom, density: 0.8442, cells: [1000, 1000, 1000] }
  interaction lj { epsilon: 1, sigma: 1, cutoff: 2.5 }
  solver { dt: 0.005, steps: 10 } }",
    );
    let o = lagra(&["run", p.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("huge.lagra:2:49: a lattice of 4000000000 bodies would need about 10000.0 GB"), "{err}");
}

/// Every integrator runs the Kepler orbit and passes its claims; at the same dt the fourth-order
/// ones measure the period far more accurately than Verlet.
#[test]
fn fourth_order_integrators_beat_verlet_at_equal_dt() {
    let dir = tempfile::tempdir().unwrap();
    let kepler = crate::common::shipped("kepler.lagra");
    let period_error = |integrator: &str| {
        let p = scene(dir.path(), &format!("{integrator}.lagra"), &kepler.replace("velocity_verlet", integrator));
        let (o, v) = run_json(&[p.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{integrator}: {v}");
        v["predictions"][0]["rel_diff"].as_f64().unwrap()
    };
    let verlet = period_error("velocity_verlet");
    for integrator in ["yoshida4", "rk4"] {
        let e = period_error(integrator);
        assert!(e < verlet / 1000.0, "{integrator}: {e} against Verlet's {verlet}");
    }
}
