use super::exchange::{Alone, Threads};
use super::*;
use crate::run::{run, Options, Report};
use lagra_checker::certificate::Mark;
use lagra_checker::monitor::Monitor;

/// 864 Lennard-Jones atoms (`cells` 6; 6,912 at 12), hot enough that atoms cross bricks and the
/// ghosts are chosen again within the run; energy and momentum claimed every 20 steps. At 6
/// cells a brick of two is narrower than two halos (every atom is a ghost of the other rank);
/// at 12 a rank takes about half the other's atoms: a ghost missed would show.
fn liquid_of(cells: usize, steps: u64) -> Scene {
    crate::compile(&format!(
        "scene l {{ entity atom {{ mass: 1 }}
           lattice {{ type: atom, kind: fcc, density: 0.8442, cells: [{cells}, {cells}, {cells}], temperature: 2.5, seed: 5, velocities: uniform }}
           interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
           @expect energy_conservation {{ tol: 1e-3, every: 20 }}
           @expect momentum_conservation {{ every: 20 }}
           solver {{ dt: 0.005, steps: {steps} }} }}"
    ))
    .unwrap()
}

fn liquid(steps: u64) -> Scene {
    liquid_of(6, steps)
}

/// The liquid with the first two atoms of every fcc cell bonded (1.19 apart, at rest length)
/// and an angle at the first between the second and third: 1,728 bonds and angles, many across
/// bricks.
fn bonded_liquid(steps: u64, k: f64) -> Scene {
    use lagra_checker::model::TermInstance;
    use lagra_checker::terms::Kind;
    let mut scene = liquid_of(12, steps);
    let cells = scene.x0.len() / 4;
    for c in 0..cells {
        let (a, b, d) = (4 * c, 4 * c + 1, 4 * c + 2);
        let bond = TermInstance { kind: Kind::HarmonicBond, sites: vec![a, b], params: vec![k, 1.188, 0.0] };
        let angle = TermInstance {
            kind: Kind::HarmonicAngle,
            sites: vec![b, a, d],
            params: vec![2.0, std::f64::consts::FRAC_PI_3],
        };
        Arc::make_mut(&mut scene.model).terms.extend([bond, angle]);
    }
    scene
}

/// The run on `ranks` threads standing for ranks (rank 0's run loop driving), its report and
/// how often rank 0 chose its ghosts.
fn in_domains(scene: &Scene, ranks: usize, grid: Option<&str>, threads: usize) -> (Report, u64) {
    let s0 = lagra_kernel::setup::start(scene);
    std::thread::scope(|scope| {
        let mut job = Threads::job(ranks).into_iter();
        let root = job.next().unwrap();
        for ex in job {
            let s0 = s0.clone();
            scope.spawn(move || Domain::new(ex, scene, &s0, grid, threads).unwrap().follow());
        }
        let mut d = Domain::new(root, scene, &s0, grid, threads).unwrap();
        let rep = run(scene, Options { shared: Some(&mut d), ..Options::plain(None) }).unwrap();
        let regroups = d.tally.regroups;
        (rep, regroups)
    })
}

fn largest_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max)
}

#[test]
fn one_domain_steps_the_bits_of_the_one_process_run() {
    let scene = liquid(60);
    let alone = run(&scene, Options::plain(None)).unwrap();
    let mut d = Domain::new(Alone, &scene, &lagra_kernel::setup::start(&scene), None, 1).unwrap();
    let shared = run(&scene, Options { shared: Some(&mut d), ..Options::plain(None) }).unwrap();
    assert!(d.tally.regroups > 1, "the atoms moved half the skin within the run");
    assert_eq!(shared.steps, 60);
    assert_eq!(differing(&shared.state, &alone.state), 0);
    assert!(passed(&shared), "{:?}", shared.outcome.verdicts);
}

