//! A uniform field: F = m g.

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(g: &[f64], x: &[f64; 3], _v: &[f64; 3], m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        Ok(([m * g[0], m * g[1], m * g[2]], -m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2])))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(g in prop::array::uniform3(-20.0f64..20.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::UniformAcceleration, &g, seed, 1.0);
        }
    }
}
