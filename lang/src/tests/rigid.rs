//! Rigid bodies and the joints between them.

use super::*;

const BRICK: &str = r#"scene s {
  entity { shape: box, size: [1, 2, 3], mass: 12, position: [0, 0, 0], orientation: { axis: [0, 0, 1], angle: 90 deg }, angular_velocity: [0, 2, 0] }
  solver { dt: 0.01, steps: 10 }
}"#;

/// A shaped entity is a rigid body: its moments from shape and mass, its spin from its
/// orientation and angular velocity (turned into the body frame).
#[test]
fn a_shaped_entity_is_a_rigid_body() {
    let s = compile(BRICK).unwrap();
    assert_eq!(s.model.bodies[0].moments, Some([13.0, 10.0, 5.0]));
    let spin = s.spin0[0];
    let half = std::f64::consts::FRAC_1_SQRT_2;
    assert!((spin[0] - half).abs() < 1e-15 && (spin[3] - half).abs() < 1e-15, "{spin:?}");
    // a body turned 90° about z has its x axis along the world's y: ω = 2ŷ is 2x̂ in the body,
    // π = I ω = (26, 0, 0)
    assert!((spin[4] - 26.0).abs() < 1e-13 && spin[5].abs() < 1e-13 && spin[6] == 0.0, "{spin:?}");
    assert_eq!(s.sizes[0], 1.5);
    let ball = compile(&BRICK.replacen("shape: box, size: [1, 2, 3]", "shape: sphere, size: 0.5", 1)).unwrap();
    assert!(ball.model.bodies[0].moments.unwrap().iter().all(|m| (m - 1.2).abs() < 1e-15)); // ⅖·12·0.5²
    let quaternion = BRICK.replacen("{ axis: [0, 0, 1], angle: 90 deg }", "[1, 0, 0, 0]", 1);
    assert_eq!(compile(&quaternion).unwrap().spin0[0][..4], [1.0, 0.0, 0.0, 0.0]);
}

#[test]
fn rigid_bodies_reject_bad_shapes_and_orientations() {
    let e = |from: &str, to: &str| error_in(BRICK, from, to);
    assert_eq!(
        e("size: [1, 2, 3]", "size: [1, 0, 3]"),
        at(2, 30, "entity.size: a box's edge length must be positive and finite, not 0")
    );
    assert_eq!(e("size: [1, 2, 3]", "size: 2"), at(2, 30, "entity.size expects a vector [x, y, z]"));
    assert_eq!(e("shape: box", "shape: cone"), at(2, 19, "unknown shape `cone`; known: box, sphere"));
    assert_eq!(
        e("size: [1, 2, 3], ", ""),
        at(2, 19, "a rigid body needs a size: `size: [a, b, c]` for a box, `size: r` for a sphere")
    );
    assert_eq!(
        e("{ axis: [0, 0, 1], angle: 90 deg }", "[1, 0, 0, 0.1]"),
        at(2, 85, "entity.orientation [w, x, y, z] must be a unit quaternion (its norm is 1.004987562112089); or write { axis: [x, y, z], angle: θ }")
    );
    assert_eq!(e("axis: [0, 0, 1]", "axis: [0, 0, 0]"), at(2, 93, "orientation.axis must not be zero"));
    assert_eq!(e(", angle: 90 deg", ""), at(2, 85, "orientation needs an `angle`"));
    assert_eq!(
        e("angular_velocity: [0, 2, 0]", "angular_velocity: [0, 2, 0] m/s"),
        at(2, 149, "entity.angular_velocity expects T⁻¹, found L·T⁻¹ (velocity)")
    );
    assert_eq!(
        e("shape: box, size: [1, 2, 3], ", ""),
        at(2, 43, "entity.orientation needs a `shape` (box or sphere): a point mass has no orientation")
    );
    assert_eq!(e("mass: 12", "mass: 0"), at(2, 47, "entity.mass must be positive, got 0"));
}

#[test]
fn a_lattice_of_rigid_bodies_is_refused() {
    let src = "scene s {\n  entity brick { mass: 1, shape: box, size: [1, 1, 1] }\n  lattice { type: brick, density: 0.8, cells: [2, 2, 2], temperature: 1, seed: 1 }\n  solver { dt: 0.01, steps: 1 }\n}";
    let d = compile(src).unwrap_err();
    assert_eq!(
        (d.line_col(src), d.message.as_str()),
        ((2, 27), "a lattice's bodies are point masses: its entity type cannot have a shape")
    );
}

/// Two bricks hinged end to end, the first hinged to the world.
const HINGED: &str = "scene s {
  entity { shape: box, size: [1, 0.2, 0.2], mass: 1, position: [0.5, 0, 0] }
  entity { shape: box, size: [1, 0.2, 0.2], mass: 1, position: [1.5, 0, 0] }
  entity { mass: 1, position: [5, 0, 0] }
  joint hinge [0] { at: [0, 0, 0], axis: [0, 0, 1] }
  joint ball [0, 1] { at: [1, 0, 0] }
  @expect joint_satisfied { tol: 1e-3 }
  solver { integrator: \"avbd\", dt: 0.001, steps: 10 }
}";

