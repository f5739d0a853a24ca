//! Criterion benches: the kernel's force loop per term kind, the neighbour-list build, the
//! checker's enclosure per atom, and whole runs end to end. `cargo bench --profile release
//! --bench kernel` (as shipped, fat LTO; plain `cargo bench` builds without it, as the tests
//! are); `-- forces/` (a name filter) runs one group. Timings are per body (throughput), so kinds
//! and sizes compare.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lagra_checker::broad_phase::{within, Foreseen, Neighbourhood};
use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
use lagra_checker::monitor::Monitor;
use lagra_checker::quantities::asked_reach;
use lagra_checker::terms::{Kind, Shape};
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::neighbours::Neighbours;
use lagra_kernel::state::State;
use lagra_lang::scene::Scene;
use lagra_run::compile;
use lagra_run::run::{run, Options};
use std::hint::black_box;

/// `k³` bodies on a cubic lattice of spacing 1.1, slightly disordered, with unit masses,
/// alternating charges and colours.
fn lattice(k: usize) -> (Vec<Body>, Vec<[f64; 3]>) {
    let n = k * k * k;
    let bodies = (0..n)
        .map(|i| Body {
            mass: 1.0,
            charge: if i % 2 == 0 { 1.0 } else { -1.0 },
            colour: [0.5, 0.3 - 0.1 * (i % 3) as f64],
            moments: None,
            solid: None,
        })
        .collect();
    let x = (0..n)
        .map(|i| {
            let c = [i % k, (i / k) % k, i / (k * k)];
            std::array::from_fn(|a| 1.1 * c[a] as f64 + 0.01 * ((i * 7 + a * 13) % 11) as f64)
        })
        .collect();
    (bodies, x)
}

/// One instance of every kind, on every body (fields and pair terms) or on lattice neighbours
/// (bonds), with unit parameters but where one must be larger (FENE's R₀) or a cutoff.
fn instance(kind: Kind, n: usize) -> Vec<TermInstance> {
    let spec = kind.spec();
    let params: Vec<f64> = spec
        .params
        .iter()
        .flat_map(|p| {
            let v = match p.name {
                "R0" => 3.0,
                "cutoff" => 2.5,
                "r0" | "sigma" => 1.0,
                _ => p.default.filter(|d| *d != 0.0).unwrap_or(1.0),
            };
            std::iter::repeat_n(v, p.len)
        })
        .collect();
    match spec.shape {
        // a staircase of lattice neighbours (x, then y, then x): bonds of 1.1, angles of 90°
        Shape::Bond(arity) => {
            let k = (n as f64).cbrt().round() as usize;
            let steps = [0, 1, k + 1, k + 2];
            (0..n)
                .filter(|i| i % k + 3 <= k && (i / k) % k + 1 < k)
                .map(|i| TermInstance {
                    kind,
                    sites: steps[..arity].iter().map(|s| i + s).collect(),
                    params: params.clone(),
                })
                .collect()
        }
        _ => vec![TermInstance { kind, sites: vec![], params }],
    }
}

fn forces(c: &mut Criterion) {
    let mut group = c.benchmark_group("forces");
    let k = 8;
    let (bodies, x) = lattice(k);
    let n = bodies.len();
    group.throughput(Throughput::Elements(n as u64));
    for &kind in Kind::ALL {
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: bodies.clone(),
            terms: instance(kind, n),
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        let graph = LagrangianGraph::new(&model);
        let s = State { step: 0, t: 0.0, x: x.clone(), v: vec![[0.1, -0.2, 0.05]; n], chain: vec![], spin: vec![] };
        let mut f = vec![[0.0; 3]; n];
        group.bench_function(BenchmarkId::new(kind.name(), n), |b| {
            b.iter(|| black_box(graph.forces(black_box(&s), &mut f).expect("no singularity")))
        });
    }
    group.finish();
}

fn scene(path: &str) -> Scene {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/");
    let text = std::fs::read_to_string(format!("{file}{path}")).expect("the scene");
    compile(&text).unwrap_or_else(|d| panic!("{}", d.render(path, &text)))
}

