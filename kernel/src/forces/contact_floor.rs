//! Penalty floor: inside (δ = y₀ − y > 0), normal force kδ − c v_y and friction
//! −μkδ v_t/√(|v_t|² + s²); nothing outside.

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(p: &[f64], x: &[f64; 3], v: &[f64; 3], _m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        let (y0, k, c, mu, slip) = (p[0], p[1], p[2], p[3], p[4]);
        if x[1] >= y0 {
            return Ok(([0.0; 3], 0.0));
        }
        let depth = y0 - x[1];
        let normal = k * depth;
        let grip = mu * normal / (v[0] * v[0] + v[2] * v[2] + slip * slip).sqrt();
        Ok(([-grip * v[0], normal - c * v[1], -grip * v[2]], 0.5 * k * depth * depth))
    }
    fn velocity_dependent(p: &[f64]) -> bool {
        p[2] != 0.0 || p[3] != 0.0
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient_plus_dissipation(y in -2.0f64..2.0, k in 1.0f64..1e4, c in 0.0f64..10.0, mu in 0.0f64..1.0, slip in 0.01f64..1.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::ContactFloor, &[y, k, c, mu, slip], seed, 1.0);
        }
    }
}
