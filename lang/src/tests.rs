//! Every kind of input error: its exact message and its position.

use super::compile;

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
            let body = fields.join(", ");
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

const LATTICE: &str = r#"scene s {
  entity atom { mass: 1.0 }
  lattice { type: atom, kind: fcc, density: 0.8442, cells: [3, 4, 5], temperature: 1.44, seed: 5 }
  interaction lj { epsilon: 1, sigma: 1, cutoff: 2.5 }
  solver { dt: 0.005, steps: 10 }
}"#;

fn lattice_error(from: &str, to: &str) -> (usize, usize, String) {
    error_in(LATTICE, from, to)
}

#[test]
fn a_lattice_fills_its_own_periodic_box() {
    let s = compile(LATTICE).unwrap();
    assert_eq!(s.model.bodies.len(), 4 * 3 * 4 * 5);
    let c = s.model.cell.unwrap();
    let a = (4.0f64 / 0.8442).cbrt();
    assert_eq!(c.periodic, [true; 3]);
    assert!((c.size[2] - 5.0 * a).abs() < 1e-12, "{:?}", c.size);
}

#[test]
fn lattice_errors() {
    assert_eq!(
        lattice_error("  interaction", "  box { size: [9, 9, 9] }\n  interaction"),
        at(4, 3, "the lattice above sets the box: remove this box")
    );
    assert_eq!(
        lattice_error("  lattice", "  box { size: [9, 9, 9] }\n  lattice"),
        at(4, 3, "a lattice sets the box itself: remove the box above")
    );
    assert_eq!(lattice_error("kind: fcc", "kind: hcp"), at(3, 31, "unknown lattice kind `hcp`; known: fcc, sc"));
    assert_eq!(
        lattice_error("seed: 5", "seed: 5, velocities: maxwell"),
        at(3, 111, "unknown velocity draw `maxwell`; known: gaussian, uniform")
    );
    assert_eq!(
        lattice_error("cells: [3, 4, 5]", "cells: [3, 4.5, 5]"),
        at(3, 60, "lattice.cells expects whole numbers from 1 to 1000, got 4.5")
    );
    assert_eq!(lattice_error("density: 0.8442, ", ""), at(3, 3, "lattice needs `density: bodies per unit volume`"));
    assert_eq!(
        lattice_error("type: atom, ", ""),
        at(3, 3, "lattice needs `type:` an entity type declared with a mass")
    );
    assert_eq!(
        lattice_error("seed: 5", "seed: 5, colour: red"),
        at(
            3,
            99,
            "unknown field `colour` for lattice; expected type, kind, density, cells, temperature, seed, velocities"
        )
    );
}

const THERMOSTATTED: &str = r#"scene s {
  entity { position: [0, 0, 0], mass: 1 }
  entity { position: [1, 0, 0], mass: 1 }
  entity { position: [0, 1, 0], mass: 1 }
  bond harmonic [0, 1] { k: 2.0, r0: 1.0 }
  thermostat nose_hoover { T: 0.5, tau: 0.2 }
  solver { dt: 0.01, steps: 10 }
}"#;

#[test]
fn a_thermostat_compiles_into_a_chain_in_the_model() {
    let s = compile(THERMOSTATTED).unwrap();
    let chain = s.model.thermostat.as_ref().unwrap();
    // 3 bodies, internal terms only: 3N − 3 degrees of freedom; Q₁ = N_f·kT·τ², Q_j = kT·τ²
    assert_eq!((chain.kt, chain.dof, chain.masses.len()), (0.5, 6.0, 3));
    assert!((chain.masses[0] - 6.0 * 0.5 * 0.04).abs() < 1e-15 && (chain.masses[1] - 0.02).abs() < 1e-15);
    assert_eq!(s.model.links(), 3);
    let sampled = s.sampling.unwrap();
    assert_eq!((sampled.equilibrate, sampled.every, sampled.tail_corrections), (0.0, 10, false));
    let langevin =
        compile(&THERMOSTATTED.replace("nose_hoover { T: 0.5, tau: 0.2 }", "langevin { T: 0.5, gamma: 2 }")).unwrap();
    assert!(langevin.model.thermostat.is_none(), "a Langevin bath adds no degree of freedom");
    assert_eq!(langevin.bath().unwrap().dof, 9.0);
}

