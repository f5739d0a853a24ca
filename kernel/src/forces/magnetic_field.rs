//! A uniform magnetic field: F = q v × B (the closing kick of the solver solves for it
//! implicitly; with the explicit opening kick the pair keeps |v⊥| exactly).

use super::{cross, Field};

pub struct Fast;

impl Field for Fast {
    fn eval(b: &[f64], _x: &[f64; 3], v: &[f64; 3], _m: f64, q: f64) -> Result<([f64; 3], f64), &'static str> {
        Ok((cross(v, &[b[0], b[1], b[2]]).map(|c| q * c), 0.0))
    }
    fn velocity_dependent(b: &[f64]) -> bool {
        b.iter().any(|&c| c != 0.0)
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_the_euler_lagrange_force(b in prop::array::uniform3(-5.0f64..5.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::MagneticField, &b, seed, 1.0);
        }
    }
}