fn neighbour_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("neighbour_build");
    let lj = scene("bench/lj_32k.lagra");
    group.throughput(Throughput::Elements(lj.x0.len() as u64));
    group.sample_size(20);
    group.bench_function("lj_32k", |b| {
        b.iter(|| {
            let mut list = Neighbours::new(&lj.model.cell, 2.5).expect("a box that takes a list");
            list.update(black_box(&lj.x0), &lj.model.cell, None);
            black_box(list.count())
        })
    });
    // the checker's own pair list, at the reach its energy sum asks for
    let reach = asked_reach(&lj.model.terms[0]);
    group.bench_function("checker_lj_32k", |b| {
        b.iter(|| black_box(within(black_box(&lj.x0), &lj.model.cell, reach).len()))
    });
    // the pairs as a checkpoint's sum takes them from the grid, in no order
    let reach = reach.expect("LJ has a cutoff");
    group.bench_function("checker_lj_32k_unordered", |b| {
        b.iter(|| {
            let near = Neighbourhood::new(black_box(&lj.x0), &lj.model.cell, Some(reach), &[]);
            let mut pairs = 0;
            near.each_unordered(0..near.parts(), |p| pairs += p.len());
            black_box(pairs)
        })
    });
    // the list made ahead of a checkpoint, and the checkpoint's pairs taken from it
    group.bench_function("checker_lj_32k_foreseen", |b| {
        b.iter(|| black_box(Foreseen::new(black_box(&lj.x0), &lj.model.cell, reach, 1).is_some()))
    });
    let ahead = [Foreseen::new(&lj.x0, &lj.model.cell, reach, 1).expect("a grid for 32,000 atoms")];
    group.bench_function("checker_lj_32k_from_foreseen", |b| {
        b.iter(|| {
            let near = Neighbourhood::new(black_box(&lj.x0), &lj.model.cell, Some(reach), &ahead);
            let mut pairs = 0;
            near.each_unordered(0..near.parts(), |p| pairs += p.len());
            black_box(pairs)
        })
    });
    group.finish();
}

/// The checker's enclosures of the energy and momentum at one checkpoint (the state observed
/// first, as the reference): what a certified run pays per checkpoint. At the start (a lattice,
/// for the 32,000 atoms) and after 100 steps, when the bodies have left their sites.
fn checker(c: &mut Criterion) {
    let mut group = c.benchmark_group("checker");
    group.sample_size(10);
    for name in ["bench/lj_32k_checked.lagra", "kepler.lagra"] {
        let s = scene(name);
        let state = State { step: 0, t: 0.0, x: s.x0.clone(), v: s.v0.clone(), chain: vec![], spin: vec![] };
        let opts = Options::plain(Some(100));
        let later = run(&s, opts).expect("the run").state;
        group.throughput(Throughput::Elements(s.x0.len() as u64));
        for (at, state) in [("reference_checkpoint", &state), ("checkpoint_at_100", &later)] {
            group.bench_function(BenchmarkId::new(at, &s.name), |b| {
                b.iter(|| {
                    let mut m = Monitor::new(s.model.clone(), s.claims.clone(), 1).expect("a valid model");
                    m.observe(black_box(&state.snapshot())).expect("no breach at the reference");
                })
            });
        }
    }
    group.finish();
}

fn end_to_end(c: &mut Criterion) {
    let mut group = c.benchmark_group("end_to_end");
    group.sample_size(10);
    for (name, steps) in [("oscillator.lagra", 5000), ("bench/lj_pair.lagra", 100_000), ("lj_liquid.lagra", 200)] {
        let s = scene(name);
        group.throughput(Throughput::Elements(steps));
        group.bench_function(BenchmarkId::new("steps", &s.name), |b| {
            b.iter(|| {
                let opts = Options::plain(Some(steps));
                black_box(run(&s, opts).expect("the run").steps)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, forces, neighbour_build, checker, end_to_end);
criterion_main!(benches);