#[test]
fn thermostat_errors_are_located() {
    let e = |from: &str, to: &str| error_in(THERMOSTATTED, from, to);
    assert_eq!(e("T: 0.5", "T: 0"), at(6, 31, "nose_hoover.T must be positive, got 0"));
    assert_eq!(e("T: 0.5", "T: -2"), at(6, 31, "nose_hoover.T must be positive, got -2"));
    assert_eq!(e("tau: 0.2", "tau: 0"), at(6, 41, "nose_hoover.tau must be positive, got 0"));
    assert_eq!(e("T: 0.5, ", ""), at(6, 14, "nose_hoover needs `T` (k_B·T, an energy)"));
    assert_eq!(
        e("nose_hoover", "berendsen"),
        at(6, 14, "unknown thermostat `berendsen`; known: nose_hoover, langevin")
    );
    assert_eq!(
        e("tau: 0.2", "tau: 0.2, gamma: 1"),
        at(6, 46, "unknown field `gamma` for nose_hoover; expected T, tau, chain")
    );
    assert_eq!(e("tau: 0.2", "tau: 0.2, chain: 0"), at(6, 53, "nose_hoover.chain expects a whole number ≥ 1, got 0"));
    assert_eq!(e("tau: 0.2", "tau: 0.2, chain: 65"), at(6, 53, "nose_hoover.chain takes 1 to 64 links, got 65"));
    assert_eq!(
        e("  solver", "  thermostat langevin { T: 1, gamma: 1 }\n  solver"),
        at(7, 3, "second thermostat: one per scene")
    );
    assert_eq!(
        e("steps: 10", "steps: 10, integrator: boris"),
        at(7, 45, "a nose_hoover thermostat runs inside velocity_verlet; boris cannot host it")
    );
    // one body whose centre of mass the terms keep has nothing to thermalize
    let lone = "scene s {\n  entity { position: [0, 0, 0], mass: 1 }\n  thermostat nose_hoover { T: 1, tau: 1 }\n  solver { dt: 0.1 }\n}";
    assert_eq!(
        error_in(lone, "mass", "mass"),
        at(3, 14, "nose_hoover has no kinetic degree of freedom to hold at a temperature: 1 body whose centre of mass the terms keep")
    );
}

#[test]
fn a_langevin_bath_refuses_the_claims_it_cannot_keep() {
    let langevin = THERMOSTATTED.replace("nose_hoover { T: 0.5, tau: 0.2 }", "langevin { T: 0.5, gamma: 2, seed: 3 }");
    let why = "a Langevin thermostat exchanges energy and momentum with its bath at random, so it cannot be conserved; remove the claim, or use `thermostat nose_hoover`, whose extended energy is certified";
    for (claim, col) in [("energy_conservation { tol: 1e-3 }", 11), ("momentum_conservation", 11), ("noether", 11)] {
        let name = claim.split(' ').next().unwrap();
        assert_eq!(
            error_in(&langevin, "  solver", &format!("  @expect {claim}\n  solver")),
            at(7, col, &format!("{name}: {why}"))
        );
    }
    assert_eq!(
        error_in(&langevin, "gamma: 2", "gamma: 2 m"),
        at(6, 42, "langevin.gamma expects T⁻¹, found L (length)")
    );
}

