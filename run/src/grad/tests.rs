//! Reverse mode against forward mode (to 1e-10) and both against central differences (to the
//! differences' own error), on scenes of every kind of term, through neighbour-list rebuilds,
//! and on random small scenes.

use super::reverse::{Checkpoint, Replayed};
use super::*;
use crate::compile;
use lagra_lang::params;
use proptest::prelude::*;

fn grad(scene: &Scene, objective: &str, wrt: &str, method: Method) -> Gradient {
    grad_on(scene, objective, wrt, method, 1)
}

fn grad_on(scene: &Scene, objective: &str, wrt: &str, method: Method, threads: usize) -> Gradient {
    let objective = Objective::parse(objective, scene).unwrap();
    let wrt = params::parse_list(wrt, scene).unwrap();
    gradient(Request { scene, objective: &objective, wrt: &wrt, threads, progress: None }, method).unwrap()
}

/// The central difference of the objective along each parameter, and an estimate of its
/// error: over steps h = 10⁻³…10⁻⁷ (relative), the pair of neighbouring estimates that agree
/// best (large steps see the kinks where a pair's force derivative jumps at a cutoff, small
/// ones rounding), their difference doubled plus rounding's floor.
fn differences(scene: &Scene, objective: &str, wrt: &str) -> Vec<(f64, f64)> {
    let obj = Objective::parse(objective, scene).unwrap();
    let j = objective_value(scene, &obj, 1).unwrap().abs().max(1.0);
    let at = |p: Param, x: f64| {
        let mut s = scene.clone();
        p.set(&mut s, x).unwrap();
        objective_value(&s, &obj, 1).unwrap()
    };
    params::parse_list(wrt, scene)
        .unwrap()
        .iter()
        .map(|n| {
            let x = n.param.get(scene);
            let fd: Vec<(f64, f64)> = (3..=7)
                .map(|e| {
                    let h = 10f64.powi(-e) * x.abs().max(0.1);
                    ((at(n.param, x + h) - at(n.param, x - h)) / (2.0 * h), h)
                })
                .collect();
            let best =
                fd.windows(2).min_by(|a, b| (a[0].0 - a[1].0).abs().total_cmp(&(b[0].0 - b[1].0).abs())).unwrap();
            (best[1].0, 2.0 * (best[0].0 - best[1].0).abs() + 1e-14 * j / best[1].1)
        })
        .collect()
}

/// Reverse = forward to 1e-10 relative, and both = the central difference within its error.
fn agree(source: &str, objective: &str, wrt: &str) {
    let scene = compile(source).unwrap();
    let (r, f) = (grad(&scene, objective, wrt, Method::Reverse), grad(&scene, objective, wrt, Method::Forward));
    assert_eq!(r.value.to_bits(), f.value.to_bits(), "{objective}: the two passes ran different trajectories");
    let scale = r.gradient.iter().fold(0.0f64, |a, g| a.max(g.1.abs()));
    for ((name, a), (_, b)) in r.gradient.iter().zip(&f.gradient) {
        assert!((a - b).abs() <= 1e-10 * scale.max(1e-300), "{objective} ∂/∂{name}: reverse {a} vs forward {b}");
    }
    for ((name, a), (fd, err)) in r.gradient.iter().zip(differences(&scene, objective, wrt)) {
        assert!(
            (a - fd).abs() <= err.max(1e-7 * scale),
            "{objective} ∂/∂{name}: reverse {a} vs central difference {fd} ± {err}"
        );
    }
}

#[test]
fn a_damped_oscillator() {
    let osc = "scene o { entity { position: [-1.35, 0, 0], mass: 1 } entity { position: [1.35, 0.1, 0], velocity: [0, 0.2, 0], mass: 1.5 }
        bond harmonic [0, 1] { k: 2, r0: 2, damping: 0.04 } solver { dt: 0.01, steps: 300, steps_per_frame: 7 } }";
    agree(osc, "position[1].x@end", "harmonic.k,harmonic.r0,harmonic.damping,body[1].mass,body[0].velocity");
    agree(osc, "energy@sum", "harmonic.k,body[0].position.x,body[1].mass");
    agree(osc, "distance[0,1]@end", "harmonic.r0,body[1].velocity.y");
}

