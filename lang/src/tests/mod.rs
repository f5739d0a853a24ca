//! Every kind of input error: its exact message and its position. The language's core here;
//! lattices and baths, rigid bodies and joints, fluids in their own files.

use super::compile;

mod ensembles;
mod fluids;
mod rigid;

const GOOD: &str = r#"scene s {
  entity { position: [0, 0, 0], mass: 1 }
  entity { position: [1, 0, 0], mass: 1 }
  bond harmonic [0, 1] { k: 2.0, r0: 1.0 }
  solver { dt: 0.01, steps: 10 }
}"#;

/// The (line, column, message) of the error in `GOOD` with `from` replaced by `to`.
fn error(from: &str, to: &str) -> (usize, usize, String) {
    error_in(GOOD, from, to)
}

fn error_in(good: &str, from: &str, to: &str) -> (usize, usize, String) {
    assert!(good.contains(from), "{from}");
    let src = good.replacen(from, to, 1);
    let d = compile(&src).expect_err("must not compile");
    let (l, c) = d.line_col(&src);
    (l, c, d.message)
}

fn at(l: usize, c: usize, m: &str) -> (usize, usize, String) {
    (l, c, m.to_string())
}

#[test]
fn the_good_scene_compiles() {
    let s = compile(GOOD).unwrap();
    assert_eq!((s.model.bodies.len(), s.model.terms.len(), s.solver.steps), (2, 1, 10));
}

#[test]
fn syntax_error_says_what_was_expected() {
    assert_eq!(error("mass: 1 }", "mass 1 }"), at(2, 33, "expected a field `name: value`, found `mass`"));
    // a vector that opens with a name: said at the name, not at the number after it
    assert_eq!(
        error("[1, 0, 0]", "[nan, 0, 0]"),
        at(3, 23, "expected a number, found `nan` (a vector holds numbers only: a value must be finite)")
    );
    assert_eq!(
        error("[1, 0, 0]", "[ x1 ,0, 0]"),
        at(3, 24, "expected a number, found `x1` (a vector holds numbers only)")
    );
    assert_eq!(
        error("[1, 0, 0]", "[a, b, 0]"),
        at(3, 23, "expected a number, found `a` (a vector holds numbers only)")
    );
    assert_eq!(error("[1, 0, 0]", "[true, 0]"), at(3, 29, "expected a name, found `0`"));
    assert_eq!(error("steps: 10 }\n}", "steps: 10 }\n"), at(6, 1, "expected `@expect`, `@predict`, `uses`, `description`, `units`, `entity`, `bond`, `constraint`, `joint`, `interaction`, `thermostat`, `solver`, `box`, `lattice` or a name, found end of file"));
}

#[test]
fn unknown_keyword() {
    assert_eq!(
        error("solver {", "solvr {"),
        at(5, 3, "unknown term `solvr`; known: gravity, well, trap, electric, drag, floor, magnetic, wall, sph")
    );
    assert_eq!(
        error("bond harmonic", "bond spring"),
        at(4, 8, "unknown bond `spring`; known: harmonic, morse, fene, angle, dihedral, hbond")
    );
    assert_eq!(error("  solver", "  @expect energy { tol: 1 }\n  solver"), at(5, 11, "unknown claim `energy`; known claims: energy_conservation, momentum_conservation, angular_momentum_conservation, dimensional_consistency, distance, constraint_satisfied, resting, no_penetration, joint_satisfied, noether"));
}

#[test]
fn unknown_template() {
    assert_eq!(
        error("entity { position: [1", "entity { type: bead, position: [1"),
        at(3, 18, "unknown entity type `bead`; known types: ball, ball_large, ball_small")
    );
}

#[test]
fn templates_supply_fields() {
    let src = GOOD
        .replace("scene s {", "scene s {\n  entity bead { mass: 3.0 }")
        .replace("position: [1, 0, 0], mass: 1", "type: bead, position: [1, 0, 0]");
    assert_eq!(compile(&src).unwrap().model.bodies[1].mass, 3.0);
}

