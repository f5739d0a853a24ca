//! The discrete action, made stationary over a window (Marsden & West 2001, "Discrete mechanics
//! and variational integrators"). Over K steps of dt from the current state (q₀, p₀),
//!
//!   S_d = Σₖ dt·L((qₖ + qₖ₊₁)/2, (qₖ₊₁ − qₖ)/dt),   L = ½ m v² − V,
//!
//! and the trajectory is the q₁…q_K at which S_d is stationary with the initial momentum held:
//! ∂S_d/∂qₖ = 0 for 0 < k < K (the discrete Euler–Lagrange equations) and p₀ = −∂S_d/∂q₀. With
//! Fₖ = F((qₖ + qₖ₊₁)/2) the force at the midpoint (the kernel's own forces), the residual is
//!
//!   rₖ = m(qₖ − qₖ₋₁)/dt + ½dt·Fₖ₋₁ − m(qₖ₊₁ − qₖ)/dt + ½dt·Fₖ,   r₀ = p₀ − m(q₁ − q₀)/dt + ½dt·F₀.
//!
//! It is descended, preconditioned by the kinetic part of the Hessian of S_d (the m/dt
//! differences, lower-triangular once the initial momentum fixes the first row, so inverted
//! exactly by a forward sweep): Q ← Q − K⁻¹ r(Q), which reads qₖ₊₁ = qₖ + (dt/m)(pₖ + ½dt·Fₖ),
//! pₖ₊₁ = pₖ + dt·Fₖ with the forces of the previous iterate. The iteration contracts by about
//! (ωK dt)² per round for a frequency ω, so a window is worth K·dt up to a fraction of a period;
//! a window whose residual does not fall to `tol` (relative to the window's largest momentum) in
//! `iterations` rounds, or stops falling, halts the run. The residual has a floor: its momenta
//! are differences of positions over dt, rounded at the size of the positions, so nothing below
//! ≈ 4u·m|q|/dt (relative to the same momentum) is meaningful; a `tol` below that floor is met at
//! the floor, and the report's worst residual says how far it went. The result is the implicit
//! midpoint rule — symplectic, second order — solved a window at a time; each round costs K
//! force evaluations, so a window costs (rounds) × a Verlet window (docs/bench measures it).
//!
//! The momenta delivered are the descent's own, pₖ₊₁ = pₖ + dt·Fₖ (equal to the discrete Legendre
//! transform m(qₖ₊₁ − qₖ)/dt + ½dt·Fₖ where the residual vanishes): pairwise forces sum to zero,
//! so total momentum is kept to rounding whatever the residual. The forces and potential
//! reported are evaluated at each state delivered.

use super::{Carried, Evaluated, Failure, Iterations, Settings, Solver, Window};
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::step::tick;
use std::collections::VecDeque;

type Vecs = Vec<[f64; 3]>;

/// A residual that sets no new low in this many rounds has stalled at the rounding floor.
const STALL: u32 = 25;

pub struct ActionDescent {
    at: Evaluated,
    settings: Settings,
    /// The states solved ahead, each (x, v), in order.
    ahead: VecDeque<(Vecs, Vecs)>,
    /// The first guess of the next window's midpoint forces: the last window's last one (at
    /// the start, the force at the initial state). Never the force at a state some caller
    /// happened to stop at, so the trajectory does not depend on where it is looked at.
    guess: Vecs,
    log: Iterations,
}

impl ActionDescent {
    pub fn new(at: Evaluated, settings: Settings) -> ActionDescent {
        let log = Iterations { what: "action windows", tol: settings.tol, ..Iterations::default() };
        let guess = at.f.clone();
        ActionDescent { at, settings, ahead: VecDeque::new(), guess, log }
    }

