//! Velocity Verlet: kick ½dt, drift dt, evaluate, kick ½dt. Symplectic and time-reversible for
//! conservative forces, and it conserves linear and angular momentum exactly in exact
//! arithmetic when the forces are pairwise and central.
//!
//! With velocity-dependent (dissipative) forces the closing kick is implicit,
//! v₁ = v½ + ½dt·F(x₁, v₁)/m, solved by fixed-point iteration, so that each kick sees the force
//! at the velocity of its own end of the step. Evaluating the damping at the half-step velocity
//! instead would lag it by ½dt and make the dissipated energy first-order wrong.

use super::{implicit_kick, Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;
use crate::step::{kick_drift, tick, Stride};

pub struct VelocityVerlet {
    pub at: Evaluated,
}

impl Solver for VelocityVerlet {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let h = 0.5 * dt;
        kick_drift(&mut s.x, &mut s.v, &mut self.at.f, &g.inverse_masses, (h, dt), false, g.spread());
        if g.velocity_dependent() {
            implicit_kick(g, s, &mut self.at, h, |_| Ok(()))
        } else {
            self.at.potential = g.forces(s, &mut self.at.f)?;
            g.kick(&mut s.v, &self.at.f, h);
            Ok(())
        }
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }

    /// With conservative forces the closing kick of one step, the opening kick of the next and
    /// its drift are one pass over the bodies (each body's velocity stays in a register between
    /// them), and the steps before the last evaluate the forces only: no one sees their
    /// potential energy. The operations on the state and their order are those of one step at a
    /// time, so the bits are the same (tested). With velocity-dependent forces, one step at a
    /// time.
    fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Failure> {
        if g.velocity_dependent() {
            while s.step < until {
                self.step(g, s, dt)?;
                tick(s, dt);
                if !self.at.potential.is_finite() {
                    break;
                }
            }
            return Ok(());
        }
        if s.step >= until {
            return Ok(());
        }
        let h = 0.5 * dt;
        kick_drift(&mut s.x, &mut s.v, &mut self.at.f, &g.inverse_masses, (h, dt), false, g.spread());
        // forces only: the force loops refuse a non-finite force, so no NaN passes unseen
        g.stride(Stride { s, f: &mut self.at.f, inverse: &g.inverse_masses, h, dt, until, spread: g.spread() })?;
        self.at.potential = g.forces(s, &mut self.at.f)?;
        g.kick(&mut s.v, &self.at.f, h);
        tick(s, dt);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::step::kick;
    use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
    use lagra_checker::terms::Kind;

    fn pair(gamma: f64) -> (LagrangianGraph, State) {
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![
                Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
                Body { mass: 3.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None },
            ],
            terms: vec![TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![5.0, 1.0, gamma] }],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        let s = State {
            step: 0,
            t: 0.0,
            x: vec![[0.0; 3], [1.7, 0.2, 0.0]],
            v: vec![[0.1, 0.3, 0.0], [-0.2, 0.0, 0.4]],
            chain: vec![],
            spin: vec![],
        };
        (LagrangianGraph::new(&model), s)
    }

    fn verlet(g: &LagrangianGraph, s: &State) -> VelocityVerlet {
        VelocityVerlet { at: Evaluated::at(g, s).unwrap() }
    }

    #[test]
    fn the_closing_kick_sees_the_force_at_its_own_velocity() {
        let (g, mut s) = pair(0.8);
        let mut vv = verlet(&g, &s);
        let dt = 0.01;
        for _ in 0..10 {
            vv.step(&g, &mut s, dt).unwrap();
        }
        // Undo the closing kick with the force at the final state: it must give back v½, and
        // re-kicking with F(x₁, v₁) must reproduce v₁ to the last bit (the fixed point).
        let mut f = vec![[0.0; 3]; 2];
        g.forces(&s, &mut f).unwrap();
        let mut half = s.v.clone();
        kick(&mut half, &f, &g.inverse_masses, -0.5 * dt);
        let mut again = half.clone();
        kick(&mut again, &f, &g.inverse_masses, 0.5 * dt);
        for (a, b) in again.iter().flatten().zip(s.v.iter().flatten()) {
            assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0), "{a} vs {b}");
        }
    }

    /// Stepping to a step in one call is stepping one at a time, to the bit: positions,
    /// velocities, forces and the potential, stopping wherever asked.
    #[test]
    fn many_steps_in_one_call_are_the_same_bits_as_one_at_a_time() {
        for gamma in [0.0, 0.4] {
            let (g, start) = pair(gamma);
            let (mut one, mut many) = (start.clone(), start.clone());
            let mut a = verlet(&g, &one);
            for _ in 0..300 {
                a.step(&g, &mut one, 0.01).unwrap();
                tick(&mut one, 0.01);
            }
            let mut b = verlet(&g, &many);
            for until in [1, 2, 120, 120, 299, 300] {
                b.advance_to(&g, &mut many, 0.01, until).unwrap();
                assert_eq!(many.step, until);
            }
            assert_eq!(one, many);
            assert_eq!((a.at.f, a.at.potential.to_bits()), (b.at.f, b.at.potential.to_bits()));
        }
    }

    #[test]
    fn momentum_is_conserved_to_round_off() {
        let (g, mut s) = pair(0.3);
        let p = |s: &State| -> [f64; 3] { std::array::from_fn(|c| s.v[0][c] * 1.0 + s.v[1][c] * 3.0) };
        let p0 = p(&s);
        let mut vv = verlet(&g, &s);
        for _ in 0..1000 {
            vv.step(&g, &mut s, 0.01).unwrap();
        }
        for (a, b) in p(&s).iter().zip(p0) {
            assert!((a - b).abs() < 1e-13, "{a} vs {b}");
        }
    }

    #[test]
    fn a_collapsed_bond_is_a_clear_error_not_nan() {
        let (g, mut s) = pair(0.0);
        s.x[1] = s.x[0];
        let err = Evaluated::at(&g, &s).err().unwrap();
        assert_eq!(
            err.to_string(),
            "HarmonicBond: bodies 0, 1: at the same point, where the bond's direction is undefined"
        );
    }
}
