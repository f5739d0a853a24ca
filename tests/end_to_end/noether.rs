//! `@expect noether` and the symmetries end to end: every shipped scene passes the claims its
//! symmetries imply, a claim they cannot support is a warning (an error under --strict), and a
//! failure they forbid is blamed on the integrator.

use crate::common::{lagra, run_json, scene, shipped, stderr, stdout};
use serde_json::Value;
use std::path::Path;

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
    let (o, v) = run_json(&[f.to_str().unwrap()]);
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

/// A declared claim the symmetries cannot support is a warning at its `file:line:col`, and an
/// error under --strict; `@expect noether` is checked like any claim.
#[test]
fn a_claim_against_the_symmetries_is_a_warning_or_with_strict_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("oscillator.lagra").replace(
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
            &shipped("oscillator.lagra").replace("  @expect momentum_conservation\n", &format!("  {bad}\n")),
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
    let f = scene(dir.path(), "o.lagra", &shipped("oscillator.lagra").replace("dt: 0.002", "dt: 1.2"));
    let o = lagra(&["run", f.to_str().unwrap(), "--steps", "50"]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("noether     energy_conservation: the scene's symmetries conserve it (Noether), so its failure points at the integrator or a force"), "{out}");
}
