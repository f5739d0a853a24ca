//! Langevin dynamics by BAOAB (Leimkuhler & Matthews 2013): kick ½dt (B), drift ½dt (A), the
//! exact Ornstein–Uhlenbeck update of the velocities v ← c₁v + √((1 − c₁²)kT/m)·ξ with
//! c₁ = e^(−γ·dt) (O), drift ½dt, evaluate, kick ½dt. Its configurational averages are exact to
//! O(dt²) and better than the other splittings'. Each ξ is drawn for (seed, step, body, axis)
//! alone, so the run is the same bits on any number of threads.

use super::{implicit_kick, Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;
use lagra_lang::random::normal;

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
        let c1 = libm::exp(-self.gamma * dt);
        let c2 = libm::sqrt(1.0 - c1 * c1);
        for (i, (v, w)) in s.v.iter_mut().zip(&g.inverse_masses).enumerate() {
            let sigma = c2 * libm::sqrt(self.kt * w);
            for (c, vc) in v.iter_mut().enumerate() {
                *vc = c1 * *vc + sigma * normal(self.seed, s.step, 3 * i as u64 + c as u64);
            }
        }
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