#[test]
fn two_and_four_ranks_follow_the_one_process_run_to_round_off() {
    let scene = liquid_of(12, 60);
    let alone = run(&scene, Options::plain(None)).unwrap();
    for (ranks, grid) in [(2, None), (4, None), (2, Some("1x1x2")), (3, Some("1x3x1"))] {
        let (rep, regroups) = in_domains(&scene, ranks, grid, 1);
        assert_eq!(rep.steps, 60);
        assert!(regroups > 1, "{ranks} ranks: ghosts chosen again within the run");
        assert!(passed(&rep), "{ranks} ranks: {:?}", rep.outcome.verdicts);
        // the pair forces are summed in another order: 60 steps of a liquid amplify round-off
        // (1e-16) by far less than 1e6
        let dx = largest_difference(&rep.state.x, &alone.state.x);
        let dv = largest_difference(&rep.state.v, &alone.state.v);
        assert!(dx < 1e-10 && dv < 1e-9, "{ranks} ranks {grid:?}: |Δx| {dx:e}, |Δv| {dv:e}");
        assert!(dx > 0.0, "{ranks} ranks: another summation order, so not the same bits");
        assert!(rep.solver_plan.as_deref().unwrap().starts_with("domains: "), "{:?}", rep.solver_plan);
        // energy and momentum judged from the ranks' parts at steps 20, 40 and 60, against
        // their parts at step 0
        let p = &rep.outcome.parts;
        assert_eq!((p.used, p.refused), (4, 0), "{ranks} ranks: {:?}", p.why);
    }
}

#[test]
fn a_job_gives_the_same_bits_every_time_and_on_any_number_of_threads() {
    let scene = liquid(40);
    let (a, _) = in_domains(&scene, 3, None, 1);
    let (b, _) = in_domains(&scene, 3, None, 1);
    let (c, _) = in_domains(&scene, 3, None, 2);
    assert_eq!(differing(&a.state, &b.state), 0);
    assert_eq!(differing(&a.state, &c.state), 0);
}

#[test]
fn atoms_on_top_of_each_other_across_two_bricks_stop_every_rank() {
    let mut scene = liquid(10);
    // atom 0 put where another rank's atom is: r = 0 in a pair that crosses the cut
    let owner = |x| Bricks::chosen(2, scene.model.cell.unwrap().size, 2.8).unwrap().owner(x);
    let other = (1..scene.x0.len()).find(|&i| owner(scene.x0[i]) != owner(scene.x0[0])).unwrap();
    scene.x0[0] = scene.x0[other];
    let s0 = lagra_kernel::setup::start(&scene);
    let said: Vec<String> = std::thread::scope(|scope| {
        let ranks: Vec<_> = Threads::job(2)
            .into_iter()
            .map(|ex| scope.spawn(|| Domain::new(ex, &scene, &s0, None, 1).err().expect("the forces are singular")))
            .collect();
        ranks.into_iter().map(|r| r.join().unwrap()).collect()
    });
    // the rank that holds both atoms says why; the other names it (both know, neither waits)
    assert!(said.iter().any(|m| m.contains("same point")), "{said:?}");
    assert!(said.iter().all(|m| m.contains("same point") || m.contains("could not be evaluated")), "{said:?}");
}

#[test]
fn what_the_domains_do_not_carry_is_said() {
    let open = crate::compile(
        "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1, 0, 0], mass: 1 }
           bond harmonic [0, 1] { k: 1, r0: 1 } solver { dt: 0.01, steps: 10 } }",
    )
    .unwrap();
    assert!(fits(&open).unwrap_err().contains("no box periodic"));
    let with = |kind, sites: Vec<usize>, params: Vec<f64>| {
        let mut scene = liquid(10);
        Arc::make_mut(&mut scene.model).terms.push(lagra_checker::model::TermInstance { kind, sites, params });
        fits(&scene)
    };
    use lagra_checker::terms::Kind;
    let field = with(Kind::UniformAcceleration, vec![], vec![0.0, -1.0, 0.0]);
    assert!(field.as_ref().unwrap_err().contains("UniformAcceleration"), "{field:?}");
    let damped = with(Kind::HarmonicBond, vec![0, 1], vec![1.0, 1.0, 0.5]);
    assert!(damped.as_ref().unwrap_err().contains("depends on the velocities"), "{damped:?}");
    assert!(with(Kind::HarmonicBond, vec![0, 1], vec![1.0, 1.0, 0.0]).is_ok());
    assert!(fits(&liquid(10)).is_ok());
}

fn passed(r: &Report) -> bool {
    r.outcome.verdicts.len() == 2
        && r.outcome.verdicts.iter().all(|v| matches!(v, lagra_checker::decision::Verdict::Pass(_)))
}

/// How many coordinates of two states differ in their bits (the states are too long to print).
fn differing(a: &State, b: &State) -> usize {
    let bits = |s: &State| s.x.iter().chain(&s.v).flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!((a.step, a.x.len()), (b.step, b.x.len()));
    bits(a).iter().zip(bits(b)).filter(|(p, q)| **p != *q).count()
}

