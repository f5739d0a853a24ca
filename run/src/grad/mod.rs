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

mod kicks;
mod objective;

pub use objective::{Objective, Quantity};

use lagra_kernel::forces::derivative::{Adjoint, Direction, Wanted};
use lagra_kernel::forces::Kept;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::{Evaluated, Stepper};
use lagra_kernel::spread;
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
        Method::Reverse => reverse(&run, r.objective, r.wrt, &mut tell),
        Method::Forward => forward(&run, r.objective, r.wrt, &mut tell),
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

/// Reverse mode: the forward pass with checkpoints, then the adjoint backwards a segment at a
/// time.
fn reverse(
    run: &Run,
    objective: &Objective,
    wrt: &[Named],
    tell: &mut dyn FnMut(&str, u64, u64),
) -> Result<Outcome, String> {
    let (g, n, dt) = (&run.graph, run.steps, run.dt);
    let segment = ((n as f64).sqrt().ceil() as u64).max(1);
    let mut s = run.start();
    let mut st =
        Stepper::new(Integrator::VelocityVerlet, run.scene.solver.settings, g, &s).map_err(|e| e.to_string())?;
    let mut checkpoints: Vec<Checkpoint> = vec![];
    let mut value = 0.0;
    loop {
        value += run.value(objective, &s, st.potential());
        if s.step == n {
            break;
        }
        if s.step.is_multiple_of(segment) {
            let (state, at) = copied(g, &s, st.evaluated());
            checkpoints.push(Checkpoint { state, at, lists: g.keep() });
        }
        st.step(g, &mut s, dt).map_err(failed(s.step + 1))?;
        tell("forward", s.step, n);
    }
    // the adjoint of the last state, then back one state at a time
    let mut lam = run.zero();
    run.objective_gradient(objective, &s, &mut lam)?;
    let (start_norm, mut largest) = (kicks::norm(g, &lam).max(f64::MIN_POSITIVE), 1.0f64);
    let mut scratch = kicks::Scratch::new(run);
    let mut opening = vec![[0.0; 3]; s.x.len()];
    let mut replayed = Replayed { states: vec![], checkpoint: None, built: vec![], current: None.into() };
    let velocity = g.velocity_dependent();
    for step in (0..=n).rev() {
        replayed.go_to(run, &checkpoints, segment, step)?;
        let (state, at) = replayed.find(step);
        // the opening kick of step `step` at this state, with the covector (h/m)·b
        if velocity && step < n {
            let mut pb = run.zero();
            g.pullback(state, &run.kick(&opening), &run.wanted, &mut pb).map_err(|e| e.to_string())?;
            add_into(&mut lam, &pb, true);
            masses_through_kick(run, &mut lam, &at.f, &opening);
        }
        if step == 0 {
            if !velocity {
                let mut pb = run.zero();
                g.pullback(state, &run.kick(&opening), &run.wanted, &mut pb).map_err(|e| e.to_string())?;
                add_into(&mut lam, &pb, false);
                masses_through_kick(run, &mut lam, &at.f, &opening);
            }
            break;
        }
        // the closing kick of step `step − 1` and its drift
        if velocity {
            // μ with μ = λ_v + (∂F/∂v)ᵀ(h/m)μ, the covector of the kick
            let mu = implicit_adjoint(run, state, &lam.v)?;
            let mut pb = run.zero();
            g.pullback(state, &run.kick(&mu), &run.wanted, &mut pb).map_err(|e| e.to_string())?;
            add_into(&mut lam, &pb, false);
            masses_through_kick(run, &mut lam, &at.f, &mu);
            opening = mu.iter().zip(&lam.x).map(|(m, x)| std::array::from_fn(|c| m[c] + dt * x[c])).collect();
            lam.v.clone_from(&opening);
        } else {
            // the covector λ_v plus the opening kick's of the step after, then the drift
            scratch.closing_kick(run, &lam.v, &opening);
            g.pullback(state, &scratch.kicked, &run.wanted, &mut scratch.pb).map_err(|e| e.to_string())?;
            kicks::closing_and_drift(run, &mut lam, &scratch.pb, &at.f, &mut opening);
        }
        // the state before it
        replayed.lists_at(g, step - 1);
        run.objective_gradient(objective, &replayed.find(step - 1).0, &mut lam)?;
        largest = largest.max(kicks::norm(g, &lam) / start_norm);
        tell("backward", n - step + 1, n);
    }
    let time = n as f64 * dt;
    let growth = Growth { factor: largest, rate_per_time: if time > 0.0 { largest.ln() / time } else { 0.0 } };
    Ok((value, collect(wrt, &lam), growth, checkpoints.len() + segment as usize + 1))
}

