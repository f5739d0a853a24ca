//! Every solver: its order of convergence on a problem with a closed-form answer, its
//! invariants, and the same bits on any number of threads.

use super::*;
use crate::setup::{compile, start};
use lagra_lang::Scene;

/// Runs a scene's own solver to time `t` at step `dt` (with the scene's settings).
fn run_to(scene: &Scene, dt: f64, t: f64) -> State {
    let g = LagrangianGraph::new(&scene.model);
    let mut s = start(scene);
    let mut stepper = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &s).unwrap();
    let steps = (t / dt).round() as u64;
    stepper.advance_to(&g, &mut s, dt, steps).unwrap();
    s
}

/// The harmonic pair (k = 4, μ = ½: ω = √8) released from a stretch of 0.3: the separation is
/// r₀ + 0.3 cos ωt exactly. The error at t = 2.
fn oscillator(integrator: &str, dt: f64) -> f64 {
    let scene = compile(&format!(
        "scene o {{ entity {{ position: [0, 0, 0], mass: 1 }} entity {{ position: [1.3, 0, 0], mass: 1 }}
           bond harmonic [0, 1] {{ k: 4, r0: 1 }}
           solver {{ integrator: \"{integrator}\", dt: 0.1 }} }}"
    ))
    .unwrap();
    let s = run_to(&scene, dt, 2.0);
    let exact = 1.0 + 0.3 * (8f64.sqrt() * s.t).cos();
    (s.x[1][0] - s.x[0][0] - exact).abs()
}

/// A charge (q = m = 1) in B = 2ẑ: a circle of radius |v|/ω at ω = 2, clockwise seen from +z.
/// The error of its position at t = 3.
fn cyclotron(integrator: &str, dt: f64) -> f64 {
    let scene = compile(&format!(
        "scene c {{ entity {{ position: [0.5, 0, 0], velocity: [0, -1, 0], mass: 1, charge: 1 }}
           magnetic {{ B: [0, 0, 2] }}
           solver {{ integrator: \"{integrator}\", dt: 0.1 }} }}"
    ))
    .unwrap();
    let s = run_to(&scene, dt, 3.0);
    let (x, y) = (0.5 * (2.0 * s.t).cos(), -0.5 * (2.0 * s.t).sin());
    ((s.x[0][0] - x).powi(2) + (s.x[0][1] - y).powi(2)).sqrt()
}

/// A rigid rotor: two unit masses held 1 apart, spinning at ω = 2 about their centre: a
/// circle. The error of body 1's position at t = 3.
fn rotor(dt: f64) -> f64 {
    let scene = compile(
        "scene r { entity { position: [-0.5, 0, 0], velocity: [0, -1, 0], mass: 1 }
           entity { position: [0.5, 0, 0], velocity: [0, 1, 0], mass: 1 }
           constraint [0, 1] { length: 1 }
           solver { integrator: \"rattle\", dt: 0.1, tol: 1e-14 } }",
    )
    .unwrap();
    let s = run_to(&scene, dt, 3.0);
    let (x, y) = (0.5 * (2.0 * s.t).cos(), 0.5 * (2.0 * s.t).sin());
    ((s.x[1][0] - x).powi(2) + (s.x[1][1] - y).powi(2)).sqrt()
}

/// The order measured between dt and dt/2.
fn order(error: impl Fn(f64) -> f64, dt: f64) -> f64 {
    (error(dt) / error(dt / 2.0)).log2()
}

#[test]
fn each_solver_converges_at_its_order() {
    for (name, dt) in [
        ("velocity_verlet", 0.01),
        ("symplectic_euler", 0.01),
        ("yoshida4", 0.02),
        ("rk4", 0.02),
        ("boris", 0.01),
        ("rattle", 0.01),
        ("action_descent", 0.01),
    ] {
        let i = Integrator::from_name(name).unwrap();
        let p = order(|dt| oscillator(name, dt), dt);
        assert!((p - i.order() as f64).abs() <= 0.3, "{name}: order {p} on the oscillator");
    }
}

#[test]
fn boris_and_verlet_converge_at_second_order_in_a_magnetic_field() {
    for name in ["boris", "velocity_verlet"] {
        let p = order(|dt| cyclotron(name, dt), 0.02);
        assert!((p - 2.0).abs() <= 0.3, "{name}: order {p}");
    }
}

#[test]
fn rattle_converges_at_second_order_on_a_rigid_rotor() {
    let p = order(rotor, 0.02);
    assert!((p - 2.0).abs() <= 0.3, "order {p}");
}

/// The relative change of a charge's speed in a pure magnetic field over `steps` steps.
fn speed_drift(integrator: &str, dt: f64, steps: u64) -> f64 {
    let scene = compile(&format!(
        "scene c {{ entity {{ position: [0.5, 0, 0], velocity: [0.3, -1, 0.2], mass: 1, charge: 1 }}
           magnetic {{ B: [0.3, -0.1, 2] }} solver {{ integrator: \"{integrator}\", dt: {dt} }} }}"
    ))
    .unwrap();
    let g = LagrangianGraph::new(&scene.model);
    let mut s = start(&scene);
    let speed = |s: &State| s.v[0].iter().map(|c| c * c).sum::<f64>().sqrt();
    let v0 = speed(&s);
    let mut stepper = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &s).unwrap();
    stepper.advance_to(&g, &mut s, dt, steps).unwrap();
    (speed(&s) - v0).abs() / v0
}

/// In a pure magnetic field (ω ≈ 2) Boris turns the velocity by exact rotations: over 10⁶
/// steps |v| (the energy) moves by rounding only, under an ulp a step, at ω·dt = 0.2 and 0.75
/// alike. Velocity Verlet's implicit closing kick keeps |v⊥| exactly only where its fixed
/// point converges to the last bit: at ω·dt = 0.2 it has drifted by 2·10⁻⁴ (measured).
#[test]
fn boris_keeps_the_speed_to_round_off_where_verlet_drifts() {
    let steps = 1_000_000;
    for dt in [0.1, 0.37] {
        let drift = speed_drift("boris", dt, steps);
        assert!(drift < steps as f64 * f64::EPSILON / 2.0, "dt {dt}: |Δv|/|v| = {drift:e}");
    }
    let verlet = speed_drift("velocity_verlet", 0.1, steps);
    assert!(verlet > 1e-6, "velocity Verlet: |Δv|/|v| = {verlet:e}");
}

/// The forces are the same bits on any number of threads, so every solver's trajectory is.
#[test]
fn every_solver_gives_the_same_bits_on_any_number_of_threads() {
    let lattice = "entity atom { mass: 1 }
        lattice { type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 1.4, seed: 5 }
        interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }";
    for i in Integrator::ALL {
        let window = if i == Integrator::ActionDescent { ", window: 2" } else { "" };
        let scene =
            compile(&format!("scene m {{ {lattice} solver {{ integrator: \"{}\", dt: 0.004{window} }} }}", i.name()))
                .unwrap();
        let end = |threads: usize| {
            let g = LagrangianGraph::with_threads(&scene.model, threads).unwrap();
            let mut s = start(&scene);
            let mut st = Stepper::new(i, scene.solver.settings, &g, &s).unwrap();
            st.advance_to(&g, &mut s, 0.004, 3).unwrap();
            (s, st.potential().to_bits())
        };
        assert_eq!(end(1), end(3), "{}", i.name());
    }
}

/// Action descent's windows are the implicit midpoint rule, a window at a time: stepping a
/// window through in one call or one step at a time gives the same bits, and the energy of the
/// oscillator stays bounded, as for any symplectic method.
#[test]
fn action_descent_delivers_the_same_states_however_it_is_stepped() {
    let scene = compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0, 0.1], velocity: [0, 0.2, 0], mass: 2 }
           bond harmonic [0, 1] { k: 4, r0: 1 }
           solver { integrator: \"action_descent\", dt: 0.01, window: 7 } }",
    )
    .unwrap();
    let g = LagrangianGraph::new(&scene.model);
    let (mut a, mut b) = (start(&scene), start(&scene));
    let mut one = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &a).unwrap();
    let mut many = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &b).unwrap();
    for _ in 0..100 {
        one.step(&g, &mut a, 0.01).unwrap();
    }
    for until in [3, 50, 51, 100] {
        many.advance_to(&g, &mut b, 0.01, until).unwrap();
    }
    assert_eq!(a, b);
    let it = one.iterations().unwrap();
    assert_eq!(it.windows.len(), 15);
    assert!(it.windows.iter().all(|w| w.residual <= 1e-12 && w.iterations >= 1));
}

/// A window too long for its dt does not converge: an error naming its first step.
#[test]
fn an_action_window_that_cannot_converge_is_an_error() {
    let scene = compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 400, r0: 1 }
           solver { integrator: \"action_descent\", dt: 0.05, window: 64, iterations: 200 } }",
    )
    .unwrap();
    let g = LagrangianGraph::new(&scene.model);
    let mut s = start(&scene);
    let mut st = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &s).unwrap();
    let e = st.advance_to(&g, &mut s, 0.05, 10).unwrap_err();
    assert!(e.to_string().contains("action window from step 0"), "{e}");
    assert_eq!(s.step, 0);
}

