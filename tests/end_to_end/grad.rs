//! End-to-end: `lagra grad` and `lagra fit` through the binary — outputs, spellings, bad input.

use crate::common::{lagra, stderr, stdout};
use serde_json::Value;
use std::path::Path;
use std::process::Output;

fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}{}", stdout(o), stderr(o)))
}

/// The JSON report has the documented fields, the gradient in the order asked, and the check
/// method's two modes agree.
#[test]
fn grad_json_names_every_derivative() {
    let o = lagra(&[
        "grad",
        "scenes/oscillator.lagra",
        "--objective",
        "position[1].x@end",
        "--wrt",
        "harmonic.k,body[0].velocity,body[1].mass",
        "--method",
        "check",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    let names = ["harmonic.k", "body[0].velocity.x", "body[0].velocity.y", "body[0].velocity.z", "body[1].mass"];
    assert_eq!(v["gradient"].as_object().unwrap().len(), names.len(), "{v}");
    // written in the order asked
    let text = stdout(&o);
    let at: Vec<usize> = names.iter().map(|n| text.find(&format!("\"{n}\"")).unwrap()).collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{text}");
    for k in ["objective", "value", "method", "steps", "seconds", "peak_memory_bytes"] {
        assert!(!v[k].is_null(), "{k} missing: {v}");
    }
    assert_eq!((v["method"].as_str(), v["steps"].as_u64()), (Some("reverse+forward"), Some(5000)));
    assert!(v["max_relative_difference"].as_f64().unwrap() < 1e-10, "{v}");
    // the oscillator moves along x only: its y and z derivatives are exactly zero
    assert_eq!(v["gradient"]["body[0].velocity.y"].as_f64(), Some(0.0));
}

/// Gradients go through SPH: the dam break's energy after three steps against its viscosity,
/// both modes agreeing (the central differences are `grad`'s unit tests, on a smaller fluid).
#[test]
fn grad_goes_through_the_dam_breaks_fluid() {
    let args = ["grad", "scenes/dam_break.lagra", "--objective", "energy@end", "--wrt", "sph.alpha", "--steps", "3"];
    let o = lagra(&[&args[..], &["--method", "check", "--json"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert!(v["max_relative_difference"].as_f64().unwrap() < 1e-10, "{v}");
    // the viscosity turns energy into heat as the column starts to fall: more of it, less left
    assert!(v["gradient"]["sph.alpha"].as_f64().unwrap() < 0.0, "{v}");
}

#[test]
fn grad_text_reports_value_method_and_derivatives() {
    let o =
        lagra(&["grad", "scenes/kepler.lagra", "--objective", "energy@end", "--wrt", "gravity.G", "--steps", "2000"]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    assert!(out.contains("objective   energy@end = "), "{out}");
    assert!(out.contains("method      reverse: 2000 steps of velocity_verlet"), "{out}");
    let line = out.lines().find(|l| l.starts_with("∂J/∂gravity.G")).expect(&out);
    let g: f64 = line.split('=').nth(1).unwrap().trim().parse().unwrap();
    // H = T − G m₁m₂/r: along an exact orbit dH/dG is −m₁m₂/r at the start, carried to the end
    assert!(g < 0.0 && g.is_finite(), "{line}");
}

/// Bad input: an unknown parameter or objective names itself, exit 2; an integrator gradients
/// do not go through is refused, exit 1.
#[test]
fn grad_bad_input_names_what_is_wrong() {
    let o = lagra(&["grad", "scenes/oscillator.lagra", "--objective", "energy@end", "--wrt", "spring.k"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stderr(&o).trim(), "lagra: `spring.k`: the scene has no term `spring`; its terms: harmonic");
    let o = lagra(&["grad", "scenes/oscillator.lagra", "--objective", "energy", "--wrt", "harmonic.k"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("objective `energy` needs @end or @sum"), "{}", stderr(&o));
    let o = lagra(&[
        "grad",
        "scenes/charged_particle_in_b_field_boris.lagra",
        "--objective",
        "energy@end",
        "--wrt",
        "magnetic.B",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("gradients go through velocity_verlet steps; this scene's solver is boris"));
    let o = lagra(&[
        "grad",
        "scenes/oscillator.lagra",
        "--objective",
        "energy@end",
        "--wrt",
        "harmonic.k",
        "--set",
        "harmonic.k=abc",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("`harmonic.k=abc`: `abc` is not a number"), "{}", stderr(&o));
}

/// A chaotic run gets a warning with its growth rate, and no NaN or infinity is printed as a
/// number: a gradient that overflows is an error.
#[test]
fn a_chaotic_gradient_is_warned_of() {
    let o = lagra(&[
        "grad",
        "scenes/lj_liquid.lagra",
        "--objective",
        "position[0].x@end",
        "--wrt",
        "lj_shifted.epsilon",
        "--steps",
        "2000",
    ]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    let warning = out.lines().find(|l| l.starts_with("warning")).expect(&out);
    assert!(warning.contains("e-folding rate of") && warning.contains("chaotic"), "{warning}");
    assert!(!out.to_lowercase().contains("nan") && !out.contains("inf"), "{out}");
}

/// The README's demonstration: the oscillator's spring constant and Kepler's G recovered from
/// traces of their motion.
#[test]
fn fit_recovers_a_spring_constant_and_kepler_g() {
    let dir = tempfile::tempdir().unwrap();
    for (scene, set, wrt, want) in [
        ("scenes/oscillator.lagra", "harmonic.k=1.5", "harmonic.k", 2.0),
        ("scenes/kepler.lagra", "gravity.G=0.9", "gravity.G", 1.0),
    ] {
        let trace = dir.path().join("t.jsonl");
        let o = lagra(&["run", scene, "--trace", trace.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
        let o = lagra(&["fit", scene, "--target", trace.to_str().unwrap(), "--wrt", wrt, "--set", set, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v = json(&o);
        let got = v["fitted"][wrt].as_f64().unwrap();
        assert!((got - want).abs() < 1e-8, "{scene}: {got} vs {want}: {v}");
        assert!(v["final_loss"].as_f64().unwrap() < 1e-16 * v["initial_loss"].as_f64().unwrap(), "{v}");
    }
}

#[test]
fn fit_bad_target_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.jsonl");
    std::fs::write(&bad, "{\"step\": 0, \"x\": [[0, 0, 0]]}\n").unwrap();
    let o = lagra(&["fit", "scenes/oscillator.lagra", "--target", bad.to_str().unwrap(), "--wrt", "harmonic.k"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bad.jsonl:1: 1 positions for a scene of 2 bodies"), "{}", stderr(&o));
    let missing = Path::new("no/such/trace.jsonl");
    let o = lagra(&["fit", "scenes/oscillator.lagra", "--target", missing.to_str().unwrap(), "--wrt", "harmonic.k"]);
    assert!(stderr(&o).contains("cannot read the target trace no/such/trace.jsonl"), "{}", stderr(&o));
}
