//! Langevin dynamics by BAOAB (Leimkuhler & Matthews 2013): kick ½dt (B), drift ½dt (A), the
//! exact Ornstein–Uhlenbeck update of the velocities v ← c₁v + √((1 − c₁²)kT/m)·ξ with
//! c₁ = e^(−γ·dt) (O), drift ½dt, evaluate, kick ½dt. Its configurational averages are exact to
//! O(dt²) and better than the other splittings'. Each ξ is drawn for (seed, step, body, axis)
//! alone, so the run is the same bits on any number of threads.

use super::{implicit_kick, Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::thermostat::langevin_bath;

pub struct Baoab {
    pub at: Evaluated,
    pub kt: f64,
    pub gamma: f64,
    pub seed: u64,
}

impl Solver for Baoab {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let h = 0.5 * dt;
        g.kick(&mut s.v, &self.at.f, h);
        g.drift(s, h);
        langevin_bath(&mut s.v, &g.inverse_masses, |i| i, (self.kt, self.gamma, self.seed), s.step, dt);
        g.drift(s, h);
        if g.velocity_dependent() {
            return implicit_kick(g, s, &mut self.at, h, |_| Ok(()));
        }
        self.at.potential = g.forces(s, &mut self.at.f)?;
        g.kick(&mut s.v, &self.at.f, h);
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }
}
