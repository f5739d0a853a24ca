//! Solvers: programs over the graph that advance the state.

mod rk4;
mod velocity_verlet;
mod yoshida;

pub use velocity_verlet::{Stride, VelocityVerlet};

use crate::forces::Singularity;
use crate::graph::LagrangianGraph;
use crate::state::State;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    VelocityVerlet,
    Yoshida4,
    Rk4,
}

impl Integrator {
    pub const ALL: [Integrator; 3] = [Integrator::VelocityVerlet, Integrator::Yoshida4, Integrator::Rk4];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::VelocityVerlet => "velocity_verlet",
            Integrator::Yoshida4 => "yoshida4",
            Integrator::Rk4 => "rk4",
        }
    }

    pub fn from_name(s: &str) -> Option<Integrator> {
        Integrator::ALL.into_iter().find(|i| i.name() == s)
    }
}

/// An integrator at work: it keeps the forces at the current state between steps.
pub struct Stepper {
    integrator: Integrator,
    vv: VelocityVerlet,
}

impl Stepper {
    pub fn new(integrator: Integrator, g: &LagrangianGraph, s: &State) -> Result<Self, Singularity> {
        Ok(Stepper { integrator, vv: VelocityVerlet::new(g, s)? })
    }

    /// One step of `dt`: the state's step counter and clock advance with it (t = step·dt).
    pub fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Singularity> {
        self.advance_to(g, s, dt, s.step + 1)
    }

    /// Steps until the state is at step `until`; the steps in between are seen by no one, so
    /// nothing else runs between them, and the integrator is chosen once, not per step. A
    /// non-finite force is an error at the step it arises; the potential energy is that of the
    /// state reached (velocity Verlet with conservative forces computes it at that step only;
    /// the others stop after the first step that leaves it non-finite, where the run must stop).
    pub fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Singularity> {
        match self.integrator {
            Integrator::VelocityVerlet => self.vv.advance_to(g, s, dt, until),
            Integrator::Yoshida4 => self.repeat(g, s, dt, until, yoshida::advance),
            Integrator::Rk4 => self.repeat(g, s, dt, until, |vv, g, s, dt| {
                vv.potential = rk4::advance(g, s, dt, &mut vv.f)?;
                Ok(())
            }),
        }
    }

    fn repeat<F>(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64, one: F) -> Result<(), Singularity>
    where
        F: Fn(&mut VelocityVerlet, &LagrangianGraph, &mut State, f64) -> Result<(), Singularity>,
    {
        while s.step < until {
            one(&mut self.vv, g, s, dt)?;
            tick(s, dt);
            if !self.vv.potential.is_finite() {
                break;
            }
        }
        Ok(())
    }

    /// The forces at the current state.
    pub fn forces(&self) -> &[[f64; 3]] {
        &self.vv.f
    }

    /// The potential energy at the current state (the f64 witness).
    pub fn potential(&self) -> f64 {
        self.vv.potential
    }
}

/// The step counter and the clock after one step.
fn tick(s: &mut State, dt: f64) {
    set_step(s, s.step + 1, dt);
}

/// The step counter and the clock at `step` (t = step·dt, never accumulated).
fn set_step(s: &mut State, step: u64, dt: f64) {
    s.step = step;
    s.t = step as f64 * dt;
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
    use lagra_checker::terms::Kind;

    /// A harmonic pair (k = 4, μ = ½: ω = √8) released from a stretch of 0.3: the separation is
    /// r₀ + 0.3 cos ωt exactly. The error at t = 2 for the given dt.
    fn error(integrator: Integrator, dt: f64) -> f64 {
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![Body { mass: 1.0, charge: 0.0, colour: [0.0; 2] }; 2],
            terms: vec![TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![4.0, 1.0, 0.0] }],
        };
        let g = LagrangianGraph::new(&model);
        let mut s = State { step: 0, t: 0.0, x: vec![[0.0; 3], [1.3, 0.0, 0.0]], v: vec![[0.0; 3]; 2] };
        let mut st = Stepper::new(integrator, &g, &s).unwrap();
        let steps = (2.0 / dt).round() as u64;
        for _ in 0..steps {
            st.step(&g, &mut s, dt).unwrap();
        }
        let exact = 1.0 + 0.3 * (8f64.sqrt() * s.t).cos();
        (s.x[1][0] - s.x[0][0] - exact).abs()
    }

    /// The measured order of convergence between dt and dt/2.
    fn order(integrator: Integrator, dt: f64) -> f64 {
        (error(integrator, dt) / error(integrator, dt / 2.0)).log2()
    }

    #[test]
    fn verlet_converges_at_second_order() {
        let p = order(Integrator::VelocityVerlet, 0.01);
        assert!((p - 2.0).abs() <= 0.3, "order {p}");
    }

    #[test]
    fn yoshida_converges_at_fourth_order() {
        let p = order(Integrator::Yoshida4, 0.02);
        assert!((p - 4.0).abs() <= 0.3, "order {p}");
    }

    #[test]
    fn rk4_converges_at_fourth_order() {
        let p = order(Integrator::Rk4, 0.02);
        assert!((p - 4.0).abs() <= 0.3, "order {p}");
    }
}
