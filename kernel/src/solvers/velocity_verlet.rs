//! Velocity Verlet: kick ½dt, drift dt, evaluate, kick ½dt. Symplectic and time-reversible for
//! conservative forces, and it conserves linear and angular momentum exactly in exact
//! arithmetic when the forces are pairwise and central.
//!
//! With velocity-dependent (dissipative) forces the closing kick is implicit,
//! v₁ = v½ + ½dt·F(x₁, v₁)/m, solved by fixed-point iteration, so that each kick sees the force
//! at the velocity of its own end of the step. Evaluating the damping at the half-step velocity
//! instead would lag it by ½dt and make the dissipated energy first-order wrong.

use super::{set_step, tick};
use crate::forces::Singularity;
use crate::graph::LagrangianGraph;
use crate::state::State;

/// The contraction factor of the iteration is ½dt·γ/m; for any dt the integrator is otherwise
/// stable at, a few iterations reach a fixed point to the last bit.
const MAX_ITERATIONS: usize = 8;

pub struct VelocityVerlet {
    /// The forces at the current state.
    pub f: Vec<[f64; 3]>,
    /// Potential energy at the current state (the witness of the last evaluation).
    pub potential: f64,
}

impl VelocityVerlet {
    pub fn new(g: &LagrangianGraph, s: &State) -> Result<Self, Singularity> {
        let mut f = vec![[0.0; 3]; s.x.len()];
        let potential = g.forces(s, &mut f)?;
        Ok(VelocityVerlet { f, potential })
    }

    /// Advances positions and velocities by `h` (the step counter and clock are the caller's).
    pub fn advance(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Singularity> {
        let h = 0.5 * dt;
        kick_drift(&mut s.x, &mut s.v, &mut self.f, &g.inverse_masses, (h, dt), false);
        let half = if g.velocity_dependent() { Some(s.v.clone()) } else { None };
        self.potential = g.forces(s, &mut self.f)?;
        kick(&mut s.v, &self.f, &g.inverse_masses, h);
        if let Some(half) = half {
            for _ in 0..MAX_ITERATIONS {
                self.potential = g.forces(s, &mut self.f)?;
                let guess = std::mem::replace(&mut s.v, half.clone());
                kick(&mut s.v, &self.f, &g.inverse_masses, h);
                if s.v == guess {
                    break;
                }
            }
        }
        Ok(())
    }

    /// Steps to step `until` (the counter and clock advance with it). With conservative forces
    /// the closing kick of one step, the opening kick of the next and its drift are one pass
    /// over the bodies (each body's velocity stays in a register between them), and the steps
    /// before the last evaluate the forces only: no one sees their potential energy. The
    /// operations on the state and their order are those of one step at a time, so the bits
    /// are the same (tested). With velocity-dependent forces, one step at a time, stopping
    /// after a step whose potential is not finite.
    pub fn advance_to(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64, until: u64) -> Result<(), Singularity> {
        if g.velocity_dependent() {
            while s.step < until {
                self.advance(g, s, dt)?;
                tick(s, dt);
                if !self.potential.is_finite() {
                    break;
                }
            }
            return Ok(());
        }
        if s.step >= until {
            return Ok(());
        }
        let h = 0.5 * dt;
        kick_drift(&mut s.x, &mut s.v, &mut self.f, &g.inverse_masses, (h, dt), false);
        // forces only: the force loops refuse a non-finite force, so no NaN passes unseen
        let stride = Stride { s, f: &mut self.f, inverse: &g.inverse_masses, h, dt, until };
        match g.sole() {
            Some(group) => group.stride(stride, g.frame_parts())?,
            None => stride.run(|s, f| g.forces_only(s, f))?,
        }
        self.potential = g.forces(s, &mut self.f)?;
        kick(&mut s.v, &self.f, &g.inverse_masses, h);
        tick(s, dt);
        Ok(())
    }
}

/// The steps before the last of a conservative `advance_to`: forces only, then the closing kick,
/// the next opening kick and the drift. A graph of one group runs them monomorphized around
/// that group's force code (`Force::stride`); any other through the graph.
pub struct Stride<'a> {
    s: &'a mut State,
    f: &'a mut Vec<[f64; 3]>,
    inverse: &'a [f64],
    h: f64,
    dt: f64,
    until: u64,
}

