//! Exact gradients of a run: the derivative of a scalar objective of the trajectory with respect
//! to the scene's parameters, through every step of velocity Verlet.
//!
//! Reverse mode (`reverse`, the default) is the discrete adjoint: the exact transpose of each
//! step, run backwards from the last state, with the forces' transposed derivatives from the
//! terms' definitions (`Force::pullback`). The forward pass keeps a checkpoint every
//! K = ⌈√N⌉ steps (the state, its forces and the neighbour lists as they were) and the backward
//! pass replays one segment at a time from its checkpoint, so memory is O(√N) states and the
//! forward run is paid twice. A replay starts from the saved lists, so it is the same bits as the
//! run, and it saves each list it rebuilds, so the backward pass, which visits the same states,
//! reads the pairs from the list that was current there and builds none. Forward mode (`forward`) carries tangents along the run, one sweep per parameter:
//! the cross-check.
//!
//! One step, with h = dt/2, F = F(x, v; θ, m, q):
//!   v½ = v₀ + (h/m)·F₀,   x₁ = x₀ + dt·v½,   v₁ = v½ + (h/m)·F(x₁, v₁)   (implicit in v₁ only
//!   for velocity-dependent forces, as the solver solves it).

mod forward;
mod kicks;
mod objective;
mod reverse;

pub use objective::{Objective, Quantity};

use lagra_kernel::forces::derivative::{Adjoint, Wanted};
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::Stepper;
use lagra_kernel::state::State;
use lagra_lang::integrator::Integrator;
use lagra_lang::params::{Named, Param};
use lagra_lang::Scene;
use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    Reverse,
    Forward,
}

/// How much the derivatives grew along the run: the largest ratio of the adjoint's (or a
/// tangent's) size to its size where it started, and the e-folding rate that ratio means over
/// the run's time.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Growth {
    pub factor: f64,
    pub rate_per_time: f64,
}

impl Growth {
    /// Whether the growth says the run is chaotic over its span (the gradient is exact for this
    /// floating-point trajectory, but says little about any nearby one).
    pub fn alarming(&self) -> bool {
        self.factor > 1e6
    }

    /// The largest growth `factor` seen over a run of `time`.
    fn over(factor: f64, time: f64) -> Growth {
        Growth { factor, rate_per_time: if time > 0.0 { factor.ln() / time } else { 0.0 } }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Gradient {
    pub value: f64,
    /// ∂J/∂p for each named parameter, in order.
    pub gradient: Vec<(String, f64)>,
    pub method: Method,
    pub steps: u64,
    pub growth: Growth,
    /// States kept at once (checkpoints and one segment), reverse mode.
    pub states_kept: usize,
}

/// A gradient to take: the scene, what of its run, with respect to what.
pub struct Request<'a> {
    pub scene: &'a Scene,
    pub objective: &'a Objective,
    pub wrt: &'a [Named],
    pub threads: usize,
    /// Called with the steps done (forward pass, replays, backward pass), for a progress line.
    pub progress: Option<&'a mut Tell<'a>>,
}

/// A progress callback: what is being counted, how many done, of how many.
pub type Tell<'a> = dyn FnMut(&str, u64, u64) + Send + 'a;

/// The run a gradient goes through: its graph and settings.
struct Run<'a> {
    scene: &'a Scene,
    graph: LagrangianGraph,
    dt: f64,
    steps: u64,
    reads: Vec<u64>,
    wanted: Wanted,
}

