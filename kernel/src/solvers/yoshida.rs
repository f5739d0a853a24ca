//! Yoshida's fourth-order symplectic integrator (Yoshida 1990): three velocity Verlet steps of
//! w₁dt, w₀dt, w₁dt with w₁ = 1/(2 − 2^{1/3}), w₀ = −2^{1/3}/(2 − 2^{1/3}). A composition of
//! Verlet steps, it keeps their symmetries: linear and angular momentum exactly conserved in
//! exact arithmetic, energy error bounded, now O(dt⁴).

use super::velocity_verlet::VelocityVerlet;
use super::{Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;

const CBRT2: f64 = 1.259_921_049_894_873_2;
const W1: f64 = 1.0 / (2.0 - CBRT2);
const W0: f64 = -CBRT2 / (2.0 - CBRT2);

pub struct Yoshida4 {
    pub vv: VelocityVerlet,
}

impl Solver for Yoshida4 {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        for w in [W1, W0, W1] {
            self.vv.step(g, s, w * dt)?;
        }
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.vv.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.vv.at = c.evaluated();
    }
}