#[test]
fn an_orbit() {
    let kepler = "scene k { entity { position: [-0.15, 0, 0], velocity: [0, -0.0577, 0], mass: 0.9 }
        entity { position: [1.35, 0, 0], velocity: [0, 0.5196, 0], mass: 0.1 }
        interaction gravity { G: 1 } solver { dt: 0.002, steps: 500 } }";
    agree(kepler, "position[1].y@end", "gravity.G,body[0].mass,body[1].position.x");
    agree(kepler, "kinetic@end", "gravity.G,body[1].mass");
    agree(kepler, "potential@sum", "gravity.G,body[0].mass");
}

#[test]
fn a_charge_in_fields() {
    let charge = "scene c { entity { position: [0, 0, 0], velocity: [1, 0, 0.2], mass: 1, charge: 1 }
        magnetic { B: [0, 0.3, 2] } electric { E: [0.1, 0, 0.05] } drag { gamma: 0.1 }
        solver { dt: 0.005, steps: 400 } }";
    agree(charge, "position[0].x@end", "magnetic.B,electric.E.x,drag.gamma,body[0].charge,body[0].mass");
    agree(charge, "velocity[0].y@sum", "magnetic.B.z,body[0].velocity.x");
}

#[test]
fn bonds_angles_and_a_trap() {
    let molecule = "scene m { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.1, 0.1, 0], mass: 2 }
        entity { position: [1.6, 1.0, 0.2], mass: 1 } entity { position: [2.7, 1.2, -0.3], mass: 1.5 }
        bond morse [0, 1] { D: 1, a: 1.5, r0: 1 } bond fene [1, 2] { k: 30, R0: 1.5 }
        bond angle [0, 1, 2] { k: 3, theta0: 1.9 } bond dihedral [0, 1, 2, 3] { k: 0.5, n: 3, phase: 0.2 }
        trap { k: 0.5, center: [1, 0.5, 0] } solver { dt: 0.002, steps: 300 } }";
    agree(molecule, "energy@end", "morse.D,morse.a,fene.k,angle.theta0,dihedral.k,dihedral.phase,trap.center.y");
    agree(molecule, "position[3].z@end", "angle.k,body[2].mass,body[3].velocity");
}

/// 108 Lennard-Jones atoms in a periodic box (a Verlet list, rebuilt during the run, and pairs
/// crossing the cutoff): the force-shifted potential's force is continuous at the cutoff, so the
/// run is differentiable and the central difference agrees. The two modes agree for the plain
/// and shifted potentials too (their force jumps at the cutoff: the derivative is that of the
/// smooth pieces, which a central difference sees only while no pair crosses in between).
/// 108 atoms of a liquid held by `term` (cut off at 1.8), 60 steps: several list rebuilds.
fn liquid(term: &str) -> String {
    format!(
        "scene l {{ entity atom {{ mass: 1 }} lattice {{ type: atom, density: 0.8442, cells: [3, 3, 3], temperature: 1.5, seed: 4 }}
           interaction {term} {{ epsilon: 1, sigma: 1, cutoff: 1.8 }} solver {{ dt: 0.005, steps: 60 }} }}"
    )
}

