//! Toy nuclear force: V = −g e^{−r/λ} / r, whatever the charges.

use super::yukawa::screened;
use super::{Lane, Paired};

pub struct Fast;

impl Paired for Fast {
    /// g and λ.
    type Row = [f64; 2];
    fn row(p: &[f64]) -> [f64; 2] {
        [p[0], p[1]]
    }
    #[inline(always)]
    fn radial<L: Lane>(p: &[f64; 2], r2: L, _: [L; 4], _colour: L) -> (L, L) {
        screened(L::splat(-p[0]), p[1], r2)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(g in 1e-3f64..10.0, range in 0.1f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::NuclearYukawa, &[g, range], seed, 1.0);
        }
    }
}
