//! FENE bond: V = −½ k R₀² ln(1 − r²/R₀²); the force on body 1 is −k d / (1 − r²/R₀²).

use super::Bonded;

pub struct Fast;

impl Bonded<2> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 2], _v: &[[f64; 3]; 2]) -> Result<([[f64; 3]; 2], f64), &'static str> {
        let (k, r02) = (p[0], p[1] * p[1]);
        let d: [f64; 3] = std::array::from_fn(|c| x[1][c] - x[0][c]);
        let slack = 1.0 - (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / r02;
        if slack <= 0.0 {
            return Err("stretched to R0 or beyond, where FENE is infinite");
        }
        let s = k / slack;
        Ok(([d.map(|c| c * s), d.map(|c| -c * s)], -0.5 * k * r02 * slack.ln()))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        /// Random bodies lie within 11 of each other, so R₀ ≥ 11 keeps the bond finite.
        #[test]
        fn force_is_minus_gradient(k in 0.1f64..100.0, r0 in 11.0f64..20.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::FeneBond, &[k, r0], seed, 1.0);
        }
    }

    #[test]
    fn overstretched_is_a_clear_error() {
        use super::{Bonded, Fast};
        let e = Fast::eval(&[30.0, 1.5], &[[0.0; 3], [1.5, 0.0, 0.0]], &[[0.0; 3]; 2]).unwrap_err();
        assert_eq!(e, "stretched to R0 or beyond, where FENE is infinite");
    }
}
