//! Coulomb: V = k qᵢ qⱼ / r.

use super::{Lane, Paired};

pub struct Fast;

impl Paired for Fast {
    type Row = f64;
    const BODIES: bool = true;
    fn row(p: &[f64]) -> f64 {
        p[0]
    }
    #[inline(always)]
    fn radial<L: Lane>(k: &f64, r2: L, [_, _, qi, qj]: [L; 4], _colour: L) -> (L, L) {
        let (a, r) = (qi * *k * qj, r2.sqrt());
        (a / r, -a / (r * r) / r)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 1e-3f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Coulomb, &[k], seed, 1.0);
        }

        #[test]
        fn near_contact_is_finite(k in 1e-3f64..10.0, tiny in 1e-100f64..1e-3, seed in any::<u64>()) {
            assert_matches_definition(Kind::Coulomb, &[k], seed, tiny);
        }
    }
}
