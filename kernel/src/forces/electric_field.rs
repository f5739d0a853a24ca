//! A uniform electric field: F = q E.

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(e: &[f64], x: &[f64; 3], _v: &[f64; 3], _m: f64, q: f64) -> Result<([f64; 3], f64), &'static str> {
        Ok(([q * e[0], q * e[1], q * e[2]], -q * (e[0] * x[0] + e[1] * x[1] + e[2] * x[2])))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(e in prop::array::uniform3(-20.0f64..20.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::ElectricField, &e, seed, 1.0);
        }
    }
}