    /// Solves the window that starts at `s`, queueing its K states.
    fn solve(&mut self, g: &LagrangianGraph, s: &State, dt: f64) -> Result<(), Failure> {
        let k = self.settings.window as usize;
        let (n, w) = (s.x.len(), &g.inverse_masses);
        let p0: Vecs = s.v.iter().zip(&g.masses).map(|(v, m)| v.map(|c| m * c)).collect();
        let mut forces: Vec<Vecs> = vec![self.guess.clone(); k];
        let mut q: Vec<Vecs> = vec![s.x.clone(); k + 1];
        let mut mid = State { x: vec![[0.0; 3]; n], ..s.clone() };
        let (mut best, mut since, mut rounds) = (f64::INFINITY, 0, 0);
        loop {
            sweep(&mut q, &p0, &forces, w, dt);
            for j in 0..k {
                for i in 0..n {
                    mid.x[i] = std::array::from_fn(|c| 0.5 * (q[j][i][c] + q[j + 1][i][c]));
                }
                g.forces_only(&mid, &mut forces[j])?;
            }
            rounds += 1;
            let (r, floor) = residual(&q, &p0, &forces, &g.masses, dt);
            if r <= self.settings.tol.max(floor) {
                self.log.record(rounds, r);
                self.log.windows.push(Window { first_step: s.step, iterations: rounds, residual: r });
                break;
            }
            (best, since) = if r < best { (r, 0) } else { (best, since + 1) };
            if rounds >= self.settings.iterations || since >= STALL || !r.is_finite() {
                let why = if since >= STALL { "stopped falling" } else { "did not fall far enough" };
                return Err(Failure::Unconverged(format!(
                    "the action window from step {} (K = {k}): its Euler–Lagrange residual {why}: {r:.3e} after {rounds} rounds > tol {:.1e} (shorten the window or dt, or loosen tol)",
                    s.step, self.settings.tol
                )));
            }
        }
        // the states and their momenta pₖ₊₁ = pₖ + dt·Fₖ, as velocities
        let mut v = s.v.clone();
        for j in 0..k {
            crate::step::kick(&mut v, &forces[j], w, dt);
            self.ahead.push_back((q[j + 1].clone(), v.clone()));
        }
        self.guess = forces.pop().expect("a window of one step at least");
        Ok(())
    }

    /// Takes the next solved state, solving a window first if none is left.
    fn next(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        if self.ahead.is_empty() {
            self.solve(g, s, dt)?;
        }
        (s.x, s.v) = self.ahead.pop_front().expect("a solved window has states");
        Ok(())
    }
}

/// The preconditioned descent step: the forward sweep that solves the kinetic part exactly.
fn sweep(q: &mut [Vecs], p0: &Vecs, forces: &[Vecs], w: &[f64], dt: f64) {
    let mut p = p0.clone();
    for j in 0..forces.len() {
        for i in 0..p.len() {
            for c in 0..3 {
                q[j + 1][i][c] = q[j][i][c] + dt * w[i] * (p[i][c] + 0.5 * dt * forces[j][i][c]);
                p[i][c] += dt * forces[j][i][c];
            }
        }
    }
}

/// max |rₖ| over the window, relative to its largest momentum (or impulse dt·F, at rest), and
/// the floor rounding puts under it there (4u·m|q|/dt, relative to the same).
fn residual(q: &[Vecs], p0: &Vecs, forces: &[Vecs], m: &[f64], dt: f64) -> (f64, f64) {
    let (mut worst, mut scale, mut size) = (0.0f64, f64::MIN_POSITIVE, 0.0f64);
    for j in 0..forces.len() {
        for i in 0..p0.len() {
            for c in 0..3 {
                let ahead = m[i] * (q[j + 1][i][c] - q[j][i][c]) / dt - 0.5 * dt * forces[j][i][c];
                let behind = match j {
                    0 => p0[i][c],
                    _ => m[i] * (q[j][i][c] - q[j - 1][i][c]) / dt + 0.5 * dt * forces[j - 1][i][c],
                };
                worst = worst.max((behind - ahead).abs());
                scale = scale.max(behind.abs()).max((dt * forces[j][i][c]).abs());
                size = size.max(m[i] * q[j + 1][i][c].abs());
            }
        }
    }
    (worst / scale, 2.0 * f64::EPSILON * size / dt / scale)
}

impl Solver for ActionDescent {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        self.next(g, s, dt)?;
        self.at.potential = g.forces(s, &mut self.at.f)?;
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn carried(&self) -> Result<Carried, String> {
        Err("action descent solves windows of steps ahead, which a restart file does not hold yet".into())
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }

    /// Takes the solved states up to `until`, evaluating the forces at that one only.
    fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Failure> {
        if s.step >= until {
            return Ok(());
        }
        while s.step + 1 < until {
            self.next(g, s, dt)?;
            tick(s, dt);
        }
        self.step(g, s, dt)?;
        tick(s, dt);
        Ok(())
    }

    fn iterations(&self) -> Option<&Iterations> {
        Some(&self.log)
    }
}