#[test]
fn joints_become_pins_in_the_bodies_frames() {
    let s = compile(HINGED).unwrap();
    let pins = &s.model.pins;
    assert_eq!(pins.len(), 3, "a hinge is two pins, a ball joint one");
    assert_eq!((pins[0].a, pins[0].b, pins[0].on_a, pins[0].on_b), (None, 0, [0.0; 3], [-0.5, 0.0, 0.0]));
    // the hinge's second pin: one reach of the brick (√(0.5² + 0.1² + 0.1²)) along z
    let reach = (0.27f64).sqrt();
    assert_eq!(pins[1].on_b, [-0.5, 0.0, reach]);
    assert_eq!((pins[2].a, pins[2].b, pins[2].on_a, pins[2].on_b), (Some(0), 1, [0.5, 0.0, 0.0], [-0.5, 0.0, 0.0]));
    // without a solver block naming one, a jointed scene gets avbd
    let plain = HINGED.replace("integrator: \"avbd\", ", "");
    assert_eq!(compile(&plain).unwrap().solver.integrator, crate::integrator::Integrator::Avbd);
}

#[test]
fn bad_joints_are_refused_where_they_are_written() {
    let e = |from: &str, to: &str| error_in(HINGED, from, to);
    assert_eq!(
        e("ball [0, 1]", "ball [0, 2]"),
        at(6, 18, "joint: body 2 is a point mass; a joint joins solids (entities with a `shape`)")
    );
    assert_eq!(e("ball [0, 1]", "ball [1, 1]"), at(6, 14, "joint ball joins body 1 to itself"));
    assert_eq!(e("ball [0, 1]", "ball [0, 9]"), at(6, 18, "joint: body 9 does not exist (3 bodies)"));
    assert_eq!(
        e("ball [0, 1]", "ball [0, 1, 2]"),
        at(6, 14, "joint ball joins two solids `[i, j]`, or one and the world `[i]`; got 3 indices")
    );
    assert_eq!(e("axis: [0, 0, 1]", "axis: [0, 0, 0]"), at(5, 42, "a hinge's axis must not be zero"));
    assert_eq!(e(", axis: [0, 0, 1]", ""), at(5, 3, "joint hinge needs `axis`, the direction it turns about"));
    assert_eq!(
        e("at: [1, 0, 0] }", "at: [1, 0, 0], axis: [1, 0, 0] }"),
        at(6, 38, "`axis` belongs to a hinge; a ball joint turns every way")
    );
    assert_eq!(e("joint ball", "joint slider"), at(6, 9, "unknown joint `slider`; known joints: ball, hinge"));
    assert_eq!(
        e("at: [1, 0, 0]", "at: [3, 0, 0]"),
        at(6, 27, "joint: its point is 2.5000 from body 0's centre, beyond the body's reach 0.5196: the bodies must start joined at `at`")
    );
    assert_eq!(
        e("integrator: \"avbd\", ", "integrator: \"sequential_impulses\", "),
        at(5, 3, "joints are held by `avbd` alone; the solver's sequential_impulses cannot keep them: set `integrator: \"avbd\"`")
    );
    assert_eq!(e("at: [0, 0, 0], ", ""), at(5, 3, "joint hinge needs `at`, the joint's point (a length vector)"));
    let unjointed = HINGED
        .replace("  joint hinge [0] { at: [0, 0, 0], axis: [0, 0, 1] }\n  joint ball [0, 1] { at: [1, 0, 0] }\n", "");
    let d = compile(&unjointed).unwrap_err();
    assert_eq!((d.line_col(&unjointed), d.message.as_str()), ((5, 11), "joint_satisfied: the model has no joint"));
}

/// Where solids touch and the scene names no solver, it gets AVBD, unless it claims what AVBD
/// does not keep (energy, momentum, angular momentum, or Noether's claims): then sequential
/// impulses. A scene that names one gets it.
#[test]
fn a_contact_scene_gets_avbd_unless_it_claims_energy_or_momentum() {
    use crate::integrator::Integrator;
    let scene = |claim: &str, solver: &str| {
        format!(
            "scene s {{
  entity {{ shape: box, size: [1, 1, 1], mass: 1, position: [0, 0.5, 0] }}
  floor {{ y: 0 }}
  {claim}
  solver {{ {solver}dt: 0.01, steps: 10 }}
}}"
        )
    };
    let integrator = |claim: &str, solver: &str| compile(&scene(claim, solver)).unwrap().solver.integrator;
    assert_eq!(integrator("@expect resting { max_speed: 1e-3 }", ""), Integrator::Avbd);
    assert_eq!(integrator("@expect no_penetration { tol: 1e-3 }", ""), Integrator::Avbd);
    assert_eq!(integrator("", ""), Integrator::Avbd);
    for claim in [
        "@expect energy_conservation { tol: 1e-3 }",
        "@expect momentum_conservation { axes: \"xz\" }",
        "@expect angular_momentum_conservation { axes: \"y\" }",
        "@expect noether",
    ] {
        assert_eq!(integrator(claim, ""), Integrator::SequentialImpulses, "{claim}");
    }
    let named = "integrator: \"sequential_impulses\", ";
    assert_eq!(integrator("@expect resting { max_speed: 1e-3 }", named), Integrator::SequentialImpulses);
}
