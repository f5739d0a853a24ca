//! Fluids (SPH) end to end: what `lagra run` says of a fluid's scene.

use crate::common::{lagra, scene, stderr};

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
