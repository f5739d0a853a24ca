//! Fluids (SPH) end to end: what `lagra run` says of a fluid's scene.

use crate::common::{lagra, scene, stderr, stdout};

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

/// `kernel: cubic_spline` selects the fluid smoothed by the cubic spline end to end: the
/// compiled term, the certificate and its re-check name it; the energy balance, enclosed with
/// the cubic spline's definition, holds along the kernel's run (it would not if the fast force
/// smoothed with another W); Noether's table implies both claims (no warning); and the run
/// differs from Wendland's.
#[test]
fn a_cubic_spline_fluid_slumps_under_its_own_certificate() {
    let dir = tempfile::tempdir().unwrap();
    let block = |kernel: &str| {
        let mut text = String::from("scene slump {\n  units si\n");
        for k in 0..64 {
            let p = [k % 4, (k / 4) % 4, k / 16].map(|c| c as f64 * 0.1);
            text += &format!("  entity {{ mass: 1 kg, position: [{}, {}, {}] m }}\n", p[0], p[1] + 0.05, p[2]);
        }
        text + &format!(
            "  sph {{ {kernel}h: 0.13 m, rest_density: 700 kg/m^3, sound_speed: 10 m/s, alpha: 0.1 }}\n  \
             wall {{ normal: [0, 1, 0], k: 20000 N/m }}\n  gravity {{ g: [0, -9.81, 0] m/s^2 }}\n  \
             @expect energy_conservation {{ tol: 1e-3, every: 50 }}\n  \
             @expect momentum_conservation {{ axes: \"xz\", tol: 1e-9 kg*m/s, every: 50 }}\n  \
             solver {{ dt: 5e-4 s, steps: 400 }}\n}}\n"
        )
    };
    let cubic = scene(dir.path(), "cubic.lagra", &block("kernel: cubic_spline, "));
    let (cert, states) = (dir.path().join("c.json"), dir.path().join("s.bin"));
    let (c, s) = (cert.to_str().unwrap(), states.to_str().unwrap());
    let o = lagra(&["run", cubic.to_str().unwrap(), "--certificate", c, "--states", s, "--strict"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    assert!(stdout(&o).contains("SphCubicSpline ×1 (dissipative)"), "{}", stdout(&o));
    assert!(stdout(&o).contains("energy_conservation PASS"), "{}", stdout(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&cert).unwrap().contains("\"SphCubicSpline\""));
    let re = lagra(&["check", c, "--states", s, "--scene", cubic.to_str().unwrap()]);
    assert_eq!(re.status.code(), Some(0), "{}", stdout(&re));
    assert!(stdout(&re).contains("AGREES with the certificate"), "{}", stdout(&re));
    // the same block smoothed by Wendland's C² runs otherwise: its energy balance's bound differs
    let wendland = scene(dir.path(), "wendland.lagra", &block(""));
    let bound = |p: &std::path::Path| {
        let o = lagra(&["run", p.to_str().unwrap(), "--json"]);
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        report["claims"][0]["bound"].as_f64().unwrap()
    };
    let (a, b) = (bound(&cubic), bound(&wendland));
    assert!(a != b, "{a} vs {b}");
}