#[test]
fn bond_index_out_of_range() {
    assert_eq!(error("[0, 1]", "[0, 2]"), at(4, 21, "body index 2 is out of range: the scene has 2 entities (0..1)"));
    assert_eq!(error("[0, 1]", "[0, 0]"), at(4, 21, "HarmonicBond lists body 0 twice"));
    assert_eq!(error("[0, 1]", "[0, 1, 1]"), at(4, 17, "HarmonicBond joins 2 bodies, got 3"));
}

#[test]
fn duplicate_field() {
    assert_eq!(error("r0: 1.0", "r0: 1.0, k: 3"), at(4, 43, "duplicate field `k`"));
}

#[test]
fn missing_field() {
    assert_eq!(error(", r0: 1.0", ""), at(4, 8, "HarmonicBond needs `r0` (L (length))"));
    assert_eq!(error("position: [0, 0, 0], ", ""), at(2, 10, "entity needs a position"));
    assert_eq!(error("  solver { dt: 0.01, steps: 10 }\n", ""), at(1, 1, "scene s has no solver block"));
}

#[test]
fn unknown_field() {
    assert_eq!(
        error("r0: 1.0", "r0: 1.0, kk: 3"),
        at(4, 43, "unknown field `kk` for HarmonicBond; expected k, r0, damping")
    );
}

#[test]
fn non_positive_mass() {
    assert_eq!(error("[1, 0, 0], mass: 1", "[1, 0, 0], mass: -1"), at(3, 39, "entity.mass must be positive, got -1"));
    assert_eq!(error("[1, 0, 0], mass: 1", "[1, 0, 0], mass: 0"), at(3, 39, "entity.mass must be positive, got 0"));
}

#[test]
fn non_finite_number() {
    assert_eq!(error("k: 2.0", "k: 1e999"), at(4, 29, "non-finite number `1e999`"));
    assert_eq!(error("k: 2.0", "k: nan"), at(4, 29, "HarmonicBond.k expects a number, found `nan`"));
}

#[test]
fn unit_mismatch() {
    let si = GOOD.replace("scene s {", "scene s {\n  units si");
    let d = compile(&si.replace("k: 2.0", "k: 2.0 C")).unwrap_err();
    assert_eq!(d.message, "HarmonicBond.k expects M·T⁻² (energy/length²), found Q (charge)");
    let d = compile(&si.replace("dt: 0.01", "dt: 0.01 m")).unwrap_err();
    assert_eq!(d.message, "solver.dt expects T (time), found L (length)");
}

#[test]
fn units_convert_to_si() {
    let si = GOOD
        .replace("scene s {", "scene s {\n  units si")
        .replace("k: 2.0", "k: 2.0 N/m")
        .replace("r0: 1.0", "r0: 10 cm");
    let s = compile(&si).unwrap();
    assert_eq!(s.model.terms[0].params[..2], [2.0, 0.1]);
}

#[test]
fn physical_unit_in_reduced_units_is_an_error() {
    assert_eq!(
        error("k: 2.0", "k: 2.0 N/m"),
        at(4, 33, "a physical unit in a scene with reduced units; declare `units si` or write a bare number")
    );
}

#[test]
fn unknown_unit() {
    let si = GOOD.replace("scene s {", "scene s {\n  units si").replace("r0: 1.0", "r0: 1.0 furlong");
    assert!(compile(&si).unwrap_err().message.starts_with("unknown unit `furlong`; known units: m, km"));
}

#[test]
fn solver_errors() {
    assert_eq!(error("steps: 10", "steps: 10, duration: 1"), at(5, 33, "give `steps` or `duration`, not both"));
    assert_eq!(error("steps: 10", "steps: 2.5"), at(5, 29, "solver.steps expects a whole number ≥ 1, got 2.5"));
    assert_eq!(
        error("dt: 0.01", "dt: 0.01, integrator: rk45"),
        at(5, 34, "unknown integrator `rk45`; known: velocity_verlet, symplectic_euler, yoshida4, rk4, boris, rattle, action_descent, sequential_impulses, avbd")
    );
    assert_eq!(compile(&GOOD.replace("steps: 10", "duration: 1")).unwrap().solver.steps, 100);
}