#[test]
fn every_step_each_owned_atom_feels_the_force_of_the_whole_system() {
    let scene = liquid_of(12, 100);
    let mut s = lagra_kernel::setup::start(&scene);
    let whole = LagrangianGraph::new(&scene.model);
    let mut f = vec![[0.0; 3]; s.x.len()];
    std::thread::scope(|scope| {
        let mut job = Threads::job(2).into_iter();
        let root = job.next().unwrap();
        let s0 = s.clone();
        let scene = &scene;
        scope.spawn(move || Domain::new(job.next().unwrap(), scene, &s0, None, 1).unwrap().follow());
        let mut d = Domain::new(root, scene, &s, None, 1).unwrap();
        for step in 1..=100 {
            d.advance_to(&mut s, step, Asks::default()).unwrap();
            whole.forces(&s, &mut f).unwrap();
            for (k, &i) in d.owned.iter().enumerate() {
                let off = (0..3).map(|c| (d.f[k][c] - f[i][c]).abs()).fold(0.0, f64::max);
                // another order of the same pair terms: round-off, where a missed pair at the
                // cut-off would be off by its force there (0.016)
                assert!(off < 1e-11, "step {step}, atom {i}: off by {off:e}");
            }
        }
        assert!(d.tally.regroups > 2, "{}", d.tally.regroups);
    });
}

#[test]
fn bonds_and_angles_across_bricks_follow_the_one_process_run_to_round_off() {
    let scene = bonded_liquid(60, 50.0);
    let alone = run(&scene, Options::plain(None)).unwrap();
    assert!(passed(&alone));
    for ranks in [2, 4] {
        let (rep, _) = in_domains(&scene, ranks, None, 1);
        assert!(passed(&rep), "{ranks} ranks: {:?}", rep.outcome.verdicts);
        let dx = largest_difference(&rep.state.x, &alone.state.x);
        assert!(dx < 1e-10, "{ranks} ranks: |Δx| {dx:e}");
        // every bond and angle counted by one rank: the parts stood for the whole
        let p = &rep.outcome.parts;
        assert_eq!((p.used, p.refused), (4, 0), "{ranks} ranks: {:?}", p.why);
    }
    // a bond's atoms both owned elsewhere is no rank's twice: the one-rank run is the same bits
    let mut d = Domain::new(Alone, &scene, &lagra_kernel::setup::start(&scene), None, 1).unwrap();
    let one = run(&scene, Options { shared: Some(&mut d), ..Options::plain(None) }).unwrap();
    assert_eq!(differing(&one.state, &alone.state), 0);
}

#[test]
fn a_bond_stretched_beyond_the_halo_stops_every_rank_with_its_atoms_named() {
    // a bond whose rest length is ten times its length at the start pushes its atoms apart
    let mut scene = bonded_liquid(200, 50.0);
    Arc::make_mut(&mut scene.model).terms.push(lagra_checker::model::TermInstance {
        kind: lagra_checker::terms::Kind::HarmonicBond,
        sites: vec![0, 1],
        params: vec![100.0, 11.88, 0.0],
    });
    scene.claims.clear();
    let (rep, _) = in_domains(&scene, 2, None, 1);
    match rep.stop {
        Some(crate::run::Stop::Solver { message, .. }) => {
            assert!(message.contains("bonded term") && message.contains("halo"), "{message}")
        }
        s => panic!("the run went on: {s:?}"),
    }
}

#[test]
fn a_restart_made_on_two_ranks_goes_on_on_three_or_in_one_process() {
    use crate::run::Restarts;
    let scene = liquid_of(12, 60);
    let alone = run(&scene, Options::plain(None)).unwrap();
    // 30 steps on two ranks, the restart made where --until stops the run
    let s0 = lagra_kernel::setup::start(&scene);
    let restart = std::thread::scope(|scope| {
        let mut job = Threads::job(2).into_iter();
        let root = job.next().unwrap();
        let (scene, s0) = (&scene, &s0);
        scope.spawn(move || Domain::new(job.next().unwrap(), scene, s0, None, 1).unwrap().follow());
        let mut d = Domain::new(root, scene, s0, None, 1).unwrap();
        let mut write = |_| Ok(());
        let restarts = Some(Restarts { every: u64::MAX, write: &mut write });
        let opts = Options { shared: Some(&mut d), until: Some(30), restarts, ..Options::plain(None) };
        run(scene, opts).unwrap().restart.unwrap().unwrap()
    });
    assert_eq!(restart.state.step, 30);
    let file = tempfile::NamedTempFile::new().unwrap();
    restart.write(file.path()).unwrap();
    let read = || crate::restart::Restart::read(file.path()).unwrap();
    // on three ranks, from its state
    let on_three = std::thread::scope(|scope| {
        let mut job = Threads::job(3).into_iter();
        let root = job.next().unwrap();
        let (scene, s) = (&scene, &restart.state);
        for ex in job {
            scope.spawn(move || Domain::new(ex, scene, s, Some("1x3x1"), 1).unwrap().follow());
        }
        let mut d = Domain::new(root, scene, s, Some("1x3x1"), 1).unwrap();
        run(scene, Options { shared: Some(&mut d), resume: Some(read()), ..Options::plain(None) }).unwrap()
    });
    // and in one process, which takes up the forces rank 0 evaluated whole
    let in_one = run(&scene, Options { resume: Some(read()), ..Options::plain(None) }).unwrap();
    for (name, rep) in [("three ranks", &on_three), ("one process", &in_one)] {
        assert_eq!(rep.steps, 60, "{name}");
        assert!(passed(rep), "{name}: {:?}", rep.outcome.verdicts);
        let dx = largest_difference(&rep.state.x, &alone.state.x);
        assert!(dx < 1e-10, "{name}: |Δx| {dx:e} from the uninterrupted run");
    }
}

