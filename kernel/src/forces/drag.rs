//! Linear drag: F = −γ v, no potential energy.

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(p: &[f64], _x: &[f64; 3], v: &[f64; 3], _m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        Ok((v.map(|c| -p[0] * c), 0.0))
    }
    fn velocity_dependent(p: &[f64]) -> bool {
        p[0] != 0.0
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_dissipation_gradient(gamma in 0.0f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Drag, &[gamma], seed, 1.0);
        }
    }
}
