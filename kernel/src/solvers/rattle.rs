//! RATTLE (Andersen 1983): velocity Verlet on the constraint manifold. The drift's positions are
//! moved back onto the constraints along the rods as they were at the start of the step (SHAKE),
//! the velocities with them; after the closing kick the velocities are made tangent to the
//! constraints. Symplectic and time-reversible on the manifold, second order; the constraint
//! forces are internal and central, so momentum and angular momentum are conserved as by
//! Verlet, and they do no work, so the energy claim holds with them. Without constraints it is
//! velocity Verlet.

use super::{implicit_kick, Carried, Evaluated, Failure, Iterations, Solver};
use crate::constraints::Tolerance;
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::step::kick_drift;

pub struct Rattle {
    at: Evaluated,
    tol: Tolerance,
    log: Iterations,
    /// Whether there is anything to keep (without constraints there is nothing to report).
    constrained: bool,
}

impl Rattle {
    pub fn new(g: &LagrangianGraph, at: Evaluated, tol: Tolerance) -> Rattle {
        let log = Iterations { what: "SHAKE/RATTLE rounds per step", tol: tol.tol, ..Iterations::default() };
        Rattle { at, tol, log, constrained: g.constrained() }
    }
}

impl Solver for Rattle {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let (h, tol) = (0.5 * dt, self.tol);
        let before = s.x.clone();
        kick_drift(&mut s.x, &mut s.v, &mut self.at.f, &g.inverse_masses, (h, dt), false, g.spread());
        let shaken = g.shake(&before, s, dt, tol)?;
        let mut sweeps = shaken.sweeps;
        if g.velocity_dependent() {
            implicit_kick(g, s, &mut self.at, h, |s| {
                sweeps += g.rattle(s, dt, tol)?.sweeps;
                Ok(())
            })?;
        } else {
            self.at.potential = g.forces(s, &mut self.at.f)?;
            g.kick(&mut s.v, &self.at.f, h);
            sweeps += g.rattle(s, dt, tol)?.sweeps;
        }
        self.log.record(sweeps, shaken.error);
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }

    fn iterations(&self) -> Option<&Iterations> {
        self.constrained.then_some(&self.log)
    }
}
