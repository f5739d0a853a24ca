//! Toy colour force: V = (cᵢ·cⱼ)(4α/r − 3σr), dV/dr = −(cᵢ·cⱼ)(4α/r² + 3σ).

use super::{Lane, Paired};

pub struct Fast;

impl Paired for Fast {
    /// α and σ.
    type Row = [f64; 2];
    const COLOUR: bool = true;
    fn row(p: &[f64]) -> [f64; 2] {
        [p[0], p[1]]
    }
    #[inline(always)]
    fn radial<L: Lane>(p: &[f64; 2], r2: L, _: [L; 4], colour: L) -> (L, L) {
        let (alpha4, sigma3, r) = (L::splat(4.0 * p[0]), 3.0 * p[1], r2.sqrt());
        (colour * (alpha4 / r - r * sigma3), -colour * (alpha4 / (r * r) + sigma3) / r)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(alpha in 0.01f64..2.0, sigma in 0.01f64..2.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::QcdCoulomb, &[alpha, sigma], seed, 1.0);
        }
    }
}
