//! End-to-end: contacts through the `lagra` binary — the brick pyramid comes to rest and stays
//! up with `resting` and `no_penetration` certified and re-checked, a forged overlap is caught,
//! colliding solids keep both momenta to round-off, Coulomb friction stops a slide where it
//! should, and bad contact scenes are refused at their line.

use crate::common::{lagra, reseal, scene, stderr, stdout};

#[test]
fn the_pyramid_comes_to_rest_and_the_re_check_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let (cert, states) = (dir.path().join("c.json"), dir.path().join("s.bin"));
    let (c, s) = (cert.to_str().unwrap(), states.to_str().unwrap());
    let o = lagra(&["run", "scenes/block_stack.lagra", "--certificate", c, "--states", s]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    assert!(stdout(&o).contains("resting PASS") && stdout(&o).contains("no_penetration PASS"), "{}", stdout(&o));
    let honest = lagra(&["check", c, "--states", s]);
    assert!(stdout(&honest).contains("AGREES"), "{}", stdout(&honest));
    // push the top brick 0.1 down into the two below it, at a state the checker judges
    let mut b = std::fs::read(&states).unwrap();
    let (bodies, record) = (15, 16 + 48 * 15 + 64 * 15);
    let count = (b.len() - 40 - 8) / record;
    let last = 40 + record * (count - 1);
    let step = u64::from_le_bytes(b[last..last + 8].try_into().unwrap());
    // a record: step, t, every position, every velocity, every spin
    let y = last + 16 + 24 * (bodies - 1) + 8;
    let top = f64::from_le_bytes(b[y..y + 8].try_into().unwrap());
    assert!((top - 2.25).abs() < 0.01, "{top}");
    b[y..y + 8].copy_from_slice(&(top - 0.1).to_le_bytes());
    reseal(&states, &cert, b);
    let forged = lagra(&["check", c, "--states", s]);
    let said = stdout(&forged) + &stderr(&forged);
    assert_ne!(forged.status.code(), Some(0), "{said}");
    assert!(said.contains(&format!("no_penetration FAIL  at step {step}")) && said.contains("DISAGREES"), "{said}");
}

/// Contacts between solids push equally and oppositely at one point: a box, a brick and a ball
/// colliding in free space keep their momentum and angular momentum to the checker's round-off
/// budget (the claims Noether's theorem gives the scene), while the energy is not claimed
/// (the contacts are inelastic).
#[test]
fn colliding_solids_keep_both_momenta() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(
        dir.path(),
        "collide.lagra",
        "scene collide {
           entity { shape: box, size: [1, 1, 1], mass: 1, position: [-1, 0, 0], velocity: [1, 0.1, 0], angular_velocity: [0, 0.5, 1] }
           entity { shape: box, size: [1, 2, 0.5], mass: 2, position: [1, 0.3, 0.2], velocity: [-1, 0, 0.05], orientation: { axis: [1, 1, 0], angle: 0.4 } }
           entity { shape: sphere, size: 0.4, mass: 0.5, position: [0, 2, 0], velocity: [0, -1, 0] }
           @expect noether { every: 10 }
           solver { dt: 0.002, duration: 3 }
         }",
    );
    let o = lagra(&["run", p.to_str().unwrap()]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    assert!(out.contains("momentum_conservation PASS") && out.contains("angular_momentum_conservation PASS"), "{out}");
    assert!(!out.contains("energy_conservation"), "{out}");
    // they did collide: the solver pushed
    let residual = out.split("worst final residual ").nth(1).unwrap();
    assert!(!residual.starts_with('0'), "{out}");
}

