//! Harmonic trap: F = −k (x − c).

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(p: &[f64], x: &[f64; 3], _v: &[f64; 3], _m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        let d: [f64; 3] = std::array::from_fn(|c| x[c] - p[1 + c]);
        Ok((d.map(|c| -p[0] * c), 0.5 * p[0] * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 0.1f64..100.0, c in prop::array::uniform3(-5.0f64..5.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicTrap, &[k, c[0], c[1], c[2]], seed, 1.0);
        }
    }
}