/// RATTLE keeps the rods of a swinging chain to its tolerance at every step.
#[test]
fn rattle_keeps_a_chain_rigid() {
    let scene = compile(
        "scene p { entity { position: [0, 0, 0], mass: 1 } entity { position: [1, 0, 0], mass: 1 }
           entity { position: [2, 0, 0], velocity: [0, 0.5, 0], mass: 1 } entity { position: [3, 0, 0], mass: 2 }
           constraint [0, 1] { length: 1 } constraint [1, 2] { length: 1 } constraint [2, 3] { length: 1 }
           gravity { g: [0, -9.81, 0] } trap { k: 100, center: [0, 0, 0], on: [0] }
           solver { dt: 0.002, tol: 1e-11 } }",
    )
    .unwrap();
    assert_eq!(scene.solver.integrator, Integrator::Rattle);
    let g = LagrangianGraph::new(&scene.model);
    let mut s = start(&scene);
    let mut st = Stepper::new(scene.solver.integrator, scene.solver.settings, &g, &s).unwrap();
    let k = crate::constraints::Constraints::of(&scene.model).unwrap();
    for until in 1..=2000 {
        st.advance_to(&g, &mut s, 0.002, until).unwrap();
        assert!(k.errors(&s.x).iter().all(|e| *e <= 1e-11), "step {until}: {:?}", k.errors(&s.x));
    }
    assert!(st.iterations().unwrap().most_iterations >= 1);
}

