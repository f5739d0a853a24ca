//! A uniform field: F_i = m_i g. Several fields add into one.

use super::{Force, Frame, Singularity};
use lagra_checker::model::TermInstance;

pub struct UniformField {
    g: [f64; 3],
}

impl UniformField {
    pub fn new(t: &[&TermInstance]) -> Self {
        let g = std::array::from_fn(|c| t.iter().map(|t| t.params[c]).sum());
        UniformField { g }
    }
}

impl Force for UniformField {
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = 0.0;
        for ((x, &m), fi) in s.x.iter().zip(s.m).zip(f.iter_mut()) {
            for c in 0..3 {
                fi[c] += m * self.g[c];
                energy -= m * self.g[c] * x[c];
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
        fn force_is_minus_gradient(g in prop::array::uniform3(-20.0f64..20.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::UniformAcceleration, &g, seed, 1.0);
        }
    }
}
