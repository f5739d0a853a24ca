//! Boris's integrator (Boris 1970) for charges in magnetic fields: the velocity-dependent
//! force F = m ω × v only turns the velocity, so instead of kicking with it the solver rotates by
//! it, with the Cayley rotation of parameter τ = ω dt/2 — an exact rotation, so |v| is kept to
//! round-off whatever dt — and kicks with every other force (the positional ones) around it.
//!
//! The classic scheme keeps velocities at half steps: v_{n+½} = K(½dt) R(τ) K(½dt) v_{n−½}.
//! Here the state is synchronous (x and v at the same step, as the checker and the trace need):
//! the rotation is split into two halves, R(τ) = R(τ_h)² with τ_h = τ/(1 + √(1 + |τ|²)) (the
//! tangent of half the angle), and a step is R(τ_h) K(½dt) D(dt) K(½dt) R(τ_h). Repeated, it is
//! the classic sequence exactly (…K R K D K R K D…), shifted by half a rotation; symmetric, so
//! second order and time-reversible.

use super::{Carried, Evaluated, Failure, Solver};
use crate::forces::{cross, Singularity};
use crate::graph::LagrangianGraph;
use crate::state::State;

pub struct Boris {
    /// The positional forces at the current state (what the kicks use).
    positional: Vec<[f64; 3]>,
    /// Each body's ω at the current positions.
    w: Vec<[f64; 3]>,
    /// All forces at the current state, the magnetic ones included (for the meters).
    at: Evaluated,
}

impl Boris {
    pub fn new(g: &LagrangianGraph, s: &State, at: Evaluated) -> Result<Boris, Singularity> {
        let mut b = Boris { positional: vec![[0.0; 3]; s.x.len()], w: vec![[0.0; 3]; s.x.len()], at };
        g.positional_forces(s, &mut b.positional)?;
        g.gyration(s, &mut b.w);
        Ok(b)
    }

    /// Half of the Boris rotation over `dt`, at the current ω.
    fn half_turn(&self, v: &mut [[f64; 3]], dt: f64) {
        for (v, w) in v.iter_mut().zip(&self.w) {
            let tau = w.map(|c| 0.5 * dt * c);
            let t2 = tau[0] * tau[0] + tau[1] * tau[1] + tau[2] * tau[2];
            let half = tau.map(|c| c / (1.0 + (1.0 + t2).sqrt()));
            rotate(v, &half);
        }
    }
}

/// The Cayley rotation of parameter t (by the angle 2·atan|t| about t): v' = v + t × v,
/// v ← v + s × v' with s = 2t/(1 + |t|²).
fn rotate(v: &mut [f64; 3], t: &[f64; 3]) {
    let t2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
    let tv = cross(t, v);
    let prime: [f64; 3] = std::array::from_fn(|c| v[c] + tv[c]);
    let s = t.map(|c| 2.0 * c / (1.0 + t2));
    let sp = cross(&s, &prime);
    for c in 0..3 {
        v[c] += sp[c];
    }
}

impl Solver for Boris {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let h = 0.5 * dt;
        self.half_turn(&mut s.v, dt);
        g.kick(&mut s.v, &self.positional, h);
        g.drift(s, dt);
        self.at.potential = g.positional_forces(s, &mut self.positional)?;
        g.gyration(s, &mut self.w);
        g.kick(&mut s.v, &self.positional, h);
        self.half_turn(&mut s.v, dt);
        // the total force at the new state, for whoever reads it: F + m ω × v
        for (((f, p), (v, w)), m) in
            self.at.f.iter_mut().zip(&self.positional).zip(s.v.iter().zip(&self.w)).zip(&g.masses)
        {
            let turn = cross(w, v);
            *f = std::array::from_fn(|c| p[c] + m * turn[c]);
        }
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }
}

#[cfg(test)]
mod tests {
    use super::rotate;

    #[test]
    fn two_half_turns_are_one_boris_turn() {
        let tau = [0.3, -0.2, 0.9];
        let t2: f64 = tau.iter().map(|c| c * c).sum();
        let half = tau.map(|c| c / (1.0 + (1.0 + t2).sqrt()));
        let (mut a, mut b) = ([1.0, 2.0, -0.5], [1.0, 2.0, -0.5]);
        rotate(&mut a, &tau);
        rotate(&mut b, &half);
        rotate(&mut b, &half);
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-14, "{a:?} {b:?}");
        }
        let norm = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>();
        assert!((norm(a) - 5.25).abs() < 1e-14);
    }
}
