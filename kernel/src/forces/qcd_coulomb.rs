//! Toy colour force: V = (cᵢ·cⱼ)(4α/r − 3σr), dV/dr = −(cᵢ·cⱼ)(4α/r² + 3σ).

use super::{central, Paired};

pub struct Fast;

impl Paired for Fast {
    /// α and σ.
    type Row = [f64; 2];
    const COLOUR: bool = true;
    fn row(p: &[f64]) -> [f64; 2] {
        [p[0], p[1]]
    }
    #[inline(always)]
    fn eval(p: &[f64; 2], d: [f64; 3], _: [f64; 4], colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let (alpha, sigma) = (p[0], p[1]);
        central(d, |r| (colour * (4.0 * alpha / r - 3.0 * sigma * r), -colour * (4.0 * alpha / (r * r) + 3.0 * sigma)))
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