/// An integrator that cannot handle the scene's terms, or a setting it does not take, is an
/// error at the solver line.
#[test]
fn integrators_refuse_what_they_cannot_handle() {
    let rod = "  constraint [0, 1] { length: 1 }\n  solver";
    assert_eq!(
        error_in(&GOOD.replace("  solver", rod), "dt: 0.01", "integrator: \"yoshida4\", dt: 0.01"),
        at(6, 25, "yoshida4 cannot keep constraints: use `rattle`")
    );
    let drag = "  drag { gamma: 0.5 }\n  solver";
    assert_eq!(
        error_in(&GOOD.replace("  solver", drag), "dt: 0.01", "integrator: \"boris\", dt: 0.01"),
        at(
            6,
            25,
            "boris rotates velocities only for magnetic fields; `drag` is dissipative: use velocity_verlet (line 5)"
        )
    );
    let magnetic = "  magnetic { B: [0, 0, 1] }\n  solver";
    assert_eq!(
        error_in(&GOOD.replace("  solver", magnetic), "dt: 0.01", "integrator: \"action_descent\", dt: 0.01"),
        at(6, 25, "action_descent makes the action of L = T − V stationary; `magnetic` depends on velocities: use velocity_verlet (line 5)")
    );
    assert_eq!(
        error("dt: 0.01", "dt: 0.01, window: 8"),
        at(5, 22, "`window` is a setting of action_descent; velocity_verlet takes no settings")
    );
    assert_eq!(
        error("dt: 0.01", "integrator: \"rattle\", dt: 0.01, window: 8"),
        at(5, 44, "`window` is a setting of action_descent; rattle takes tol, iterations")
    );
    // Boris with a conservative field, RATTLE without constraints: fine
    assert!(compile(
        &GOOD
            .replace("  solver", "  electric { E: [1, 0, 0] }\n  solver")
            .replace("dt: 0.01", "integrator: \"boris\", dt: 0.01")
    )
    .is_ok());
    assert!(compile(&GOOD.replace("dt: 0.01", "integrator: \"rattle\", dt: 0.01")).is_ok());
}

#[test]
fn constraint_errors() {
    let with = |c: &str| GOOD.replace("  solver", &format!("  {c}\n  solver"));
    let scene = compile(&with("constraint [0, 1] { length: 1 }")).unwrap();
    assert_eq!(scene.solver.integrator.name(), "rattle");
    assert_eq!(scene.model.constraints[0].length, 1.0);
    // without a length, the initial distance
    assert_eq!(compile(&with("constraint [0, 1]")).unwrap().model.constraints[0].length, 1.0);
    assert_eq!(
        error_in(&with("constraint [0, 1] { length: 1.5 }"), "", ""),
        at(5, 3, "constraint [0, 1] holds its bodies 1.5 apart, but they start 1 apart: place them within 1e-6 of the length")
    );
    assert_eq!(error_in(&with("constraint [0, 0]"), "", ""), at(5, 18, "constraint lists body 0 twice"));
    assert_eq!(error_in(&with("constraint [0, 1, 2]"), "", ""), at(5, 14, "constraint joins 2 bodies, got 3"));
    assert_eq!(
        error_in(&with("constraint [0, 7]"), "", ""),
        at(5, 18, "body index 7 is out of range: the scene has 2 entities (0..1)")
    );
    assert_eq!(
        error_in(&with("constraint [0, 1] { length: 2 kg }"), "", ""),
        at(5, 33, "constraint.length expects L (length), found M (mass)")
    );
    assert_eq!(
        error_in(&with("@expect constraint_satisfied { tol: 1e-9 }"), "", ""),
        at(5, 11, "constraint_satisfied: the scene declares no constraint")
    );
    // a start within 1e-6 of the length compiles as written: the kernel moves it onto the
    // constraint and makes the velocities tangent (`lagra_kernel::setup::place`, tested there)
    let near = compile(&with("constraint [0, 1] { length: 1.0000005 }")).unwrap();
    assert_eq!(near.x0[1][0] - near.x0[0][0], 1.0);
}