/// 5,324 LJ atoms (enough to split the pair list), under a scene's thermostat.
fn thermostatted(bath: &str) -> Scene {
    compile(&format!(
        "scene m {{ entity atom {{ mass: 1.3 }}
           lattice {{ type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 1.4, seed: 5 }}
           interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
           thermostat {bath}
           solver {{ dt: 0.004 }} }}"
    ))
    .unwrap()
}

/// Both thermostats give the same bits on any number of threads (a Langevin bath draws each
/// body's noise alone), and stepping to a step in one call is stepping one at a time.
#[test]
fn thermostats_give_the_same_bits_on_any_number_of_threads_and_however_stepped() {
    for bath in ["nose_hoover { T: 1.0, tau: 0.1 }", "langevin { T: 1.0, gamma: 2, seed: 9 }"] {
        let scene = thermostatted(bath);
        let end = |threads: usize, at_once: bool| {
            let g = LagrangianGraph::with_threads(&scene.model, threads).unwrap();
            let mut s = start(&scene);
            let mut st = Stepper::for_scene(&scene, &g, &s).unwrap();
            if at_once {
                st.advance_to(&g, &mut s, 0.004, 4).unwrap();
            } else {
                for _ in 0..4 {
                    st.step(&g, &mut s, 0.004).unwrap();
                }
            }
            (s, st.potential().to_bits(), st.forces().to_vec())
        };
        let one = end(1, true);
        assert!(one.0.chain.iter().any(|l| l[1] != 0.0) || bath.starts_with("langevin"), "{bath}: the chain moved");
        assert_eq!(one, end(3, true), "{bath}");
        assert_eq!(one, end(1, false), "{bath}");
    }
}

