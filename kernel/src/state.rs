//! The dynamical state: time, positions, velocities (exact binary64 values, what the checker sees).

use lagra_checker::model::Snapshot;

#[derive(Clone, Debug, PartialEq)]
pub struct State {
    pub step: u64,
    pub t: f64,
    pub x: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
}

impl State {
    pub fn snapshot(&self) -> Snapshot<'_> {
        Snapshot { step: self.step, t: self.t, x: &self.x, v: &self.v }
    }

    /// The first body with a non-finite coordinate, if any.
    pub fn non_finite(&self) -> Option<usize> {
        self.x.iter().zip(&self.v).position(|(x, v)| x.iter().chain(v).any(|c| !c.is_finite()))
    }

    pub fn kinetic(&self, m: &[f64]) -> f64 {
        self.v.iter().zip(m).map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])).sum()
    }
}
