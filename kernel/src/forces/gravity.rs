//! Newtonian gravity: V = −G mᵢ mⱼ / r.

use super::{Lane, Paired};

pub struct Fast;

impl Paired for Fast {
    type Row = f64;
    const BODIES: bool = true;
    fn row(p: &[f64]) -> f64 {
        p[0]
    }
    #[inline(always)]
    fn radial<L: Lane>(g: &f64, r2: L, [mi, mj, _, _]: [L; 4], _colour: L) -> (L, L) {
        let (gmm, r) = (mi * *g * mj, r2.sqrt());
        (-gmm / r, gmm / (r * r) / r)
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
