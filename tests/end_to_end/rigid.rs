//! End-to-end: rigid bodies through the `lagra` binary — the spinning brick's energy (with its
//! rotation) and angular momentum certified, a rotation the checker does not account for caught,
//! and the spins re-checked from the state file (a forged one caught).

use crate::common::{lagra, reseal, scene, stderr, stdout};
use serde_json::Value;

#[test]
fn the_spinning_brick_certifies_its_energy_and_angular_momentum() {
    let o = lagra(&["run", "scenes/spinning_top.lagra", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let lines: Vec<&str> = v["claims"].as_array().unwrap().iter().map(|c| c["line"].as_str().unwrap()).collect();
    assert_eq!(lines.len(), 3);
    assert!(lines.iter().all(|l| l.contains(" PASS ")), "{lines:?}");
    // the energy moves (the splitting's O(dt²) error): the rotation is in it
    let bound = |l: &str| l.split("≤ ").nth(1).unwrap().split(' ').next().unwrap().parse::<f64>().unwrap();
    assert!((1e-8..1e-5).contains(&bound(lines[0])), "{}", lines[0]);
}

/// The brick's only energy is its rotation: with a small step its splitting error is within a
/// tolerance of 1e-6, with eight times the step (64 times the error) it is not, and the checker
/// says so — it measures the rotational energy of the state the kernel produced.
#[test]
fn a_rotation_too_fast_for_its_step_fails_the_energy_claim() {
    let dir = tempfile::tempdir().unwrap();
    let brick = |w: f64, dt: f64| {
        format!(
            "scene b {{ entity {{ shape: box, size: [1, 2, 3], mass: 12, position: [0, 0, 0], angular_velocity: [0.01, {w}, 0.005] }}
               @expect energy_conservation {{ tol: 1e-6, every: 100 }}
               solver {{ dt: {dt}, duration: 15 }} }}"
        )
    };
    let slow = scene(dir.path(), "slow.lagra", &brick(2.0, 0.0005));
    assert_eq!(lagra(&["run", slow.to_str().unwrap()]).status.code(), Some(0));
    let fast = scene(dir.path(), "fast.lagra", &brick(2.0, 0.004));
    let o = lagra(&["run", fast.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(stdout(&o).contains("energy_conservation FAIL"), "{}", stdout(&o));
}

/// The spins are in the state file: the re-check agrees, and a forged π, resealed, is caught
/// (the angular momentum at that state is no longer what it was).
#[test]
fn a_forged_spin_is_caught_by_the_re_check() {
    let dir = tempfile::tempdir().unwrap();
    let (cert, states) = (dir.path().join("c.json"), dir.path().join("s.bin"));
    let (c, s) = (cert.to_str().unwrap(), states.to_str().unwrap());
    let o = lagra(&["run", "scenes/spinning_top.lagra", "--steps", "1000", "--certificate", c, "--states", s]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let honest = lagra(&["check", c, "--states", s]);
    assert!(stdout(&honest).contains("AGREES"), "{}", stdout(&honest));
    // state 500's π₂ (a state a step), a checkpoint: after one body's x, v and q
    let mut b = std::fs::read(&states).unwrap();
    assert_eq!(&b[..16], b"lagra-states/3\0\0");
    let record = 16 + 48 + 64;
    let at = 40 + record * 500 + 16 + 48 + 8 * 5;
    let pi = f64::from_le_bytes(b[at..at + 8].try_into().unwrap());
    assert!((pi - 20.0).abs() < 0.1, "{pi}");
    b[at..at + 8].copy_from_slice(&(pi * (1.0 + 1e-9)).to_le_bytes());
    reseal(&states, &cert, b);
    let forged = lagra(&["check", c, "--states", s]);
    assert_ne!(forged.status.code(), Some(0), "{}", stdout(&forged));
    let said = stdout(&forged) + &stderr(&forged);
    assert!(said.contains("halted at step 500"), "{said}");
}

/// A brick thrown spinning through gravity: the field acts through its centre, so the centre
/// follows the parabola, and the energy (fall, flight and spin) and the horizontal momentum are
/// certified.
#[test]
fn a_brick_thrown_spinning_through_gravity_follows_the_parabola() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        "scene t { entity { shape: box, size: [0.2, 0.1, 0.05], mass: 0.5, position: [0, 0, 0], velocity: [1, 4, 0],
                   orientation: { axis: [1, 1, 0], angle: 0.4 }, angular_velocity: [3, 20, -1] }
                 gravity { g: [0, -9.81, 0] }
                 @expect energy_conservation { tol: 1e-6, every: 10 }
                 @expect momentum_conservation { axes: \"xz\", every: 10 }
                 solver { dt: 0.0005, steps: 1600 } }";
    let file = scene(dir.path(), "t.lagra", text);
    let trace = dir.path().join("t.jsonl");
    let o = lagra(&["run", file.to_str().unwrap(), "--json", "--trace", trace.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(v["claims"].as_array().unwrap().iter().all(|c| c["status"] == "PASS"), "{v}");
    // after t = 0.8: x = 0.8, y = 4·0.8 − ½·9.81·0.8²
    let last: Value = serde_json::from_str(std::fs::read_to_string(&trace).unwrap().lines().last().unwrap()).unwrap();
    let x = &last["x"][0];
    let (px, py) = (x[0].as_f64().unwrap(), x[1].as_f64().unwrap());
    assert!((px - 0.8).abs() < 1e-9 && (py - (3.2 - 0.5 * 9.81 * 0.64)).abs() < 1e-9, "{x}");
}
