//! Reverse mode: the discrete adjoint, the exact transpose of each velocity Verlet step run
//! backwards from the last state. The forward pass keeps a checkpoint every K = ⌈√N⌉ steps and
//! the backward pass replays one segment at a time from it (memory O(√N) states, the forward run
//! paid twice), with the neighbour lists as they were, so the replay is the same bits as the run.

use super::{collect, failed, kicks, settled, Growth, Objective, Outcome, Run};
use lagra_kernel::forces::derivative::Adjoint;
use lagra_kernel::forces::Kept;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::{Evaluated, Stepper};
use lagra_kernel::spread;
use lagra_kernel::state::State;
use lagra_lang::integrator::Integrator;
use lagra_lang::params::Named;

/// Reverse mode: the forward pass with checkpoints, then the adjoint backwards a segment at a
/// time.
pub(super) fn reverse(
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
    let growth = Growth::over(largest, n as f64 * dt);
    Ok((value, collect(wrt, &lam), growth, checkpoints.len() + segment as usize + 1))
}

/// A state the forward pass kept: with its forces and the neighbour lists as they were.
pub(super) struct Checkpoint {
    pub(super) state: State,
    pub(super) at: Evaluated,
    pub(super) lists: Vec<Option<Kept>>,
}

/// One segment's states, replayed from its checkpoint, and the lists each state's pairs were
/// read from: its checkpoint's, then each one the replay built, with the first step it served.
pub(super) struct Replayed<'c> {
    pub(super) states: Vec<(State, Evaluated)>,
    pub(super) checkpoint: Option<&'c Checkpoint>,
    pub(super) built: Vec<(u64, Vec<Option<Kept>>)>,
    /// Which lists the graph holds (0 the checkpoint's, k the k-th of `built`), and its build
    /// count then (a rebuild since changes it).
    pub(super) current: std::cell::Cell<Option<(usize, u64)>>,
}

impl<'c> Replayed<'c> {
    /// The segment that holds `step` and the step before it replayed, if it is not already,
    /// and the lists the run read at `step` put back.
    pub(super) fn go_to(
        &mut self,
        run: &Run,
        checkpoints: &'c [Checkpoint],
        segment: u64,
        step: u64,
    ) -> Result<(), String> {
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
        let done = settled(&next, &mu);
        mu = next;
        if done {
            return Ok(mu);
        }
    }
    Err(format!("the adjoint of the implicit closing kick at step {} did not converge (the time step is too large for the velocity-dependent forces)", s.step))
}