#[test]
fn sampling_settings_are_checked() {
    assert_eq!(
        error("steps: 10", "steps: 10, equilibrate: -1"),
        at(5, 46, "solver.equilibrate must be a time ≥ 0, got -1")
    );
    assert_eq!(
        error("steps: 10", "steps: 10, tail_corrections: maybe"),
        at(5, 51, "solver.tail_corrections is true or false, got `maybe`")
    );
    assert_eq!(
        error("steps: 10", "steps: 10, tail_corrections: true"),
        at(5, 51, "tail_corrections apply to the measured observables: give `equilibrate` too")
    );
    // the language has no objection to this one; the run does (`lagra_run::compile`)
    assert!(compile(&GOOD.replace("steps: 10", "steps: 10, equilibrate: 0, tail_corrections: true")).is_ok());
    let s = compile(&GOOD.replace("steps: 10", "steps: 10, equilibrate: 0.05, sample_every: 2")).unwrap();
    assert_eq!(s.sampling.map(|s| (s.equilibrate, s.every)), Some((0.05, 2)));
}

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

const FLUID: &str = "scene s {
  entity { mass: 0.001, position: [0.05, 0.05, 0] }
  entity { mass: 0.001, position: [0.15, 0.05, 0] }
  sph { h: 0.13, rest_density: 1000, sound_speed: 10, alpha: 0.1 }
  wall { normal: [1, 0, 0], k: 100 }
  gravity { g: [0, -9.81, 0] }
  @predict dam_break_front { tol: 0.05 }
  solver { dt: 0.001, steps: 10 }
}";

#[test]
fn a_fluid_is_one_term_on_every_body_with_its_walls() {
    let s = compile(FLUID).unwrap();
    use lagra_checker::terms::Kind;
    let kinds: Vec<Kind> = s.model.terms.iter().map(|t| t.kind).collect();
    assert_eq!(kinds, [Kind::Sph, Kind::Wall, Kind::UniformAcceleration]);
    // γ = 7 and β = 0 by default; the wall at the origin
    assert_eq!(s.model.terms[0].params, [0.13, 1000.0, 10.0, 7.0, 0.1, 0.0]);
    assert_eq!(s.model.terms[1].params, [1.0, 0.0, 0.0, 0.0, 100.0]);
    assert!(s.model.terms[0].dissipates());
    // two bodies 0.1 apart stand for a column 0.2 wide from 0, whose front is at 1
    let column = crate::prediction::Column::of(&s.model, &s.x0).unwrap();
    assert!((column.a - 0.2).abs() < 1e-15 && column.back.abs() < 1e-15 && column.g == 9.81);
    assert!((column.front(&s.x0) - 1.0).abs() < 1e-15);
}

#[test]
fn bad_fluids_are_refused_where_they_are_written() {
    let e = |from: &str, to: &str| error_in(FLUID, from, to);
    assert_eq!(e("h: 0.13", "h: 0"), at(4, 12, "Sph.h must be positive, got 0"));
    assert_eq!(e("h: 0.13", "h: -1"), at(4, 12, "Sph.h must be positive, got -1"));
    assert_eq!(e("rest_density: 1000", "rest_density: 0"), at(4, 32, "Sph.rest_density must be positive, got 0"));
    assert_eq!(e("sound_speed: 10", "sound_speed: -3"), at(4, 51, "Sph.sound_speed must be positive, got -3"));
    assert_eq!(
        e("alpha: 0.1", "gamma: 1, alpha: 0.1"),
        at(4, 62, "Sph.gamma must exceed 1 (the internal energy divides by γ − 1)")
    );
    assert_eq!(
        e("h: 0.13", "kernel: 2, h: 0.13"),
        at(4, 9, "unknown field `kernel` for Sph; expected h, rest_density, sound_speed, gamma, alpha, beta")
    );
    assert_eq!(
        e("sph { h", "sph { on: [0], h"),
        at(4, 9, "Sph acts on every body of the fluid; `on` belongs to external terms")
    );
    assert_eq!(
        e("normal: [1, 0, 0]", "normal: [0, 0, 0]"),
        at(5, 18, "Wall.normal must not be zero: it says which side of the wall is the room")
    );
    assert_eq!(e("k: 100", "k: 0"), at(5, 32, "Wall.k must be positive, got 0"));
    assert_eq!(
        e("  wall { normal: [1, 0, 0], k: 100 }\n", ""),
        at(6, 12, "dam_break_front: needs a back wall, a `wall` with normal +x")
    );
}