impl<'a> Run<'a> {
    fn new(r: &Request<'a>) -> Result<Run<'a>, String> {
        let scene = r.scene;
        if scene.solver.integrator != Integrator::VelocityVerlet {
            return Err(format!(
                "gradients go through velocity_verlet steps; this scene's solver is {}",
                scene.solver.integrator.name()
            ));
        }
        if let Some(t) = &scene.thermostat {
            return Err(format!(
                "gradients go through plain velocity_verlet steps; the adjoint of a {} thermostat is not built yet",
                t.name()
            ));
        }
        let graph = LagrangianGraph::with_threads(&scene.model, r.threads)?;
        let mut wanted = Wanted { params: vec![vec![]; scene.model.terms.len()], masses: false, charges: false };
        for n in r.wrt {
            match n.param {
                Param::Term { term, index } => wanted.params[term].push(index),
                Param::Mass(_) => wanted.masses = true,
                Param::Charge(_) => wanted.charges = true,
                Param::Position(..) | Param::Velocity(..) => {}
            }
        }
        let (steps, every) = (scene.solver.steps, scene.solver.steps_per_frame);
        Ok(Run { scene, graph, dt: scene.solver.dt, steps, reads: r.objective.steps(steps, every), wanted })
    }

    /// `work()` on the graph's pool where its steps spread (`spread::within`), else here, as a
    /// run's steps go: the backward pass's passes (several a step) then start on the pool, where
    /// one sent from outside wakes its workers and puts this thread to sleep until it is done.
    /// At two threads that was within the noise (lj_32k's gradient 1.255–1.324 s against
    /// 1.237–1.271 s); the wake is of every worker, so it is meant for many threads.
    fn on_pool<T: Send>(&self, work: impl FnOnce() -> T + Send) -> T {
        match self.graph.pool().filter(|_| self.graph.steps_spread()) {
            Some(pool) => lagra_kernel::spread::within(pool, work),
            None => work(),
        }
    }

    fn start(&self) -> State {
        lagra_kernel::setup::start(&self.scene)
    }

    fn value(&self, objective: &Objective, s: &State, potential: f64) -> f64 {
        if self.reads.binary_search(&s.step).is_ok() {
            objective.value(s.step, s, &self.graph.masses, potential, &self.scene.model.cell)
        } else {
            0.0
        }
    }

    fn objective_gradient(&self, objective: &Objective, s: &State, out: &mut Adjoint) -> Result<(), String> {
        if self.reads.binary_search(&s.step).is_ok() {
            objective
                .gradient(s.step, s, &self.graph, &self.scene.model.cell, &self.wanted, out)
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    fn zero(&self) -> Adjoint {
        Adjoint::zero(self.scene.x0.len(), &self.scene.model.terms)
    }

    /// (h/m)·a for each body.
    fn kick(&self, a: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let h = 0.5 * self.dt;
        a.iter().zip(&self.graph.inverse_masses).map(|(a, w)| a.map(|c| h * w * c)).collect()
    }
}

fn failed(step: u64) -> impl Fn(lagra_kernel::solvers::Failure) -> String {
    move |e| format!("the run failed at step {step}: {e}")
}

/// The gradient by the chosen method.
pub fn gradient(mut r: Request, method: Method) -> Result<Gradient, String> {
    let run = Run::new(&r)?;
    let mut progress = r.progress.take();
    let mut tell = |what: &str, done: u64, of: u64| progress.iter_mut().for_each(|p| p(what, done, of));
    let (value, gradient, growth, kept) = run.on_pool(|| match method {
        Method::Reverse => reverse::reverse(&run, r.objective, r.wrt, &mut tell),
        Method::Forward => forward::forward(&run, r.objective, r.wrt, &mut tell),
    })?;
    if !value.is_finite() {
        return Err(format!("the objective is not finite ({value}): the run left the range of binary64"));
    }
    if let Some((name, g)) = gradient.iter().find(|g| !g.1.is_finite()) {
        return Err(format!(
            "the gradient overflowed (∂J/∂{name} = {g}): the derivatives grew by more than binary64 holds along the run (by {:.1e} where they were last finite, an e-folding rate of {:.3} per unit time)",
            growth.factor, growth.rate_per_time
        ));
    }
    Ok(Gradient { value, gradient, method, steps: run.steps, growth, states_kept: kept })
}

type Outcome = (f64, Vec<(String, f64)>, Growth, usize);

/// Each named parameter's share of an adjoint (the state parameters at step 0).
fn collect(wrt: &[Named], a: &Adjoint) -> Vec<(String, f64)> {
    wrt.iter()
        .map(|n| {
            let g = match n.param {
                Param::Term { term, index } => a.params[term][index],
                Param::Mass(i) => a.m[i],
                Param::Charge(i) => a.q[i],
                Param::Position(i, c) => a.x[i][c],
                Param::Velocity(i, c) => a.v[i][c],
            };
            (n.name.clone(), g)
        })
        .collect()
}

/// Whether a fixed-point iterate `next` has settled on `last`: no component moved by more than
/// a few units in the last place of the largest (the implicit closing kick's own test).
fn settled(next: &[[f64; 3]], last: &[[f64; 3]]) -> bool {
    let (change, size) = next
        .iter()
        .flatten()
        .zip(last.iter().flatten())
        .fold((0.0f64, 0.0f64), |(d, s), (a, b)| (d.max((a - b).abs()), s.max(a.abs())));
    change <= 4.0 * f64::EPSILON * size
}

/// The objective's value on a scene, by running it (for finite differences and `lagra fit`'s
/// line search): the same arithmetic as the gradient's forward pass.
pub fn objective_value(scene: &Scene, objective: &Objective, threads: usize) -> Result<f64, String> {
    let run = Run::new(&Request { scene, objective, wrt: &[], threads, progress: None })?;
    run.on_pool(|| {
        let mut s = run.start();
        let g = &run.graph;
        let mut st =
            Stepper::new(Integrator::VelocityVerlet, scene.solver.settings, g, &s).map_err(|e| e.to_string())?;
        let mut value = 0.0;
        loop {
            value += run.value(objective, &s, st.potential());
            if s.step == run.steps {
                return Ok(value);
            }
            st.step(g, &mut s, run.dt).map_err(failed(s.step + 1))?;
        }
    })
}

#[cfg(test)]
mod tests;
