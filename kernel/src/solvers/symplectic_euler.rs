//! Symplectic Euler (kick, then drift): v₁ = v₀ + dt·F(x₀)/m, x₁ = x₀ + dt·v₁. First order,
//! symplectic: the energy error stays bounded (O(dt)) instead of drifting, and linear and
//! angular momentum are conserved exactly in exact arithmetic for pairwise central forces. One
//! force evaluation a step, like velocity Verlet, at one order less; it is here as the simplest
//! member of the family and the bottom row of `lagra bench precision`.
//!
//! With velocity-dependent forces the kick is implicit in the new velocity,
//! v₁ = v₀ + dt·F(x₀, v₁)/m (a fixed point, as velocity Verlet's closing kick), so a damping
//! removes energy at the velocity it acts on.

use super::{implicit_kick, Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;

pub struct SymplecticEuler {
    pub at: Evaluated,
}

impl Solver for SymplecticEuler {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        if g.velocity_dependent() {
            implicit_kick(g, s, &mut self.at, dt, |_| Ok(()))?;
        } else {
            g.kick(&mut s.v, &self.at.f, dt);
        }
        g.drift(s, dt);
        self.at.potential = g.forces(s, &mut self.at.f)?;
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }
}