/// The hot liquid inside a thermostat: a Nosé–Hoover chain (its H′ and momentum claimed) or a
/// Langevin bath (which allows no conservation claim).
fn thermostatted(cells: usize, steps: u64, bath: &str) -> Scene {
    let claims = match bath.starts_with("nose_hoover") {
        true => "@expect energy_conservation { tol: 5e-3, every: 20 } @expect momentum_conservation { every: 20 }",
        false => "",
    };
    crate::compile(&format!(
        "scene l {{ entity atom {{ mass: 1 }}
           lattice {{ type: atom, kind: fcc, density: 0.8442, cells: [{cells}, {cells}, {cells}], temperature: 2.5, seed: 5, velocities: uniform }}
           interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
           thermostat {bath}
           {claims}
           solver {{ dt: 0.005, steps: {steps} }} }}"
    ))
    .unwrap()
}

const BATHS: [&str; 2] = ["nose_hoover { T: 1.0, tau: 0.1 }", "langevin { T: 1.0, gamma: 2, seed: 9 }"];

#[test]
fn a_thermostat_in_one_domain_steps_the_one_process_bits() {
    for bath in BATHS {
        let scene = thermostatted(6, 60, bath);
        let alone = run(&scene, Options::plain(None)).unwrap();
        let mut d = Domain::new(Alone, &scene, &lagra_kernel::setup::start(&scene), None, 1).unwrap();
        let shared = run(&scene, Options { shared: Some(&mut d), ..Options::plain(None) }).unwrap();
        assert_eq!(differing(&shared.state, &alone.state), 0, "{bath}");
        assert_eq!(shared.state.chain, alone.state.chain, "{bath}");
        // a thermostat samples the observables (every 10 steps): measured on the gathered state
        let seen = |r: &Report| serde_json::to_string(&r.observables).unwrap();
        assert!(alone.observables.as_ref().is_some_and(|o| o.kinetic_temperature.samples == 7), "{bath}");
        assert_eq!(seen(&shared), seen(&alone), "{bath}");
        assert_eq!(shared.outcome.verdicts.len(), alone.outcome.verdicts.len());
        assert!(shared.outcome.verdicts.iter().all(|v| matches!(v, lagra_checker::decision::Verdict::Pass(_))));
    }
}