#[test]
fn a_liquid_through_list_rebuilds_and_cutoffs() {
    let scene = compile(&liquid("lj_force_shifted")).unwrap();
    let r = grad(&scene, "energy@end", "lj_force_shifted.epsilon", Method::Reverse);
    let g = LagrangianGraph::new(&scene.model);
    assert!(g.plan()[0].1.starts_with("cluster-pair list"), "{:?}", g.plan());
    agree(
        &liquid("lj_force_shifted"),
        "position[5].x@end",
        "lj_force_shifted.epsilon,lj_force_shifted.sigma,body[5].velocity.x",
    );
    assert!(r.gradient[0].1.is_finite());
    for term in ["lj", "lj_shifted"] {
        let scene = compile(&liquid(term)).unwrap();
        let wrt = format!("{term}.epsilon,{term}.sigma");
        let (a, b) =
            (grad(&scene, "kinetic@end", &wrt, Method::Reverse), grad(&scene, "kinetic@end", &wrt, Method::Forward));
        for (x, y) in a.gradient.iter().zip(&b.gradient) {
            assert!((x.1 - y.1).abs() <= 1e-10 * x.1.abs().max(y.1.abs()), "{term}: {x:?} vs {y:?}");
        }
    }
    // the energy at the end, whose gradient goes through the list with the jets' ∂V/∂p (the
    // cut-off's too, which moves the shifted and force-shifted energies); the two modes share
    // it, so the central difference is what holds it
    for (term, cut) in [("lj", true), ("lj_shifted", true), ("lj_force_shifted", true), ("wca", false)] {
        let (text, wrt) = match cut {
            true => (liquid(term), format!("{term}.epsilon,{term}.sigma,{term}.cutoff")),
            false => (liquid(term).replace(", cutoff: 1.8", ""), format!("{term}.epsilon,{term}.sigma")),
        };
        agree(&text, "energy@end", &wrt);
    }
}

/// Walking back through segments replayed from their checkpoints, past the list's rebuilds,
/// each state's pairs are read from the list the run read them from (built where the run's
/// was): the backward pass is the transpose of the run's own arithmetic, not of a list that
/// merely holds the same pairs.
#[test]
fn the_backward_pass_reads_each_state_from_the_runs_own_list() {
    let scene = compile(&liquid("lj")).unwrap();
    let objective = Objective::parse("energy@end", &scene).unwrap();
    let run =
        Run::new(&Request { scene: &scene, objective: &objective, wrt: &[], threads: 1, progress: None }).unwrap();
    let (g, segment) = (&run.graph, 8);
    let mut s = run.start();
    let mut st = Stepper::new(Integrator::VelocityVerlet, scene.solver.settings, g, &s).unwrap();
    let (mut read, mut checkpoints) = (vec![g.lists_built_at()], vec![]);
    while s.step < run.steps {
        if s.step.is_multiple_of(segment) {
            checkpoints.push(Checkpoint { state: s.clone(), at: st.evaluated().clone(), lists: g.keep() });
        }
        st.step(g, &mut s, run.dt).unwrap();
        read.push(g.lists_built_at());
    }
    let lists = 1 + read.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(lists >= 4, "the run rebuilds its list inside segments: {lists} lists");
    let mut replayed = Replayed { states: vec![], checkpoint: None, built: vec![], current: None.into() };
    for step in (0..=run.steps).rev() {
        replayed.go_to(&run, &checkpoints, segment, step).unwrap();
        assert!(
            g.lists_built_at() == read[step as usize],
            "step {step}: the graph holds a list the run did not read there"
        );
    }
}

