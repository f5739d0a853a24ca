//! A frictionless penalty wall: behind the plane n̂·x = d, at depth δ = d − n̂·x, the force kδ n̂.

use super::Field;

pub struct Fast;

impl Field for Fast {
    fn eval(p: &[f64], x: &[f64; 3], _v: &[f64; 3], _m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let n = [p[0] / norm, p[1] / norm, p[2] / norm];
        let depth = p[3] - super::dot(&n, x);
        if depth <= 0.0 {
            return Ok(([0.0; 3], 0.0));
        }
        Ok((n.map(|c| p[4] * depth * c), 0.5 * p[4] * depth * depth))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(n in prop::array::uniform3(-1.0f64..1.0), d in -2.0f64..2.0, k in 1.0f64..1e4, seed in any::<u64>()) {
            prop_assume!(n.iter().map(|c| c * c).sum::<f64>() > 1e-2);
            assert_matches_definition(Kind::Wall, &[n[0], n[1], n[2], d, k], seed, 1.0);
        }
    }
}