#[test]
fn a_thermostat_on_several_ranks_follows_the_one_process_run_to_round_off() {
    for bath in BATHS {
        let scene = thermostatted(12, 60, bath);
        let alone = run(&scene, Options::plain(None)).unwrap();
        let chained = bath.starts_with("nose_hoover");
        assert!(!chained || alone.state.chain.iter().any(|l| l[1] != 0.0), "the chain moved");
        assert!(!chained || passed(&alone), "{:?}", alone.outcome.verdicts);
        for ranks in [2, 3] {
            let (rep, regroups) = in_domains(&scene, ranks, None, 1);
            assert!(regroups > 1, "{bath}, {ranks} ranks");
            if chained {
                assert!(passed(&rep), "{bath}, {ranks} ranks: {:?}", rep.outcome.verdicts);
                // H′ from the parts, the chain's share added on rank 0
                let p = &rep.outcome.parts;
                assert_eq!((p.used, p.refused), (4, 0), "{bath}, {ranks} ranks: {:?}", p.why);
                let dl = rep
                    .state
                    .chain
                    .iter()
                    .zip(&alone.state.chain)
                    .map(|(a, b)| (a[1] - b[1]).abs())
                    .fold(0.0, f64::max);
                assert!(dl < 1e-10, "{bath}, {ranks} ranks: the links' velocities off by {dl:e}");
            }
            // a chain's kinetic energy summed over the ranks, or an atom's noise drawn for its
            // place on its rank, would be off by far more than round-off
            let dx = largest_difference(&rep.state.x, &alone.state.x);
            let dv = largest_difference(&rep.state.v, &alone.state.v);
            assert!(dx < 1e-10 && dv < 1e-9, "{bath}, {ranks} ranks: |Δx| {dx:e}, |Δv| {dv:e}");
            let [a, b] = [&rep, &alone].map(|r| r.observables.as_ref().unwrap());
            for (p, q) in [
                (a.kinetic_temperature.mean, b.kinetic_temperature.mean),
                (a.potential_energy_per_body.mean, b.potential_energy_per_body.mean),
                (a.pressure.as_ref().unwrap().mean, b.pressure.as_ref().unwrap().mean),
            ] {
                assert!((p - q).abs() < 1e-10 * q.abs(), "{bath}, {ranks} ranks: sampled {p} against {q}");
            }
        }
    }
}

/// The marks a run on three ranks took from the ranks' parts meet the enclosures evaluated
/// whole from the same states (what `lagra check --states` re-derives), and would not if a part
/// were off by its own width; where the parts show a breach, the whole state decides it, so a
/// failure is re-derived to the bit.
#[test]
fn the_parts_enclosures_meet_the_whole_states_and_a_breach_is_judged_whole() {
    use lagra_checker::decision::{Verdict, BINARY64, PARTS};
    let scene = liquid_of(12, 60);
    let s0 = lagra_kernel::setup::start(&scene);
    let mut states: Vec<State> = vec![];
    let rep = std::thread::scope(|scope| {
        let mut job = Threads::job(3).into_iter();
        let root = job.next().unwrap();
        for ex in job {
            let (scene, s0) = (&scene, &s0);
            scope.spawn(move || Domain::new(ex, scene, s0, None, 1).unwrap().follow());
        }
        let mut d = Domain::new(root, &scene, &s0, None, 1).unwrap();
        let mut keep = |s: &lagra_checker::model::Snapshot| {
            states.push(State {
                step: s.step,
                t: s.t,
                x: s.x.to_vec(),
                v: s.v.to_vec(),
                chain: s.chain.to_vec(),
                spin: vec![],
            });
            Ok::<(), std::io::Error>(())
        };
        run(&scene, Options { shared: Some(&mut d), record: Some(&mut keep), ..Options::plain(None) }).unwrap()
    });
    assert!(passed(&rep), "{:?}", rep.outcome.verdicts);
    let mut whole = Monitor::new(scene.model.clone(), scene.claims.clone(), 60).unwrap();
    states.iter().for_each(|s| whole.observe(&s.snapshot()).unwrap());
    let derived = whole.finish().trails;
    let mut from_parts = 0;
    for (t, d) in rep.outcome.trails.iter().zip(&derived) {
        assert_eq!(t.marks.len(), d.marks.len());
        for (a, b) in t.marks.iter().zip(&d.marks) {
            assert!(a.same(b) || a.meets(b), "{:?} at step {}: {a:?} against {b:?}", t.claim, a.step);
            if a.precision == PARTS {
                from_parts += 1;
                let w = (a.hi - a.lo).max(1e-300);
                let beyond = Mark { lo: b.hi + w, hi: b.hi + 2.0 * w, ..*a };
                assert!(!beyond.meets(b), "a part off by its width would be seen");
            }
        }
    }
    assert_eq!(from_parts, 6, "energy and momentum at steps 20, 40 and 60");

    // a tolerance the liquid cannot keep: the parts show the breach, the whole state decides it
    let mut strict = scene.clone();
    strict.claims[0].tol = Some(1e-9);
    let alone = run(&strict, Options::plain(None)).unwrap();
    let (rep, _) = in_domains(&strict, 3, None, 1);
    let breach = |r: &Report| match &r.outcome.verdicts[0] {
        Verdict::Fail(b) => (b.step, b.precision),
        v => panic!("{v:?}"),
    };
    assert_eq!(breach(&alone), (20, BINARY64));
    assert_eq!(breach(&rep), (20, BINARY64), "found in the parts, decided on the whole state");
    assert_eq!(rep.outcome.parts.used, 2, "steps 0 and 20");
}