/// Through a list cut into several pieces (6,912 atoms: 3 pieces), the reverse gradient is the
/// same bits on 1, 2 and 3 threads and agrees with forward mode to 1e-10.
#[test]
fn a_big_liquid_gives_the_same_gradient_on_any_number_of_threads() {
    let scene = compile(
        "scene l { entity atom { mass: 1 } lattice { type: atom, density: 0.8442, cells: [12, 12, 12], temperature: 1.5, seed: 4 }
           interaction lj_force_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 } solver { dt: 0.005, steps: 12 } }",
    )
    .unwrap();
    let wrt = "lj_force_shifted.epsilon,lj_force_shifted.sigma,lj_force_shifted.cutoff,body[7].position.y";
    let on = |threads: usize| {
        let g = grad_on(&scene, "position[3].x@end", wrt, Method::Reverse, threads);
        g.gradient.iter().map(|g| g.1.to_bits()).collect::<Vec<_>>()
    };
    let one = on(1);
    assert!(on(2) == one && on(3) == one);
    let (g, s) = (LagrangianGraph::new(&scene.model), lagra_kernel::setup::start(&scene));
    g.forces(&s, &mut vec![[0.0; 3]; s.x.len()]).unwrap();
    assert!(g.plan()[0].1.contains(" 3 piece(s)"), "{:?}", g.plan());
    let forward = grad(&scene, "position[3].x@end", wrt, Method::Forward);
    let scale = forward.gradient.iter().fold(0.0f64, |a, g| a.max(g.1.abs()));
    for (a, b) in one.iter().zip(&forward.gradient) {
        let a = f64::from_bits(*a);
        assert!((a - b.1).abs() <= 1e-10 * scale, "∂/∂{}: reverse {a} vs forward {}", b.0, b.1);
    }
}

/// 16,384 atoms, enough that the passes between pullbacks (`kicks`) spread over the threads: the
/// same bits on 1 and 3 threads, masses' adjoints and the energy's pullback through the list's
/// pieces included, and forward mode's values to 1e-10.
#[test]
fn the_passes_between_pullbacks_spread_with_the_same_bits() {
    let scene = compile(
        "scene l { entity atom { mass: 1 } lattice { type: atom, density: 0.8442, cells: [16, 16, 16], temperature: 1.5, seed: 4 }
           interaction lj_force_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 } solver { dt: 0.005, steps: 6 } }",
    )
    .unwrap();
    assert_eq!(scene.x0.len(), 16_384);
    let wrt = "lj_force_shifted.epsilon,lj_force_shifted.cutoff,body[5].mass";
    let on = |threads: usize| grad_on(&scene, "energy@end", wrt, Method::Reverse, threads);
    let (one, three) = (on(1), on(3));
    let bits = |g: &Gradient| g.gradient.iter().map(|g| g.1.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&three));
    assert_eq!(one.growth.factor.to_bits(), three.growth.factor.to_bits());
    let forward = grad(&scene, "energy@end", wrt, Method::Forward);
    for (a, b) in one.gradient.iter().zip(&forward.gradient) {
        assert!((a.1 - b.1).abs() <= 1e-10 * b.1.abs(), "∂/∂{}: reverse {} vs forward {}", b.0, a.1, b.1);
    }
}

/// A chaotic run: the adjoint grows like e^{λt}, and the report says by how much.
#[test]
fn a_chaotic_run_reports_its_growth() {
    let scene = compile(
        "scene l { entity atom { mass: 1 } lattice { type: atom, density: 0.8442, cells: [3, 3, 3], temperature: 2.5, seed: 9 }
           interaction lj_force_shifted { epsilon: 1, sigma: 1, cutoff: 1.8 } solver { dt: 0.005, steps: 3000 } }",
    )
    .unwrap();
    let r = grad(&scene, "position[0].x@end", "lj_force_shifted.epsilon", Method::Reverse);
    assert!(r.growth.alarming() && r.growth.rate_per_time > 0.5, "{:?}", r.growth);
    let short = compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 4, r0: 1 } solver { dt: 0.01, steps: 100 } }",
    )
    .unwrap();
    assert!(!grad(&short, "position[1].x@end", "harmonic.k", Method::Reverse).growth.alarming());
}

/// Memory: the reverse pass keeps about 2√N states, not N.
#[test]
fn reverse_mode_keeps_about_two_root_n_states() {
    let scene = compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 4, r0: 1 } solver { dt: 0.001, steps: 10000 } }",
    )
    .unwrap();
    let r = grad(&scene, "position[1].x@end", "harmonic.k", Method::Reverse);
    assert!(r.states_kept <= 2 * 100 + 2, "{}", r.states_kept);
}

