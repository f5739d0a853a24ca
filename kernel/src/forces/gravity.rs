//! Newtonian gravity over all pairs: F_i = G m_i m_j (x_j − x_i)/r³, F_j = −F_i.

use super::{apply_pair, Force, Frame, Singularity};
use lagra_checker::model::{Model, TermInstance};
use nalgebra::Vector3;

pub struct PairGravity {
    /// G·m_i·m_j for every pair i < j, in loop order.
    strength: Vec<f64>,
    n: usize,
}

impl PairGravity {
    pub fn new(t: &[&TermInstance], model: &Model) -> Self {
        let g: f64 = t.iter().map(|t| t.params[0]).sum();
        let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
        let n = m.len();
        let strength = (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| g * m[i] * m[j]).collect();
        PairGravity { strength, n }
    }
}

impl Force for PairGravity {
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = 0.0;
        let mut p = 0;
        for i in 0..self.n {
            for j in i + 1..self.n {
                let d = Vector3::from(s.x[j]) - Vector3::from(s.x[i]);
                let r2 = d.norm_squared();
                if r2 == 0.0 {
                    return Err(Singularity { term: "Gravity", i, j });
                }
                let r = r2.sqrt();
                let gmm = self.strength[p];
                apply_pair(f, i, j, (d * (gmm / (r2 * r))).into());
                energy -= gmm / r;
                p += 1;
            }
        }
        Ok(energy)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(g in 1e-3f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Gravity, &[g], seed, 1.0);
        }
    }
}
