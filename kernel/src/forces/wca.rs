//! WCA: Lennard-Jones + ε inside 2^{1/6}σ, nothing beyond.

use super::lennard_jones::Lj;
use super::{Jet, Lane, Paired};
use lagra_checker::terms::wca::MINIMUM;

pub struct Fast;

impl Paired for Fast {
    type Row = Lj;
    fn row(p: &[f64]) -> Lj {
        Lj::new(p[0], p[1], MINIMUM * p[1], -p[0])
    }
    fn reach2(lj: &Lj) -> f64 {
        lj.reach2()
    }
    #[inline(always)]
    fn radial<L: Lane>(lj: &Lj, r2: L, _: [L; 4], _colour: L) -> (L, L) {
        lj.shifted_at(r2)
    }
    /// Inside 2^{1/6}σ the force is Lennard-Jones's (the cutoff moves with σ, but the force is
    /// zero there, so no pair's force jumps); the energy's + ε adds 1 to ∂V/∂ε (and V is zero at
    /// the cutoff, so its move adds nothing).
    #[inline(always)]
    fn jet<L: Lane>(lj: &Lj, p: &[f64], r2: L) -> Option<Jet<L>> {
        let jet = lj.jet_at(p, r2);
        Some(Jet { dv: [jet.dv[0] + L::splat(1.0), jet.dv[1], jet.dv[2]], ..jet })
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        /// σ from 1 to 8 puts the random pair on both sides of 2^{1/6}σ.
        #[test]
        fn force_is_minus_gradient(eps in 0.1f64..5.0, sigma in 1.0f64..8.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Wca, &[eps, sigma], seed, 1.0);
        }
    }
}