/// A state the forward pass kept: with its forces and the neighbour lists as they were.
struct Checkpoint {
    state: State,
    at: Evaluated,
    lists: Vec<Option<Kept>>,
}

/// One segment's states, replayed from its checkpoint, and the lists each state's pairs were
/// read from: its checkpoint's, then each one the replay built, with the first step it served.
struct Replayed<'c> {
    states: Vec<(State, Evaluated)>,
    checkpoint: Option<&'c Checkpoint>,
    built: Vec<(u64, Vec<Option<Kept>>)>,
    /// Which lists the graph holds (0 the checkpoint's, k the k-th of `built`), and its build
    /// count then (a rebuild since changes it).
    current: std::cell::Cell<Option<(usize, u64)>>,
}

impl<'c> Replayed<'c> {
    /// The segment that holds `step` and the step before it replayed, if it is not already,
    /// and the lists the run read at `step` put back.
    fn go_to(&mut self, run: &Run, checkpoints: &'c [Checkpoint], segment: u64, step: u64) -> Result<(), String> {
        let holding = (step.saturating_sub(1) / segment) as usize;
        if self.states.first().is_none_or(|(r, _)| r.step != holding as u64 * segment) {
            replay(run, &checkpoints[holding], segment, self)?;
        }
        self.lists_at(&run.graph, step);
        Ok(())
    }

    fn find(&self, step: u64) -> &(State, Evaluated) {
        let first = self.states[0].0.step;
        &self.states[(step - first) as usize]
    }

    /// Puts back the lists the replay read at `step`, unless the graph holds them already.
    fn lists_at(&self, g: &LagrangianGraph, step: u64) {
        let Some(c) = self.checkpoint else { return };
        let k = self.built.iter().rposition(|(from, _)| *from <= step).map_or(0, |k| k + 1);
        if self.current.get() != Some((k, g.builds())) {
            g.resume(if k == 0 { &c.lists } else { &self.built[k - 1].1 });
            self.current.set(Some((k, g.builds())));
        }
    }
}

/// The states of one segment, replayed from its checkpoint with the lists as they were: the
/// same bits as the forward pass. Each list it rebuilds is saved with the step it was built at;
/// the lists it starts from are the checkpoint's, read there, not copied, and the graph is left
/// holding the last, which the backward pass reads first.
/// The states are copied into the memory the segment before held: fresh copies, each paying
/// its page faults on the run's thread, were nine tenths of the backward pass's serial time
/// (32,000 atoms: 0.32 s of 3.1 s). The copies of states and lists are passes on the graph's
/// threads (`spread::copy`): on the run's thread they were most of what was left of it
/// (lj_32k at one thread, `lagra bench gradient`: 4.0–6.0% serial before, 2.0–2.1% after).
fn replay<'c>(run: &Run, c: &'c Checkpoint, segment: u64, out: &mut Replayed<'c>) -> Result<(), String> {
    let g = &run.graph;
    let (mut s, at) = copied(g, &c.state, &c.at);
    let mut st = Stepper::resume_verlet(at);
    g.resume(&c.lists);
    let end = (s.step + segment).min(run.steps);
    let (mut states, mut held) = (std::mem::take(&mut out.states), 0);
    let mut keep = |s: &State, at: &Evaluated| {
        match states.get_mut(held) {
            Some(kept) => copy_into(g, kept, s, at),
            None => states.push(copied(g, s, at)),
        }
        held += 1;
    };
    keep(&s, &c.at);
    (out.checkpoint, out.built) = (Some(c), vec![]);
    let mut builds = g.builds();
    while s.step < end {
        st.step(g, &mut s, run.dt).map_err(failed(s.step + 1))?;
        if g.builds() != builds {
            builds = g.builds();
            out.built.push((s.step, g.keep()));
        }
        keep(&s, st.evaluated());
    }
    states.truncate(held);
    out.states = states;
    out.current.set(Some((out.built.len(), builds)));
    Ok(())
}

/// `kept` made equal to (`s`, `at`) in the memory it holds, the bodies' arrays copied on the
/// graph's threads (`spread::copy`); every field is named, so that a field added to `State` is a
/// compile error here, not a stale copy.
fn copy_into(g: &LagrangianGraph, (kept, kept_at): &mut (State, Evaluated), s: &State, at: &Evaluated) {
    let State { step, t, x, v, chain, spin } = kept;
    (*step, *t) = (s.step, s.t);
    spread::copy(g.spread(), x, &s.x);
    spread::copy(g.spread(), v, &s.v);
    chain.clone_from(&s.chain);
    spin.clone_from(&s.spin);
    let Evaluated { f, potential } = kept_at;
    spread::copy(g.spread(), f, &at.f);
    *potential = at.potential;
}