#[test]
fn claim_errors() {
    assert_eq!(
        error("  solver", "  @expect energy_conservation\n  solver"),
        at(5, 11, "energy_conservation needs a tolerance: `{ tol: 1e-5 }` (relative)")
    );
    assert_eq!(
        error("  solver", "  @expect momentum_conservation\n  @expect momentum_conservation\n  solver"),
        at(6, 11, "momentum_conservation is declared twice")
    );
}

#[test]
fn claims_with_axes_and_bounds() {
    let src = GOOD.replace(
        "  solver",
        "  @expect momentum_conservation { axes: \"zx\" }\n  @expect distance { between: [1, 0], min: 0.5, max: 2 }\n  @expect distance { between: [0, 1], min: 0, max: 9 }\n  solver",
    );
    let s = compile(&src).unwrap();
    assert_eq!(s.claims[0].axes, Some([true, false, true]));
    assert_eq!(s.claims[0].label(), "momentum_conservation(x, z)");
    let b = s.claims[1].between.as_ref().unwrap();
    assert_eq!((b.bodies, b.min, b.max), ([1, 0], 0.5, 2.0));
    assert_eq!(s.claims.len(), 3, "distance may be declared more than once");
}

#[test]
fn claim_field_errors() {
    let with = |c: &str| error("  solver", &format!("  @expect {c}\n  solver"));
    assert_eq!(
        with("momentum_conservation { axes: \"xw\" }"),
        at(5, 42, "momentum_conservation.axes takes some of x, y, z once each, got `xw`")
    );
    assert_eq!(
        with("energy_conservation { tol: 1e-5, axes: \"x\" }"),
        at(5, 44, "unknown field `axes` for energy_conservation; expected tol, every")
    );
    assert_eq!(
        with("distance { between: [0, 5], min: 0, max: 1 }"),
        at(5, 35, "body index 5 is out of range: the scene has 2 entities (0..1)")
    );
    assert_eq!(with("distance { between: [0, 1], min: 2, max: 1 }"), at(5, 11, "distance: min 2 is above max 1"));
    assert_eq!(
        with("distance { between: [0], min: 0, max: 1 }"),
        at(5, 31, "distance.between expects 2 body indices `[i, j]`")
    );
    assert_eq!(with("distance { min: 0, max: 1 }"), at(5, 11, "distance needs `between: [i, j]`"));
    assert_eq!(with("distance { between: [1, 1], min: 0, max: 1 }"), at(5, 35, "distance needs two different bodies"));
}

#[test]
fn prediction_that_does_not_apply() {
    assert_eq!(
        error("  solver", "  @predict kepler_period\n  solver"),
        at(5, 12, "kepler_period: needs exactly two bodies and one gravity interaction")
    );
}

#[test]
fn comments_and_empty_bodies() {
    let s = compile(&GOOD.replace("scene s {", "scene s { // a comment\n  // another")).unwrap();
    assert_eq!(s.name, "s");
    assert_eq!(error("  entity { position: [0, 0, 0], mass: 1 }\n  entity { position: [1, 0, 0], mass: 1 }\n  bond harmonic [0, 1] { k: 2.0, r0: 1.0 }\n", ""), at(1, 1, "scene s has no entities"));
}