#[test]
fn other_integrators_are_refused() {
    let scene = compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 4, r0: 1 } solver { integrator: \"rk4\", dt: 0.01, steps: 10 } }",
    )
    .unwrap();
    let objective = Objective::parse("position[1].x@end", &scene).unwrap();
    let wrt = params::parse_list("harmonic.k", &scene).unwrap();
    let e = gradient(
        Request { scene: &scene, objective: &objective, wrt: &wrt, threads: 1, progress: None },
        Method::Reverse,
    )
    .unwrap_err();
    assert_eq!(e, "gradients go through velocity_verlet steps; this scene's solver is rk4");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random small scenes: two or three bodies, a spring, a pair term and a field, random
    /// parameters and start; reverse = forward to 1e-10.
    #[test]
    fn random_small_scenes(
        k in 0.5f64..5.0, r0 in 0.8f64..1.5, g in 0.1f64..2.0, eps in 0.1f64..1.0,
        x in prop::array::uniform3(-0.3f64..0.3), v in prop::array::uniform3(-0.5f64..0.5),
        m in 0.5f64..3.0, three in any::<bool>(), objective in 0usize..4,
    ) {
        let third = if three { "entity { position: [0.2, 1.4, 0.3], mass: 1.2 } bond harmonic [1, 2] { k: 1.5, r0: 1.2 }" } else { "" };
        let source = format!(
            "scene p {{ entity {{ position: [0, 0, 0], mass: 1 }} entity {{ position: [{}, {}, {}], velocity: [{}, {}, {}], mass: {m} }} {third}
               bond harmonic [0, 1] {{ k: {k}, r0: {r0} }} interaction gravity {{ G: {g} }} interaction yukawa {{ k: {eps}, range: 1.5 }}
               well {{ G: 0.5, M: 1, center: [3, 3, 3] }} solver {{ dt: 0.01, steps: 150 }} }}",
            1.1 + x[0], x[1], x[2], v[0], v[1], v[2]
        );
        let scene = compile(&source).unwrap();
        let objective = ["position[1].x@end", "energy@end", "kinetic@sum", "distance[0,1]@end"][objective];
        let wrt = "harmonic#0.k,harmonic#0.r0,gravity.G,yukawa.k,yukawa.range,well.center.x,body[1].mass,body[1].velocity";
        let (a, b) = (grad(&scene, objective, wrt, Method::Reverse), grad(&scene, objective, wrt, Method::Forward));
        let scale = a.gradient.iter().fold(1e-300f64, |s, g| s.max(g.1.abs()));
        for (x, y) in a.gradient.iter().zip(&b.gradient) {
            prop_assert!((x.1 - y.1).abs() <= 1e-10 * scale, "{objective} ∂/∂{}: {} vs {}", x.0, x.1, y.1);
        }
    }
}

/// SPH, a density term: a 3×3×3 block of fluid slumping onto a floor against a wall, its
/// artificial viscosity on (the pairs it finds change along the run). The bodies start stirred:
/// at rest, every pair would sit on the viscosity's switch (it acts on approaching pairs only),
/// where the objective has a kink and a central difference no derivative to agree with.
#[test]
fn a_slumping_fluid() {
    let mut entities = String::new();
    for k in 0..27 {
        let at = [k % 3, (k / 3) % 3, k / 9].map(|i| 0.5 + i as f64);
        let v = [(1.3 * k as f64).sin(), (2.1 * k as f64).cos(), (0.7 * k as f64).sin()].map(|c| 0.1 * c);
        entities += &format!(
            "entity {{ position: [{}, {}, {}], velocity: [{}, {}, {}], mass: 1 }}\n",
            at[0], at[1], at[2], v[0], v[1], v[2]
        );
    }
    let scene = format!(
        "scene s {{ {entities} sph {{ h: 1.3, rest_density: 0.9, sound_speed: 10, alpha: 0.1, beta: 0.2 }}
        wall {{ normal: [0, 1, 0], offset: 0, k: 400 }} wall {{ normal: [1, 0, 0], offset: 0, k: 400 }}
        gravity {{ g: [0, -1, 0] }} solver {{ dt: 0.01, steps: 200 }} }}"
    );
    agree(&scene, "energy@end", "sph.sound_speed,sph.alpha,sph.h,sph.beta,body[0].velocity.x,body[4].mass");
    agree(&scene, "position[26].x@end", "sph.sound_speed,sph.alpha,sph.rest_density,sph.gamma");
}