/// A copy of (`s`, `at`) in fresh memory, made as `copy_into` makes it.
fn copied(g: &LagrangianGraph, s: &State, at: &Evaluated) -> (State, Evaluated) {
    let empty = State { step: 0, t: 0.0, x: vec![], v: vec![], chain: vec![], spin: vec![] };
    let mut kept = (empty, Evaluated { f: vec![], potential: 0.0 });
    copy_into(g, &mut kept, s, at);
    kept
}

/// Adds a pullback's position, mass, charge and parameter adjoints (and its velocity ones, if
/// `velocities`) into the running adjoint.
fn add_into(lam: &mut Adjoint, pb: &Adjoint, velocities: bool) {
    for (a, b) in lam.x.iter_mut().zip(&pb.x) {
        (0..3).for_each(|c| a[c] += b[c]);
    }
    if velocities {
        for (a, b) in lam.v.iter_mut().zip(&pb.v) {
            (0..3).for_each(|c| a[c] += b[c]);
        }
    }
    lam.m.iter_mut().zip(&pb.m).for_each(|(a, b)| *a += b);
    lam.q.iter_mut().zip(&pb.q).for_each(|(a, b)| *a += b);
    for (a, b) in lam.params.iter_mut().zip(&pb.params) {
        a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
    }
}

/// The kick (h/m)·F through the mass: ∂/∂m = −(h/m²)·F·a for the covector a.
fn masses_through_kick(run: &Run, lam: &mut Adjoint, f: &[[f64; 3]], a: &[[f64; 3]]) {
    if !run.wanted.masses {
        return;
    }
    let h = 0.5 * run.dt;
    for (((m, w), f), a) in lam.m.iter_mut().zip(&run.graph.inverse_masses).zip(f).zip(a) {
        *m -= h * w * w * (f[0] * a[0] + f[1] * a[1] + f[2] * a[2]);
    }
}

/// μ = λ + (∂F/∂v)ᵀ(h/m)μ, by the iteration the forward fixed point contracts by (to the last
/// bits, or an error: the closing kick's own iteration converged there, so this one must).
fn implicit_adjoint(run: &Run, s: &State, lam: &[[f64; 3]]) -> Result<Vec<[f64; 3]>, String> {
    let mut mu = lam.to_vec();
    for _ in 0..64 {
        let mut pb = run.zero();
        run.graph.pullback(s, &run.kick(&mu), &run.wanted, &mut pb).map_err(|e| e.to_string())?;
        let next: Vec<[f64; 3]> = lam.iter().zip(&pb.v).map(|(l, p)| std::array::from_fn(|c| l[c] + p[c])).collect();
        let (change, size) = next
            .iter()
            .flatten()
            .zip(mu.iter().flatten())
            .fold((0.0f64, 0.0f64), |(d, s), (a, b)| (d.max((a - b).abs()), s.max(a.abs())));
        mu = next;
        if change <= 4.0 * f64::EPSILON * size {
            return Ok(mu);
        }
    }
    Err(format!("the adjoint of the implicit closing kick at step {} did not converge (the time step is too large for the velocity-dependent forces)", s.step))
}

/// Forward mode: one tangent sweep per parameter.
fn forward(
    run: &Run,
    objective: &Objective,
    wrt: &[Named],
    tell: &mut dyn FnMut(&str, u64, u64),
) -> Result<Outcome, String> {
    let mut out = vec![];
    let (mut value, mut largest) = (0.0, 1.0f64);
    for (k, named) in wrt.iter().enumerate() {
        let (v, d, grew) = sweep(run, objective, named.param, &mut |done, of| {
            tell(&named.name, done + k as u64 * of, of * wrt.len() as u64)
        })?;
        (value, largest) = (v, largest.max(grew));
        out.push((named.name.clone(), d));
    }
    let time = run.steps as f64 * run.dt;
    Ok((value, out, Growth { factor: largest, rate_per_time: if time > 0.0 { largest.ln() / time } else { 0.0 } }, 1))
}

/// The tangent of the state and parameters along one parameter, at the start.
struct Tangent {
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    m: Vec<f64>,
    q: Vec<f64>,
    params: Vec<Vec<f64>>,
}

