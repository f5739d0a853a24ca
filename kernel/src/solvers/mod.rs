//! Solvers: short programs over the graph's operations (evaluate, kick, drift, rotate, project),
//! one file each, read like the algorithm in its paper. A solver keeps the forces at the current
//! state between steps; `Stepper` runs the one a scene chose.

mod action_descent;
mod avbd;
mod boris;
mod impulses;
mod langevin;
mod nose_hoover;
mod rattle;
mod rk4;
mod symplectic_euler;
mod velocity_verlet;
mod yoshida;

use crate::constraints::{Tolerance, Unconverged};
use crate::contact::Solids;
use crate::forces::Singularity;
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::step::tick;
use lagra_lang::integrator::{Integrator, Settings};
use lagra_lang::thermostat::Thermostat;
use lagra_lang::Scene;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Why a step could not be taken.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// A force is undefined at the state reached.
    Singular(Singularity),
    /// An iteration inside the step did not reach its tolerance.
    Unconverged(String),
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Singular(s) => s.fmt(f),
            Failure::Unconverged(m) => f.write_str(m),
        }
    }
}

impl From<Singularity> for Failure {
    fn from(s: Singularity) -> Failure {
        Failure::Singular(s)
    }
}

impl From<Unconverged> for Failure {
    fn from(u: Unconverged) -> Failure {
        Failure::Unconverged(u.to_string())
    }
}

/// The forces at the current state and the potential energy there (the f64 witness).
#[derive(Clone, Debug)]
pub struct Evaluated {
    pub f: Vec<[f64; 3]>,
    pub potential: f64,
}

impl Evaluated {
    pub fn at(g: &LagrangianGraph, s: &State) -> Result<Evaluated, Singularity> {
        let mut f = vec![[0.0; 3]; s.x.len()];
        let potential = g.forces(s, &mut f)?;
        Ok(Evaluated { f, potential })
    }
}

/// How an iterating solver's iterations went, for the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Iterations {
    /// What iterated (`SHAKE/RATTLE sweeps`, `action windows`).
    pub what: &'static str,
    pub tol: f64,
    /// Solves (steps, or windows) and the iterations they took.
    pub solves: u64,
    pub iterations: u64,
    pub most_iterations: u32,
    /// The largest final residual of any solve, relative (the tolerance it was held to: `tol`).
    pub worst_residual: f64,
    /// Each action window: its first step, iterations and final residual.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub windows: Vec<Window>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct Window {
    pub first_step: u64,
    pub iterations: u32,
    pub residual: f64,
}

impl Iterations {
    fn record(&mut self, iterations: u32, residual: f64) {
        self.solves += 1;
        self.iterations += iterations as u64;
        self.most_iterations = self.most_iterations.max(iterations);
        self.worst_residual = self.worst_residual.max(residual);
    }
}

/// What a solver carries from one step to the next besides the state, exactly: a restart
/// file's, so that a run resumed from it is the same bits as the run that wrote it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Carried {
    /// The forces and potential at the state (what the next step's first kick uses).
    pub forces: Vec<[f64; 3]>,
    pub potential: f64,
    /// Sequential impulses' warm starts: each touching pair's impulses (normal, two tangents)
    /// by place, in the order of the pairs.
    pub warm: Vec<((usize, usize), Vec<([f64; 3], [f64; 3])>)>,
    /// AVBD's contact stiffnesses (the three rows'), in the order of `warm` (empty for any
    /// other solver).
    pub stiffness: Vec<Vec<[f64; 3]>>,
}

impl Carried {
    /// What velocity Verlet carries: the forces and potential at the state.
    pub fn forces(at: &Evaluated) -> Carried {
        Carried { forces: at.f.clone(), potential: at.potential, warm: vec![], stiffness: vec![] }
    }
    pub(crate) fn evaluated(&self) -> Evaluated {
        Evaluated { f: self.forces.clone(), potential: self.potential }
    }
}

