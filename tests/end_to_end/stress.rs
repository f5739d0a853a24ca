//! Stability under stress. Slow: run with `cargo test --release --test end_to_end -- --ignored stress::`.
//! Every case must end in a PASS, a certified FAIL naming its step, or a named error — never a
//! NaN in the output, never a hang, never a panic.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn run(dir: &Path, name: &str, text: &str, extra: &[&str]) -> (i32, Value, String) {
    let p: PathBuf = dir.join(name);
    std::fs::write(&p, text).unwrap();
    let mut args = vec!["run", "--json", p.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = Command::new(env!("CARGO_BIN_EXE_lagra")).args(&args).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{name}: {err}");
    let v: Value = serde_json::from_str(&out).unwrap_or(Value::Null);
    (o.status.code().unwrap_or(-1), v, out + &err)
}

fn never_nan(text: &str) {
    assert!(!text.contains("NaN") && !text.contains("nan,"), "a NaN escaped: {text}");
}

/// A harmonic pair with ω = √(k/μ) = 2 (k = 2, μ = ½), no damping.
fn oscillator(dt: f64, steps: u64, every: u64) -> String {
    format!(
        "scene s {{
  entity {{ position: [-1.35, 0, 0], mass: 1 }}
  entity {{ position: [1.35, 0, 0], mass: 1 }}
  bond harmonic [0, 1] {{ k: 2, r0: 2 }}
  @expect energy_conservation {{ tol: 1e-5, every: {every} }}
  @expect momentum_conservation {{ every: {every} }}
  solver {{ dt: {dt}, steps: {steps} }}
}}"
    )
}

#[test]
#[ignore]
fn ten_million_oscillator_steps_keep_the_energy_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let (code, v, text) = run(dir.path(), "long.lagra", &oscillator(0.002, 10_000_000, 10_000), &[]);
    never_nan(&text);
    assert_eq!(code, 0, "{text}");
    // Verlet's energy error oscillates with amplitude (ωdt)²/8 relative and does not grow
    let bound = v["claims"][0]["bound"].as_f64().unwrap();
    assert!(bound < 2.0 * (2.0f64 * 0.002).powi(2) / 8.0 * 1.5, "bound {bound}");
}

#[test]
#[ignore]
fn kepler_at_eccentricity_0_9_over_ten_thousand_orbits() {
    // a = 1, GM = 1, start at apoapsis r = 1.9 with speed √((1 − e)/(1 + e)) = √(0.1/1.9)
    let v = (0.1f64 / 1.9).sqrt();
    let text = format!(
        "scene k {{
  entity {{ position: [0, 0, 0], mass: 1 }}
  entity {{ position: [1.9, 0, 0], velocity: [0, {v}, 0], mass: 1e-9 }}
  interaction gravity {{ G: 1 }}
  @expect energy_conservation {{ tol: 1e-3, every: 1000 }}
  @expect angular_momentum_conservation {{ every: 1000 }}
  @predict kepler_period {{ tol: 1e-3 }}
  solver {{ dt: 0.0005, steps: {} }}
}}",
        (10_000.0 * std::f64::consts::TAU / 0.0005) as u64
    );
    let dir = tempfile::tempdir().unwrap();
    let (code, v, out) = run(dir.path(), "kepler.lagra", &text, &[]);
    never_nan(&out);
    assert_eq!(code, 0, "{out}");
    assert!(v["predictions"][0]["rel_diff"].as_f64().unwrap() < 1e-3);
}

#[test]
#[ignore]
fn past_the_stability_limit_the_run_fails_clearly() {
    let dir = tempfile::tempdir().unwrap();
    // ωdt from 0.5 to 3: Verlet is stable below 2
    for wdt in [0.5, 1.0, 1.5, 1.9, 2.0, 2.1, 2.5, 3.0] {
        let dt = wdt / 2.0;
        let (code, v, text) = run(dir.path(), "unstable.lagra", &oscillator(dt, 100_000, 1), &[]);
        never_nan(&text);
        assert!(code == 0 || code == 1, "ωdt = {wdt}: {text}");
        if code == 1 {
            let halted = v["halted"].as_str().unwrap_or_default().to_string();
            assert!(halted.starts_with("halted at step") || halted.starts_with("halted:"), "ωdt = {wdt}: {text}");
        }
        if wdt > 2.0 {
            assert_eq!(code, 1, "ωdt = {wdt} must not pass: {text}");
        }
    }
}

#[test]
#[ignore]
fn two_lennard_jones_particles_almost_on_top_of_each_other() {
    let dir = tempfile::tempdir().unwrap();
    for gap in ["1e-3", "1e-9", "1e-30", "1e-200", "0"] {
        let text = format!(
            "scene lj {{
  entity {{ position: [0, 0, 0], mass: 1 }}
  entity {{ position: [{gap}, 0, 0], mass: 1 }}
  interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
  @expect energy_conservation {{ tol: 1e-5 }}
  solver {{ dt: 0.001, steps: 100 }}
}}"
        );
        let (code, _, out) = run(dir.path(), "close.lagra", &text, &[]);
        never_nan(&out);
        assert!(code == 1 || code == 2, "gap {gap}: must FAIL or stop with an error: {out}");
    }
}

#[test]
#[ignore]
fn extreme_magnitudes_in_si_units() {
    let dir = tempfile::tempdir().unwrap();
    for (scale, name) in [(1e-30, "tiny"), (1e30, "huge")] {
        // the oscillator with every quantity's unit scaled: masses and stiffness by `scale`
        let text = format!(
            "scene si {{
  units si
  entity {{ position: [-1.35, 0, 0] m, mass: {scale:e} kg }}
  entity {{ position: [1.35, 0, 0] m, mass: {scale:e} kg }}
  bond harmonic [0, 1] {{ k: {:e} N/m, r0: 2 m }}
  @expect energy_conservation {{ tol: 1e-5 }}
  @expect momentum_conservation
  solver {{ dt: 0.002 s, steps: 5000 }}
}}",
            2.0 * scale
        );
        let (code, _, out) = run(dir.path(), &format!("{name}.lagra"), &text, &[]);
        never_nan(&out);
        assert_eq!(code, 0, "{name}: {out}");
    }
}
