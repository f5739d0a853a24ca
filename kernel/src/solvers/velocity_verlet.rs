//! Velocity Verlet: kick ½dt, drift dt, evaluate, kick ½dt. Symplectic and time-reversible for
//! conservative forces, and it conserves linear and angular momentum exactly in exact
//! arithmetic when the forces are pairwise and central.
//!
//! With velocity-dependent (dissipative) forces the closing kick is implicit,
//! v₁ = v½ + ½dt·F(x₁, v₁)/m, solved by fixed-point iteration, so that each kick sees the force
//! at the velocity of its own end of the step. Evaluating the damping at the half-step velocity
//! instead would lag it by ½dt and make the dissipated energy first-order wrong.

use crate::forces::Singularity;
use crate::graph::LagrangianGraph;
use crate::state::State;

/// The contraction factor of the iteration is ½dt·γ/m; for any dt the integrator is otherwise
/// stable at, a few iterations reach a fixed point to the last bit.
const MAX_ITERATIONS: usize = 8;

pub struct VelocityVerlet {
    f: Vec<[f64; 3]>,
    /// Potential energy at the current state (the witness of the last evaluation).
    pub potential: f64,
}

impl VelocityVerlet {
    pub fn new(g: &LagrangianGraph, s: &State) -> Result<Self, Singularity> {
        let mut f = vec![[0.0; 3]; s.x.len()];
        let potential = g.forces(s, &mut f)?;
        Ok(VelocityVerlet { f, potential })
    }

    pub fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Singularity> {
        let h = 0.5 * dt;
        kick(&mut s.v, &self.f, &g.masses, h);
        for (x, v) in s.x.iter_mut().zip(&s.v) {
            for c in 0..3 {
                x[c] += dt * v[c];
            }
        }
        let half = if g.dissipative() { Some(s.v.clone()) } else { None };
        self.potential = g.forces(s, &mut self.f)?;
        kick(&mut s.v, &self.f, &g.masses, h);
        if let Some(half) = half {
            for _ in 0..MAX_ITERATIONS {
                self.potential = g.forces(s, &mut self.f)?;
                let guess = std::mem::replace(&mut s.v, half.clone());
                kick(&mut s.v, &self.f, &g.masses, h);
                if s.v == guess {
                    break;
                }
            }
        }
        s.step += 1;
        s.t = s.step as f64 * dt;
        Ok(())
    }
}

fn kick(v: &mut [[f64; 3]], f: &[[f64; 3]], m: &[f64], h: f64) {
    for ((v, f), m) in v.iter_mut().zip(f).zip(m) {
        for c in 0..3 {
            v[c] += h * f[c] / m;
        }
    }
}