impl Tangent {
    fn dir(&self) -> Direction<'_> {
        Direction { x: &self.x, v: &self.v, m: &self.m, q: &self.q, params: &self.params }
    }

    /// ⟨∇, tangent⟩ for a gradient gathered in an adjoint.
    fn dot(&self, a: &Adjoint) -> f64 {
        let d3 = |p: &[[f64; 3]], q: &[[f64; 3]]| -> f64 {
            p.iter().zip(q).map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).sum()
        };
        let d = |p: &[f64], q: &[f64]| -> f64 { p.iter().zip(q).map(|(p, q)| p * q).sum() };
        d3(&self.x, &a.x)
            + d3(&self.v, &a.v)
            + d(&self.m, &a.m)
            + d(&self.q, &a.q)
            + self.params.iter().zip(&a.params).map(|(p, q)| d(p, q)).sum::<f64>()
    }
}

/// One tangent sweep: the objective, its derivative along `p`, and how much the tangent grew.
fn sweep(
    run: &Run,
    objective: &Objective,
    p: Param,
    tell: &mut dyn FnMut(u64, u64),
) -> Result<(f64, f64, f64), String> {
    let (g, n, dt) = (&run.graph, run.steps, run.dt);
    let h = 0.5 * dt;
    let bodies = run.scene.x0.len();
    let mut t = Tangent {
        x: vec![[0.0; 3]; bodies],
        v: vec![[0.0; 3]; bodies],
        m: vec![0.0; bodies],
        q: vec![0.0; bodies],
        params: run.scene.model.terms.iter().map(|t| vec![0.0; t.params.len()]).collect(),
    };
    match p {
        Param::Term { term, index } => t.params[term][index] = 1.0,
        Param::Mass(i) => t.m[i] = 1.0,
        Param::Charge(i) => t.q[i] = 1.0,
        Param::Position(i, c) => t.x[i][c] = 1.0,
        Param::Velocity(i, c) => t.v[i][c] = 1.0,
    }
    let mut s = run.start();
    let mut st =
        Stepper::new(Integrator::VelocityVerlet, run.scene.solver.settings, g, &s).map_err(|e| e.to_string())?;
    let mut df = vec![[0.0; 3]; bodies];
    g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
    let size = |t: &Tangent| t.x.iter().chain(&t.v).flatten().map(|c| c * c).sum::<f64>().sqrt();
    let (start, mut largest) = (size(&t).max(1.0), 1.0f64);
    let (mut value, mut derivative) = (0.0, 0.0);
    loop {
        value += run.value(objective, &s, st.potential());
        if run.reads.binary_search(&s.step).is_ok() {
            let mut grad = run.zero();
            run.objective_gradient(objective, &s, &mut grad)?;
            derivative += t.dot(&grad);
        }
        if s.step == n {
            break;
        }
        // the opening kick and drift of the tangent, with the forces and their tangent here
        let f0 = st.evaluated().f.clone();
        let half: Vec<[f64; 3]> = (0..bodies)
            .map(|i| {
                let (w, dw) = (g.inverse_masses[i], -t.m[i] * g.inverse_masses[i] * g.inverse_masses[i]);
                std::array::from_fn(|c| t.v[i][c] + h * (w * df[i][c] + dw * f0[i][c]))
            })
            .collect();
        for (x, v) in t.x.iter_mut().zip(&half) {
            (0..3).for_each(|c| x[c] += dt * v[c]);
        }
        st.step(g, &mut s, dt).map_err(failed(s.step + 1))?;
        // the closing kick: δv₁ = δv½ + (h/m)δF(x₁, v₁) − (h δm/m²)F₁, a fixed point in δv₁ if
        // the forces depend on velocities
        let f1 = &st.evaluated().f;
        t.v = half.clone();
        for round in 0..64 {
            g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
            let next: Vec<[f64; 3]> = (0..bodies)
                .map(|i| {
                    let (w, dw) = (g.inverse_masses[i], -t.m[i] * g.inverse_masses[i] * g.inverse_masses[i]);
                    std::array::from_fn(|c| half[i][c] + h * (w * df[i][c] + dw * f1[i][c]))
                })
                .collect();
            let (change, size) = next
                .iter()
                .flatten()
                .zip(t.v.iter().flatten())
                .fold((0.0f64, 0.0f64), |(d, s), (a, b)| (d.max((a - b).abs()), s.max(a.abs())));
            let settled = change <= 4.0 * f64::EPSILON * size;
            t.v = next;
            if !g.velocity_dependent() || settled {
                break;
            }
            if round == 63 {
                return Err(format!("the tangent of the implicit closing kick at step {} did not converge", s.step));
            }
        }
        if g.velocity_dependent() {
            g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
        }
        largest = largest.max(size(&t) / start);
        tell(s.step, n);
    }
    Ok((value, derivative, largest))
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