/// Every shipped scene that velocity Verlet runs (100 steps of it): reverse = forward to 1e-10
/// for every parameter of the first declaration of each of its terms, and both = the central
/// difference within its own error. (Scenes with another integrator have no gradient: RATTLE and
/// Boris steps are not differentiated.)
#[test]
fn every_shipped_scene_with_a_parameter() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "lagra") {
            continue;
        }
        let mut scene = compile(&std::fs::read_to_string(&path).unwrap()).unwrap();
        // a gradient of energy@end along body 0's velocity, refused: why
        let refusal = |scene: &Scene| {
            let objective = Objective::parse("energy@end", scene).unwrap();
            let wrt = params::parse_list("body[0].velocity.x", scene).unwrap();
            let request = Request { scene, objective: &objective, wrt: &wrt, threads: 1, progress: None };
            gradient(request, Method::Reverse).map(|_| ()).unwrap_err()
        };
        if scene.solver.integrator != Integrator::VelocityVerlet
            || !scene.model.constraints.is_empty()
            || scene.thermostat.is_some()
        {
            if scene.thermostat.is_some() {
                let refused = refusal(&scene);
                assert!(refused.contains("thermostat"), "{}: {refused}", path.display());
            }
            continue;
        }
        // (the dam break's 2,304 particles would take a minute of differences here: its fluid is
        // `a_slumping_fluid` above, the scene itself goes through the binary's check mode in
        // tests/end_to_end/grad.rs)
        if scene.model.terms.iter().any(|t| t.kind.spec().shape == lagra_checker::terms::Shape::Density) {
            continue;
        }
        scene.solver.steps = scene.solver.steps.min(100);
        let mut keywords: Vec<&str> = vec![];
        let mut wrt = vec![];
        for t in &scene.model.terms {
            let keyword = t.kind.spec().keyword;
            if keywords.contains(&keyword) {
                continue;
            }
            keywords.push(keyword);
            let declared = scene.model.terms.iter().filter(|u| u.kind.spec().keyword == keyword).count();
            let head = if declared > 1 { format!("{keyword}#0") } else { keyword.to_string() };
            wrt.extend(
                t.kind.spec().params.iter().filter(|p| p.name != "cutoff").map(|p| format!("{head}.{}", p.name)),
            );
        }
        wrt.push("body[0].velocity.x".into());
        let wrt = wrt.join(",");
        let (r, f) =
            (grad(&scene, "energy@end", &wrt, Method::Reverse), grad(&scene, "energy@end", &wrt, Method::Forward));
        let scale = r.gradient.iter().fold(1e-300f64, |a, g| a.max(g.1.abs()));
        for ((name, a), (_, b)) in r.gradient.iter().zip(&f.gradient) {
            assert!((a - b).abs() <= 1e-10 * scale, "{}: ∂/∂{name}: reverse {a} vs forward {b}", path.display());
        }
        for ((name, a), (fd, err)) in r.gradient.iter().zip(differences(&scene, "energy@end", &wrt)) {
            assert!(
                (a - fd).abs() <= err.max(1e-7 * scale),
                "{}: ∂/∂{name}: reverse {a} vs difference {fd} ± {err}",
                path.display()
            );
        }
        seen += 1;
    }
    assert!(seen >= 12, "{seen} scenes");
}
