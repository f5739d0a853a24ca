//! Velocity Verlet inside a Nosé–Hoover chain: the chain's half-step, a Verlet step, the
//! chain's half-step (Martyna, Tuckerman & Klein 1996). Time-reversible; the extended energy
//! H′ = H + the chain's share is conserved to O(dt²), and the checker certifies it.

use super::velocity_verlet::VelocityVerlet;
use super::{Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::step::{kick_drift, tick};
use crate::thermostat::nose_hoover_half;
use lagra_checker::thermostat::Chain;

pub struct NoseHoover {
    pub vv: VelocityVerlet,
    pub chain: Chain,
}

impl Solver for NoseHoover {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        nose_hoover_half(&self.chain, s, &g.masses, 0.5 * dt);
        self.vv.step(g, s, dt)?;
        nose_hoover_half(&self.chain, s, &g.masses, 0.5 * dt);
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.vv.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.vv.at = c.evaluated();
    }

    /// With conservative forces, the steps before the last evaluate the forces only (no one
    /// sees their potential energy); the operations on the state are those of `step`, so the
    /// bits are the same (tested).
    fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Failure> {
        if g.velocity_dependent() {
            while s.step < until {
                self.step(g, s, dt)?;
                tick(s, dt);
                if !self.vv.at.potential.is_finite() {
                    break;
                }
            }
            return Ok(());
        }
        let (h, at) = (0.5 * dt, &mut self.vv.at);
        while s.step < until {
            nose_hoover_half(&self.chain, s, &g.masses, h);
            kick_drift(&mut s.x, &mut s.v, &mut at.f, &g.inverse_masses, (h, dt), false, g.spread());
            if s.step + 1 == until {
                at.potential = g.forces(s, &mut at.f)?;
            } else {
                g.forces_only(s, &mut at.f)?;
            }
            g.kick(&mut s.v, &at.f, h);
            nose_hoover_half(&self.chain, s, &g.masses, h);
            tick(s, dt);
        }
        Ok(())
    }
}