/// A box sliding on a floor with μ = 0.5 from 2 m/s stops after v²/(2μg) = 0.4077 m (Coulomb),
/// and without friction it slides on at 2 m/s: under either contact solver.
#[test]
fn friction_stops_a_slide_where_coulomb_says() {
    let dir = tempfile::tempdir().unwrap();
    let slide = |mu: f64, integrator: &str| {
        let p = scene(
            dir.path(),
            "slide.lagra",
            &format!(
                "scene slide {{
                   entity {{ shape: box, size: [1, 1, 1], mass: 2, position: [0, 0.5, 0], velocity: [2, 0, 0] }}
                   gravity {{ g: [0, -9.81, 0] }}
                   floor {{ y: 0, friction: {mu} }}
                   @expect no_penetration {{ tol: 1e-4 }}
                   solver {{ integrator: \"{integrator}\", dt: 0.001, duration: 1, steps_per_frame: 1000 }}
                 }}"
            ),
        );
        let trace = dir.path().join("t.jsonl");
        let o = lagra(&["run", p.to_str().unwrap(), "--trace", trace.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
        let last: serde_json::Value =
            serde_json::from_str(std::fs::read_to_string(&trace).unwrap().lines().last().unwrap()).unwrap();
        (last["x"][0][0].as_f64().unwrap(), last["v"][0][0].as_f64().unwrap())
    };
    for integrator in ["sequential_impulses", "avbd"] {
        let (x, v) = slide(0.5, integrator);
        let expected = 4.0 / (2.0 * 0.5 * 9.81);
        assert!(
            (x - expected).abs() < 0.01 * expected && v.abs() < 1e-6,
            "{integrator}: stopped at {x} (Coulomb: {expected}), v {v}"
        );
        let (x, v) = slide(0.0, integrator);
        assert!((v - 2.0).abs() < 1e-9 && (x - 2.0).abs() < 1e-6, "{integrator}: {x} {v}");
    }
}

/// Bad contact scenes: each refused with its line and column and a message that says why.
#[test]
fn bad_contact_scenes_are_refused_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let cube = |y: f64| format!("entity {{ shape: box, size: [1, 1, 1], mass: 1, position: [0, {y}, 0] }}");
    let cases = [
        (format!("{}\n{}\nfloor {{ y: 0 }}", cube(0.5), cube(1.2)), "3:", "start interpenetrated"),
        (format!("{}\nfloor {{ y: 0 }}", cube(0.3)), "2:", "below the floor"),
        (format!("{}\nfloor {{ y: 0, damping: 2 }}", cube(0.5)), "3:15", "belongs to a penalty floor"),
        (
            format!(
                "{}\n{}\nfloor {{ y: 0 }}\nsolver {{ integrator: \"velocity_verlet\", dt: 0.01 }}",
                cube(0.5),
                cube(1.5)
            ),
            "5:",
            "use `sequential_impulses`",
        ),
        (format!("{}\n@expect resting {{ tol: 1 }}", cube(0.5)), "3:", "needs a tolerance"),
        (format!("{}\n@expect resting {{ max_speed: 1 m }}", cube(0.5)), "3:", "velocity"),
        (format!("{}\n@expect resting {{ max_speed: 1, after: 50 }}", cube(0.5)), "3:", "past the end of the run"),
        (format!("{}\n@expect no_penetration {{ tol: 0.1 }}", cube(0.5)), "3:", "no floor and fewer than two solids"),
        (
            format!("entity {{ shape: box, size: [1, 1, 1], mass: 1, position: [0, 1, 0], friction: -1 }}"),
            "2:",
            "friction must be ≥ 0",
        ),
    ];
    for (body, at, says) in cases {
        let text = format!("scene bad {{\n{body}\nsolver {{ dt: 0.01, duration: 1 }}\n}}");
        // the solver line is the scene's own when the case gives none
        let text =
            if body.contains("solver {") { text.replacen("solver { dt: 0.01, duration: 1 }\n", "", 1) } else { text };
        let p = scene(dir.path(), "bad.lagra", &text);
        let o = lagra(&["run", p.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{text}\n{err}");
        assert!(err.contains(&format!("bad.lagra:{at}")) && err.contains(says), "{text}\n{err}");
    }
}

/// The hinged chain at AVBD's default 10 sweeps: unfinished sweeps cost energy (2.5e-2 of H₀
/// over 2 s, measured) but must not run away; with joints' λ carried whole from step to step
/// |ΔH| had reached 14 × H₀ within 0.44 s. The hinges stay shut to 1e-3 throughout.
#[test]
fn a_hinged_chain_at_ten_sweeps_keeps_its_energy_within_five_percent() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("scenes/hinged_chain.lagra").unwrap();
    let few = text
        .replace("iterations: 40, ", "")
        .replace("energy_conservation { tol: 5e-3", "energy_conservation { tol: 0.05");
    assert_ne!(few, text);
    let file = scene(dir.path(), "few_sweeps.lagra", &few);
    let o = lagra(&["run", file.to_str().unwrap(), "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let claims = report["claims"].as_array().unwrap();
    assert_eq!(claims.len(), 4, "{claims:?}");
    assert!(claims.iter().all(|c| c["status"] == "PASS"), "{claims:?}");
}

/// `--explain` says how AVBD spread its sweeps over the threads: island by island where the
/// bodies fall into islands enough to share out (two towers apart), the whole with each colour
/// spread where one island holds them all (the pyramid), island by island on one thread.
#[test]
fn explain_says_how_avbd_shared_out_its_islands() {
    let dir = tempfile::tempdir().unwrap();
    let boxes: String = (0..4)
        .map(|n| {
            let (x, y) = ((n % 2) as f64 * 3.0, (n / 2) as f64 * 1.001 + 0.5005);
            format!("entity {{ shape: box, size: [1, 1, 1], mass: 1, position: [{x}, {y}, 0] }}\n")
        })
        .collect();
    let towers = scene(
        dir.path(),
        "towers.lagra",
        &format!(
            "scene towers {{ {boxes} gravity {{ g: [0, -9.81, 0] }} floor {{ y: 0, friction: 0.6 }} \
             solver {{ integrator: \"avbd\", dt: 0.005, duration: 0.05 }} }}"
        ),
    );
    let pyramid = std::fs::read_to_string("scenes/block_stack.lagra")
        .unwrap()
        .replace("solver {", "solver { integrator: \"avbd\",");
    let pyramid = scene(dir.path(), "pyramid.lagra", &pyramid);
    let plan = |file: &std::path::Path, threads: &str| {
        let o = lagra(&["run", file.to_str().unwrap(), "--threads", threads, "--steps", "10", "--explain"]);
        let line = stdout(&o).lines().find(|l| l.starts_with("plan        solver: ")).map(str::to_string);
        line.unwrap_or_else(|| panic!("no solver plan: {}{}", stdout(&o), stderr(&o)))
    };
    let apart = plan(&towers, "2");
    assert!(apart.ends_with("island by island, a task each on the pool in 10 step(s); the last step 2 island(s), the largest of 2 bodies"), "{apart}");
    let alone = plan(&towers, "1");
    assert!(
        alone.ends_with(
            "island by island on one thread in 10 step(s); the last step 2 island(s), the largest of 2 bodies"
        ),
        "{alone}"
    );
    let whole = plan(&pyramid, "2");
    assert!(
        whole.contains("the whole, colour by colour")
            && whole.contains("; 0 of its colour passes spread over the pool (those of 64 bodies or more)")
            && whole.contains("the largest of 15 bodies"),
        "{whole}"
    );
}
