//! The dynamical state: time, positions, velocities, exact binary64 values. The type is the
//! checker's own, so what the kernel steps is what the checker reads.

pub use lagra_checker::states::State;

use crate::sum::Sum;

/// Kinetic energy in f64: the witness the trace prints (the checker's is an enclosure).
pub fn kinetic(s: &State, m: &[f64]) -> f64 {
    s.v.iter().zip(m).map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])).collect::<Sum>().value()
}