/// For every parameter of every term, a unit of the wrong dimension is rejected with the
/// parameter's name and both dimensions, before any numerics.
#[test]
fn every_parameter_of_every_term_rejects_a_wrong_unit() {
    use lagra_checker::terms::{Kind, Shape};
    use lagra_checker::units::Dim;
    for &kind in Kind::ALL {
        let spec = kind.spec();
        for target in spec.params {
            let (wrong, found) = if target.dim == Dim::CHARGE { ("m", "L (length)") } else { ("C", "Q (charge)") };
            let fields: Vec<String> = spec
                .params
                .iter()
                .map(|p| {
                    let value = if p.len == 3 { "[1, 2, 3]" } else { "1" };
                    let unit = if p.name == target.name { wrong } else { "" };
                    format!("{}: {value} {unit}", p.name)
                })
                .collect();
            // (a term that shares its keyword is chosen by its variant's field)
            let chosen = kind.variant().map(|v| format!("{}: {}, ", v.field, v.value)).unwrap_or_default();
            let body = chosen + &fields.join(", ");
            let term = match spec.shape {
                Shape::Bond(n) => format!(
                    "bond {} [{}] {{ {body} }}",
                    spec.keyword,
                    (0..n).map(|i| i.to_string()).collect::<Vec<_>>().join(", ")
                ),
                Shape::Pairwise => format!("interaction {} {{ {body} }}", spec.keyword),
                Shape::External | Shape::Density => format!("{} {{ {body} }}", spec.keyword),
            };
            let src = format!(
                "scene s {{\n  units si\n  {}\n  {term}\n  solver {{ dt: 1 s }}\n}}",
                "entity { position: [0, 0, 0] m, mass: 1 kg }\n".repeat(4)
            );
            let d = compile(&src).expect_err(&src);
            let expected =
                format!("{}.{} expects {}, found {found}", spec.name, target.name, super::block::typed(target.dim));
            assert_eq!(d.message, expected, "{src}");
        }
    }
}

#[test]
fn angles_take_degrees_in_any_unit_system() {
    let src = GOOD.replace(
        "bond harmonic [0, 1] { k: 2.0, r0: 1.0 }",
        "entity { position: [0, 1, 0], mass: 1 }\n  bond angle [0, 1, 2] { k: 2.0, theta0: 90 deg }",
    );
    let s = compile(&src).unwrap();
    assert_eq!(s.model.terms[0].params[1], std::f64::consts::FRAC_PI_2);
}

#[test]
fn a_periodic_box_and_its_reach_checks() {
    let boxed =
        |term: &str, cell: &str| GOOD.replace("bond harmonic [0, 1] { k: 2.0, r0: 1.0 }", &format!("{cell}\n  {term}"));
    let s = compile(&boxed("interaction lj { epsilon: 1, sigma: 1, cutoff: 2.5 }", "box { size: [6, 6, 6] }")).unwrap();
    assert_eq!(s.model.cell.unwrap().periodic, [true; 3]);
    let e =
        compile(&boxed("interaction lj { epsilon: 1, sigma: 1, cutoff: 2.5 }", "box { size: [6, 4, 6] }")).unwrap_err();
    assert_eq!(e.message, "LennardJones reaches 2.5, more than half the periodic box (2)");
    let e = compile(&boxed("interaction coulomb { k: 1 }", "box { size: [6, 6, 6] }")).unwrap_err();
    assert!(e.message.starts_with("Coulomb has unbounded reach"), "{}", e.message);
    // a box closed along every axis that matters imposes nothing
    compile(&boxed("interaction coulomb { k: 1 }", "box { size: [6, 6, 6], periodic: [false, false, false] }"))
        .unwrap();
    let e = compile(&boxed("", "box { size: [6, 6, 6], periodic: [true, maybe, true] }")).unwrap_err();
    assert_eq!(e.message, "box.periodic expects 3 of true or false, like [true, true, false]");
    let e = compile(&boxed("", "box { size: [6, 0, 6] }")).unwrap_err();
    assert_eq!(e.message, "box.size must be positive, got 0");
}

#[test]
fn external_terms_act_on_listed_bodies() {
    let with = |t: &str| GOOD.replace("bond harmonic [0, 1] { k: 2.0, r0: 1.0 }", t);
    let s = compile(&with("trap { k: 5, on: [1] }")).unwrap();
    assert_eq!(s.model.terms[0].sites, [1]);
    assert_eq!(
        compile(&with("trap { k: 5, on: [3] }")).unwrap_err().message,
        "body index 3 is out of range: the scene has 2 entities (0..1)"
    );
    assert_eq!(
        compile(&with("interaction gravity { G: 1, on: [0] }")).unwrap_err().message,
        "Gravity acts on every pair; `on` belongs to external terms"
    );
}
