//! Lattices, thermostats and sampling settings.

use super::*;

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

/// A compile asks for the run's threads only for a lattice of `SPREAD_FROM` bodies or more,
/// once, with its bodies; laid out on them, the scene is the same to the bit.
#[test]
fn a_large_lattice_asks_for_threads_once_and_is_the_same_on_them() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    let asked = AtomicUsize::new(0);
    let threads = |bodies: usize| {
        asked.fetch_add(bodies, Ordering::Relaxed);
        Some(&pool)
    };
    let small = crate::compile_on(LATTICE, &threads).unwrap();
    assert_eq!((asked.load(Ordering::Relaxed), small.x0.len()), (0, 240), "a small lattice asks for none");
    let large = LATTICE.replace("[3, 4, 5]", "[16, 16, 17]"); // 17,408 bodies
    let (one, many) = (compile(&large).unwrap(), crate::compile_on(&large, &threads).unwrap());
    assert_eq!(asked.load(Ordering::Relaxed), 17_408);
    let bits = |s: &crate::Scene| [&s.x0, &s.v0].map(|xs| xs.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>());
    assert_eq!(bits(&one), bits(&many));
    assert_eq!((&one.model.bodies, &one.sizes), (&many.model.bodies, &many.sizes));
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