/// One integrator at work.
pub trait Solver {
    /// One step of `dt` (positions and velocities; the caller ticks the clock).
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure>;
    /// The forces and potential at the current state.
    fn evaluated(&self) -> &Evaluated;
    /// Steps until the state is at step `until`, stopping early after a step whose potential is
    /// not finite (the run must stop there). A solver with a faster way to the same bits
    /// overrides it.
    fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Failure> {
        while s.step < until {
            self.step(g, s, dt)?;
            tick(s, dt);
            if !self.evaluated().potential.is_finite() {
                break;
            }
        }
        Ok(())
    }
    /// Whether its steps spread over the graph's pool (then they go to the pool whole).
    fn spreads(&self, g: &LagrangianGraph) -> bool {
        g.steps_spread()
    }
    /// How the iterations inside its steps went, for a solver that iterates.
    fn iterations(&self) -> Option<&Iterations> {
        None
    }
    /// How it spread its steps over the run's threads, where that is its own choice
    /// (`--explain`'s `plan        solver:` line).
    fn plan(&self) -> Option<String> {
        None
    }
    /// Whether it turns the rigid bodies itself (else the stepper turns them freely after it).
    fn rotates(&self) -> bool {
        false
    }
    /// What it carries to the next step besides the state (`Carried`), or why it cannot be
    /// cut here.
    fn carried(&self) -> Result<Carried, String> {
        Ok(Carried::forces(self.evaluated()))
    }
    /// Takes up what `carried` gave, at the state it was given at.
    fn take_up(&mut self, c: &Carried);
}

/// The integrator a scene chose, at work on a graph.
pub struct Stepper {
    solver: Box<dyn Solver + Send>,
}

impl Stepper {
    pub fn new(
        integrator: Integrator,
        settings: Settings,
        g: &LagrangianGraph,
        s: &State,
    ) -> Result<Self, Singularity> {
        let at = Evaluated::at(g, s)?;
        let tol = Tolerance { tol: settings.tol, sweeps: settings.iterations };
        let solver: Box<dyn Solver + Send> = match integrator {
            Integrator::VelocityVerlet => Box::new(velocity_verlet::VelocityVerlet { at }),
            Integrator::SymplecticEuler => Box::new(symplectic_euler::SymplecticEuler { at }),
            Integrator::Yoshida4 => Box::new(yoshida::Yoshida4 { vv: velocity_verlet::VelocityVerlet { at } }),
            Integrator::Rk4 => Box::new(rk4::Rk4 { at }),
            Integrator::Boris => Box::new(boris::Boris::new(g, s, at)?),
            Integrator::Rattle => Box::new(rattle::Rattle::new(g, at, tol)),
            Integrator::ActionDescent => Box::new(action_descent::ActionDescent::new(at, settings)),
            Integrator::SequentialImpulses => {
                let solids = g.solids().unwrap_or_else(|| Solids::none(s.x.len()));
                Box::new(impulses::Impulses::new(at, solids, settings.substeps, settings.iterations))
            }
            Integrator::Avbd => {
                let solids = g.solids().unwrap_or_else(|| Solids::none(s.x.len()));
                Box::new(avbd::Avbd::new(at, solids, settings.iterations))
            }
        };
        Ok(Stepper { solver })
    }

    /// The stepper a scene asks for: its integrator, inside its thermostat if it has one (the
    /// compiler allows a thermostat only with velocity Verlet).
    pub fn for_scene(scene: &Scene, g: &LagrangianGraph, s: &State) -> Result<Self, Singularity> {
        let at = || Evaluated::at(g, s);
        let solver: Box<dyn Solver + Send> = match (&scene.thermostat, &scene.model.thermostat) {
            (None, _) => return Stepper::new(scene.solver.integrator, scene.solver.settings, g, s),
            (Some(Thermostat::NoseHoover { .. }), Some(chain)) => Box::new(nose_hoover::NoseHoover {
                vv: velocity_verlet::VelocityVerlet { at: at()? },
                chain: chain.clone(),
            }),
            (Some(Thermostat::Langevin { kt, gamma, seed }), _) => {
                Box::new(langevin::Baoab { at: at()?, kt: *kt, gamma: *gamma, seed: *seed })
            }
            (Some(Thermostat::NoseHoover { .. }), None) => unreachable!("a Nosé–Hoover scene's model holds its chain"),
        };
        Ok(Stepper { solver })
    }

    /// Velocity Verlet resumed at a state whose forces and potential are `at` (a replay from a
    /// saved state: the same bits as the run that saved it).
    pub fn resume_verlet(at: Evaluated) -> Self {
        Stepper { solver: Box::new(velocity_verlet::VelocityVerlet { at }) }
    }

    /// What the solver carries to the next step besides the state (a restart file's), or why
    /// it cannot be cut here.
    pub fn carried(&self) -> Result<Carried, String> {
        self.solver.carried()
    }

