//! Springs, with damping along the bond: F_j = −(k(r − r₀) + γṙ) r̂, F_i = −F_j.

use super::{apply_pair, Force, Frame, Singularity};
use lagra_checker::model::TermInstance;
use nalgebra::Vector3;

pub struct HarmonicBonds {
    ends: Vec<(usize, usize)>,
    k: Vec<f64>,
    r0: Vec<f64>,
    gamma: Vec<f64>,
}

impl HarmonicBonds {
    pub fn new(t: &[&TermInstance]) -> Self {
        HarmonicBonds {
            ends: t.iter().map(|t| (t.sites[0], t.sites[1])).collect(),
            k: t.iter().map(|t| t.params[0]).collect(),
            r0: t.iter().map(|t| t.params[1]).collect(),
            gamma: t.iter().map(|t| t.params[2]).collect(),
        }
    }
}

impl Force for HarmonicBonds {
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = 0.0;
        for (b, &(i, j)) in self.ends.iter().enumerate() {
            let d = Vector3::from(s.x[j]) - Vector3::from(s.x[i]);
            let r = d.norm();
            if r == 0.0 {
                return Err(Singularity { term: "HarmonicBond", i, j });
            }
            let u = d / r;
            let stretch = r - self.r0[b];
            let rdot = (Vector3::from(s.v[j]) - Vector3::from(s.v[i])).dot(&u);
            let along = self.k[b] * stretch + self.gamma[b] * rdot;
            apply_pair(f, i, j, (u * along).into());
            energy += 0.5 * self.k[b] * stretch * stretch;
        }
        Ok(energy)
    }

    fn dissipative(&self) -> bool {
        self.gamma.iter().any(|&g| g != 0.0)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient_plus_dissipation(k in 0.1f64..100.0, r0 in 0.0f64..3.0, gamma in 0.0f64..2.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicBond, &[k, r0, gamma], seed, 1.0);
        }

        #[test]
        fn near_collapse_is_finite(k in 0.1f64..100.0, r0 in 0.5f64..3.0, tiny in 1e-140f64..1e-6, seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicBond, &[k, r0, 0.5], seed, tiny);
        }
    }
}
