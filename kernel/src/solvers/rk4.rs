//! Classic fourth-order Runge–Kutta on (x, v): the non-symplectic baseline. Accurate per step,
//! but its energy error drifts secularly, and it conserves linear momentum only (not angular
//! momentum) exactly.

use super::{Carried, Evaluated, Failure, Solver};
use crate::graph::LagrangianGraph;
use crate::state::State;

type Vecs = Vec<[f64; 3]>;

pub struct Rk4 {
    pub at: Evaluated,
}

/// x + h·dx and v + h·dv, as a state for a force evaluation.
fn shifted(s: &State, dx: &Vecs, dv: &Vecs, h: f64) -> State {
    let add = |a: &Vecs, b: &Vecs| a.iter().zip(b).map(|(a, b)| std::array::from_fn(|c| a[c] + h * b[c])).collect();
    State { step: s.step, t: s.t, x: add(&s.x, dx), v: add(&s.v, dv), chain: vec![], spin: vec![] }
}

/// Accelerations at a state.
fn accel(g: &LagrangianGraph, s: &State, f: &mut Vecs) -> Result<Vecs, Failure> {
    g.forces(s, f)?;
    Ok(f.iter().zip(&g.masses).map(|(f, m)| f.map(|c| c / m)).collect())
}

impl Solver for Rk4 {
    /// Leaves the forces at the new state and the potential there.
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let f = &mut self.at.f;
        let (x1, v1) = (s.v.clone(), accel(g, s, f)?);
        let s2 = shifted(s, &x1, &v1, dt / 2.0);
        let (x2, v2) = (s2.v.clone(), accel(g, &s2, f)?);
        let s3 = shifted(s, &x2, &v2, dt / 2.0);
        let (x3, v3) = (s3.v.clone(), accel(g, &s3, f)?);
        let s4 = shifted(s, &x3, &v3, dt);
        let (x4, v4) = (s4.v.clone(), accel(g, &s4, f)?);
        let combine = |y: &mut Vecs, k: [&Vecs; 4]| {
            for (i, yi) in y.iter_mut().enumerate() {
                for c in 0..3 {
                    yi[c] += dt / 6.0 * (k[0][i][c] + 2.0 * k[1][i][c] + 2.0 * k[2][i][c] + k[3][i][c]);
                }
            }
        };
        combine(&mut s.x, [&x1, &x2, &x3, &x4]);
        combine(&mut s.v, [&v1, &v2, &v3, &v4]);
        self.at.potential = g.forces(s, f)?;
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
    }
}