    /// Takes up what a solver of the same scene carried at state `s`, where this one was just
    /// made (`for_scene`, its lists built where the carrying run's were). Forces that depend on
    /// positions alone must come out the bits this kernel computed at `s`: otherwise the
    /// restart was written by a kernel with other arithmetic, and the run would not be the one
    /// it continues.
    pub fn take_up(&mut self, c: &Carried, g: &LagrangianGraph) -> Result<(), String> {
        let now = self.solver.evaluated();
        if c.forces.len() != now.f.len() {
            return Err(format!("it holds forces on {} bodies, the scene has {}", c.forces.len(), now.f.len()));
        }
        let bits = |f: &[[f64; 3]]| f.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        if !g.velocity_dependent() && bits(&c.forces) != bits(&now.f) {
            return Err("its forces are not the ones this kernel computes at its state: it was written by \
                        another version of lagra, or edited"
                .into());
        }
        self.solver.take_up(c);
        Ok(())
    }

    /// The forces and potential at the current state.
    pub fn evaluated(&self) -> &Evaluated {
        self.solver.evaluated()
    }

    /// One step of `dt`: the state's step counter and clock advance with it (t = step·dt).
    pub fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        self.advance_to(g, s, dt, s.step + 1)
    }

    /// Steps until the state is at step `until`; the steps in between are seen by no one, so
    /// nothing else runs between them. A failure is an error at the step it arises (the state's
    /// counter is then at the step before); the potential energy is that of the state reached.
    pub fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Failure> {
        let from = s.step;
        // on a pool, the steps go to it whole: its passes then wake no one from outside
        let solver = &mut self.solver;
        let done = match g.pool().filter(|_| solver.spreads(g)) {
            Some(pool) => crate::spread::within(pool, || solver.advance_to(g, s, dt, until)),
            None => solver.advance_to(g, s, dt, until),
        };
        // the rigid bodies turn through the steps taken, failed or not (`LagrangianGraph::turn`)
        if !self.solver.rotates() {
            g.turn(&mut s.spin, dt, s.step - from);
        }
        done
    }

    /// The forces at the current state.
    pub fn forces(&self) -> &[[f64; 3]] {
        &self.solver.evaluated().f
    }

    /// The potential energy at the current state (the f64 witness).
    pub fn potential(&self) -> f64 {
        self.solver.evaluated().potential
    }

    /// How the iterations inside the steps went (RATTLE, action descent).
    pub fn iterations(&self) -> Option<&Iterations> {
        self.solver.iterations()
    }

    /// How the solver spread its steps over the threads, where it chose (AVBD's islands).
    pub fn plan(&self) -> Option<String> {
        self.solver.plan()
    }
}

/// v = v₀ + h·F(x, v)/m for a velocity-dependent F, solved by fixed-point iteration from
/// v = v₀ + h·F(x, v₀)/m until a round moves the velocities by rounding alone (`settled`; the
/// explicit kick and at most eight more rounds), `project` applied after every kick; `e` holds
/// F(x, v) at the end. A contraction of factor h·γ/m: at any dt the integrator is otherwise
/// stable at, a few rounds reach the last bit.
fn implicit_kick(
    g: &LagrangianGraph,
    s: &mut State,
    e: &mut Evaluated,
    h: f64,
    mut project: impl FnMut(&mut State) -> Result<(), Failure>,
) -> Result<(), Failure> {
    let start = s.v.clone();
    for _ in 0..FIXED_POINT {
        e.potential = g.forces(s, &mut e.f)?;
        let guess = std::mem::replace(&mut s.v, start.clone());
        g.kick(&mut s.v, &e.f, h);
        project(s)?;
        if settled(&s.v, &guess) {
            break;
        }
    }
    Ok(())
}

/// Whether a round of the fixed point moved no velocity by more than 4 ulps of the largest
/// speed: from there on the rounds only wander by rounding, often between two values in the last
/// bit, where waiting for a round that moves nothing ran every kick to the last round. The dam
/// break's kicks contract ~200-fold a round and reached that floor in 6 or 7 rounds of 9 (a
/// round is a pass over every pair). A contraction too slow to reach it (a magnetic field at
/// ω·dt = 0.2) runs every round, as before.
fn settled(v: &[[f64; 3]], guess: &[[f64; 3]]) -> bool {
    let (mut moved, mut largest) = (0.0f64, 0.0f64);
    for (a, b) in v.iter().flatten().zip(guess.iter().flatten()) {
        moved = moved.max((a - b).abs());
        largest = largest.max(a.abs());
    }
    moved <= 4.0 * f64::EPSILON * largest
}

const FIXED_POINT: usize = 9;

#[cfg(test)]
mod tests;