impl Stride<'_> {
    /// Steps until one step before `until`, with `forces` adding the forces at a state to `f`,
    /// which it finds zeroed.
    #[inline]
    pub fn run(
        self,
        mut forces: impl FnMut(&State, &mut [[f64; 3]]) -> Result<(), Singularity>,
    ) -> Result<(), Singularity> {
        // the clock is set once at the end (t = step·dt: the same bits); no force reads it
        let (mut step, mut done) = (self.s.step, Ok(()));
        while step + 1 < self.until {
            if let Err(e) = forces(self.s, self.f) {
                done = Err(e);
                break;
            }
            kick_drift(&mut self.s.x, &mut self.s.v, self.f, self.inverse, (self.h, self.dt), true);
            step += 1;
        }
        set_step(self.s, step, self.dt);
        done
    }
}

/// One pass over the bodies: v += h·F/m (twice with `closing`: the closing kick of a step, then
/// the opening kick of the next, with the same forces), then x += dt·v; and the forces, spent,
/// are zeroed for the next evaluation to add to (no pass of their own).
fn kick_drift(
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    f: &mut [[f64; 3]],
    inverse: &[f64],
    (h, dt): (f64, f64),
    closing: bool,
) {
    for (((x, v), f), w) in x.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(inverse) {
        let s = h * w;
        for c in 0..3 {
            if closing {
                v[c] += s * f[c];
            }
            v[c] += s * f[c];
            x[c] += dt * v[c];
        }
        *f = [0.0; 3];
    }
}

/// v += h·F/m, with `inverse` the 1/m of each body.
fn kick(v: &mut [[f64; 3]], f: &[[f64; 3]], inverse: &[f64], h: f64) {
    for ((v, f), w) in v.iter_mut().zip(f).zip(inverse) {
        let s = h * w;
        for c in 0..3 {
            v[c] += s * f[c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
    use lagra_checker::terms::Kind;

    fn pair(gamma: f64) -> (LagrangianGraph, State) {
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![
                Body { mass: 1.0, charge: 0.0, colour: [0.0; 2] },
                Body { mass: 3.0, charge: 0.0, colour: [0.0; 2] },
            ],
            terms: vec![TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![5.0, 1.0, gamma] }],
        };
        let s =
            State { step: 0, t: 0.0, x: vec![[0.0; 3], [1.7, 0.2, 0.0]], v: vec![[0.1, 0.3, 0.0], [-0.2, 0.0, 0.4]] };
        (LagrangianGraph::new(&model), s)
    }

    #[test]
    fn the_closing_kick_sees_the_force_at_its_own_velocity() {
        let (g, mut s) = pair(0.8);
        let mut vv = VelocityVerlet::new(&g, &s).unwrap();
        let dt = 0.01;
        for _ in 0..10 {
            vv.advance(&g, &mut s, dt).unwrap();
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
            let mut a = VelocityVerlet::new(&g, &one).unwrap();
            for _ in 0..300 {
                a.advance(&g, &mut one, 0.01).unwrap();
                tick(&mut one, 0.01);
            }
            let mut b = VelocityVerlet::new(&g, &many).unwrap();
            for until in [1, 2, 120, 120, 299, 300] {
                b.advance_to(&g, &mut many, 0.01, until).unwrap();
                assert_eq!(many.step, until);
            }
            assert_eq!(one, many);
            assert_eq!((a.f, a.potential.to_bits()), (b.f, b.potential.to_bits()));
        }
    }

    #[test]
    fn momentum_is_conserved_to_round_off() {
        let (g, mut s) = pair(0.3);
        let p = |s: &State| -> [f64; 3] { std::array::from_fn(|c| s.v[0][c] * 1.0 + s.v[1][c] * 3.0) };
        let p0 = p(&s);
        let mut vv = VelocityVerlet::new(&g, &s).unwrap();
        for _ in 0..1000 {
            vv.advance(&g, &mut s, 0.01).unwrap();
        }
        for (a, b) in p(&s).iter().zip(p0) {
            assert!((a - b).abs() < 1e-13, "{a} vs {b}");
        }
    }

    #[test]
    fn the_same_inputs_give_the_same_bits() {
        let run = || {
            let (g, mut s) = pair(0.5);
            let mut vv = VelocityVerlet::new(&g, &s).unwrap();
            for _ in 0..500 {
                vv.advance(&g, &mut s, 0.01).unwrap();
            }
            s
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn a_collapsed_bond_is_a_clear_error_not_nan() {
        let (g, mut s) = pair(0.0);
        s.x[1] = s.x[0];
        let err = VelocityVerlet::new(&g, &s).err().unwrap();
        assert_eq!(
            err.to_string(),
            "HarmonicBond: bodies 0, 1: at the same point, where the bond's direction is undefined"
        );
    }
}