/// A Langevin bath's O step is exact for free bodies: from rest, the velocities become
/// Gaussian at the bath's kT/m, on every axis; the same seed gives the same bits, another seed
/// other ones.
#[test]
fn a_langevin_bath_brings_free_bodies_to_its_temperature() {
    let scene = |seed: u64| {
        compile(&format!(
            "scene g {{ entity atom {{ mass: 2 }}
               lattice {{ type: atom, density: 0.01, cells: [10, 10, 10] }}
               thermostat langevin {{ T: 0.7, gamma: 5, seed: {seed} }}
               solver {{ dt: 0.01, steps: 400 }} }}"
        ))
        .unwrap()
    };
    let end = |seed: u64| {
        let s = scene(seed);
        let g = LagrangianGraph::new(&s.model);
        let mut state = start(&s);
        Stepper::for_scene(&s, &g, &state).unwrap().advance_to(&g, &mut state, 0.01, 400).unwrap();
        state
    };
    let s = end(4);
    let n = 3.0 * s.v.len() as f64;
    let t = 2.0 * crate::state::kinetic(&s, &vec![2.0; s.v.len()]) / n;
    // 3000 components: the kinetic temperature's relative spread is √(2/3000) ≈ 2.6%
    assert!((t / 0.7 - 1.0).abs() < 0.08, "kinetic temperature {t}");
    assert_eq!(s, end(4));
    assert_ne!(s.v, end(5).v);
}

/// The Nosé–Hoover chain holds an LJ liquid started hot near the bath's temperature, and H′
/// stays put (the checker certifies it in the shipped scene `lj_nvt`).
#[test]
fn a_nose_hoover_chain_holds_a_liquid_at_its_temperature() {
    let scene = compile(
        "scene m { entity atom { mass: 1 }
           lattice { type: atom, density: 0.8442, cells: [4, 4, 4], temperature: 2.0, seed: 5 }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           thermostat nose_hoover { T: 0.9, tau: 0.2 }
           solver { dt: 0.004 } }",
    )
    .unwrap();
    let g = LagrangianGraph::new(&scene.model);
    let mut s = start(&scene);
    let chain = scene.model.thermostat.clone().unwrap();
    let mut st = Stepper::for_scene(&scene, &g, &s).unwrap();
    let h = |s: &State, potential: f64| crate::state::kinetic(s, &g.masses) + potential + chain.energy(&s.chain, &0.0);
    let h0 = h(&s, st.potential());
    let (mut sum, mut n, mut worst) = (0.0, 0.0, 0.0f64);
    for until in (10..=5000).step_by(10) {
        st.advance_to(&g, &mut s, 0.004, until).unwrap();
        worst = worst.max(((h(&s, st.potential()) - h0) / h0).abs());
        if until > 2500 {
            sum += 2.0 * crate::state::kinetic(&s, &g.masses) / chain.dof;
            n += 1.0;
        }
    }
    assert!((sum / n / 0.9 - 1.0).abs() < 0.03, "⟨T⟩ = {}", sum / n);
    assert!(worst < 1e-3, "H′ moved by {worst:e}");
}

/// The implicit kick's rounds stop where a round moves no velocity by more than 4 ulps of the
/// largest speed: a wander in the last bits settles, a real move does not, and bodies at rest
/// have settled.
#[test]
fn a_round_that_moves_by_rounding_alone_has_settled() {
    let v = vec![[1.5, -0.25, 0.0], [1e-9, 3.0, -2.0]];
    let nudged = |by: f64| {
        let mut w = v.clone();
        w[1][0] += by * f64::EPSILON * 3.0;
        w
    };
    assert!(super::settled(&v, &v));
    assert!(super::settled(&nudged(3.5), &v) && super::settled(&v, &nudged(-3.5)));
    assert!(!super::settled(&nudged(4.5), &v) && !super::settled(&v, &nudged(-4.5)));
    assert!(super::settled(&[[0.0; 3]; 2], &[[0.0; 3]; 2]));
    assert!(!super::settled(&[[0.0; 3]; 2], &[[0.0, 1e-300, 0.0]; 2]));
}
