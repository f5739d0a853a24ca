//! `lagra bench summation`: what compensated summation buys on the 32,000-atom LJ benchmark.
//! The energy and momentum witnesses are sums of ~10⁶ terms (a kinetic term per atom, a
//! potential term per pair within the cutoff); each term is evaluated once in binary64 and the
//! same terms are added three ways — in order (plain), by the kernel's `Sum` (Neumaier), and
//! exactly (MPFR with enough bits to hold every sum of binary64 numbers) — so the differences
//! are summation error alone, at the first and the last state of a run.

use lagra_checker::broad_phase;
use lagra_checker::model::{Cell, Model};
use lagra_checker::terms::{Shape, Site};
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::Stepper;
use lagra_kernel::state::State;
use lagra_kernel::sum::Sum;
use lagra_lang::integrator::Integrator;
use lagra_run::compile;
use rug::Float;
use serde::Serialize;

const SCENE: &str = "scenes/bench/lj_32k_shifted.lagra";
/// The scene itself, built into the binary so the study runs from anywhere.
const TEXT: &str = include_str!("../scenes/bench/lj_32k_shifted.lagra");

/// Enough bits that adding binary64 numbers (exponents −1074 … 1023) never rounds.
const EXACT_BITS: u32 = 2200;

/// One witness summed three ways.
#[derive(Serialize, Clone, Copy)]
pub struct Sums {
    pub plain: f64,
    pub compensated: f64,
    /// The exact sum of the same binary64 terms, rounded once.
    pub exact: f64,
}

impl Sums {
    fn of(terms: &[f64]) -> Sums {
        let mut exact = Float::with_val(EXACT_BITS, 0);
        terms.iter().for_each(|&t| exact += t);
        Sums {
            plain: terms.iter().sum(),
            compensated: terms.iter().copied().collect::<Sum>().value(),
            exact: exact.to_f64(),
        }
    }
    fn plain_error(&self) -> f64 {
        (self.plain - self.exact).abs()
    }
    fn compensated_error(&self) -> f64 {
        (self.compensated - self.exact).abs()
    }
}

#[derive(Serialize)]
pub struct Witnesses {
    pub step: u64,
    pub terms: usize,
    pub energy: Sums,
    pub momentum_x: Sums,
}

/// The energy's terms (½mv² per body, then every instance of every term; pair terms over the
/// pairs within reach, nearest image) and the x-momentum's (m vₓ per body), in binary64.
fn witnesses(model: &Model, s: &State) -> Witnesses {
    let site = |i: usize| {
        let b = &model.bodies[i];
        Site { x: s.x[i], v: s.v[i], m: b.mass, q: b.charge, colour: b.colour }
    };
    // body j as seen from body i: its nearest periodic image
    let seen = |i: usize, j: usize| {
        let d = Cell::image(&model.cell, std::array::from_fn(|a| s.x[j][a] - s.x[i][a]));
        Site { x: std::array::from_fn(|a| s.x[i][a] + d[a]), ..site(j) }
    };
    let mut energy: Vec<f64> =
        (0..s.x.len()).map(|i| 0.5 * model.bodies[i].mass * s.v[i].iter().map(|c| c * c).sum::<f64>()).collect();
    for t in &model.terms {
        let v = |sites: &[Site<f64>]| t.kind.potential(&t.params, &sites.iter().collect::<Vec<_>>());
        match t.kind.spec().shape {
            Shape::Pairwise => {
                // the pairs within reach (the others add exact zeros)
                let pairs =
                    broad_phase::within(&s.x, &model.cell, Some(t.kind.reach(&t.params)).filter(|r| r.is_finite()));
                energy.extend(pairs.iter().map(|p| v(&[site(p.i), seen(p.i, p.j)])));
            }
            Shape::Bond(_) => energy.push(v(&t.sites.iter().map(|&j| seen(t.sites[0], j)).collect::<Vec<_>>())),
            Shape::External if t.sites.is_empty() => energy.extend((0..s.x.len()).map(|i| v(&[site(i)]))),
            Shape::External => energy.extend(t.sites.iter().map(|&i| v(&[site(i)]))),
            Shape::Density => {
                // each body's internal energy at the density its pairs within reach give it
                let share = |a: &Site<f64>, b: &Site<f64>| t.kind.density(&t.params, a, b).unwrap_or(0.0);
                let mut rho: Vec<f64> = (0..s.x.len()).map(|i| share(&site(i), &site(i))).collect();
                for p in broad_phase::within(&s.x, &model.cell, Some(t.kind.reach(&t.params))) {
                    rho[p.i] += share(&site(p.i), &seen(p.i, p.j));
                    rho[p.j] += share(&seen(p.i, p.j), &site(p.i));
                }
                energy.extend(rho.iter().enumerate().filter_map(|(i, &r)| t.kind.internal(&t.params, &site(i), r)));
            }
        }
    }
    let momentum: Vec<f64> = (0..s.x.len()).map(|i| model.bodies[i].mass * s.v[i][0]).collect();
    Witnesses { step: s.step, terms: energy.len(), energy: Sums::of(&energy), momentum_x: Sums::of(&momentum) }
}

#[derive(Serialize)]
pub struct Study {
    pub scene: &'static str,
    pub start: Witnesses,
    pub end: Witnesses,
}

pub fn study(steps: u64) -> Result<Study, String> {
    let scene = compile(TEXT).map_err(|d| d.render(SCENE, TEXT).to_string())?;
    let graph = LagrangianGraph::new(&scene.model);
    let mut s = lagra_kernel::setup::start(&scene);
    let start = witnesses(&scene.model, &s);
    let mut stepper = Stepper::new(Integrator::VelocityVerlet, Integrator::VelocityVerlet.defaults(), &graph, &s)
        .map_err(|e| e.to_string())?;
    for _ in 0..steps {
        stepper.step(&graph, &mut s, scene.solver.dt).map_err(|e| e.to_string())?;
    }
    Ok(Study { scene: SCENE, start, end: witnesses(&scene.model, &s) })
}

impl Study {
    pub fn render(&self) -> String {
        let (a, b) = (&self.start, &self.end);
        let drift = |f: fn(&Sums) -> f64, w: fn(&Witnesses) -> Sums| f(&w(b)) - f(&w(a));
        let row = |name: &str, w: fn(&Witnesses) -> Sums| {
            let exact = drift(|s| s.exact, w);
            format!(
                "{name:<10} | {:>9.1e} | {:>9.1e} | {:>9.1e} | {:>9.1e} | {:>12.4e} | {:>9.1e} | {:>9.1e}\n",
                w(a).plain_error(),
                w(a).compensated_error(),
                w(b).plain_error(),
                w(b).compensated_error(),
                exact,
                (drift(|s| s.plain, w) - exact).abs(),
                (drift(|s| s.compensated, w) - exact).abs(),
            )
        };
        format!(
            "{}: {} terms in the energy, summation error alone (against the exact sum of the same terms)\n\
             witness    | plain @{:<3}| comp. @{:<3}| plain @{:<3}| comp. @{:<3}| exact drift  | plain err | comp. err\n{}{}",
            self.scene,
            a.terms,
            a.step,
            a.step,
            b.step,
            b.step,
            row("energy", |w| w.energy),
            row("momentum_x", |w| w.momentum_x),
        )
    }
}
