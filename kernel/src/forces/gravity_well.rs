//! A fixed point mass: F = −G M m (x − c)/r³.

use super::{central, Field};

pub struct Fast;

impl Field for Fast {
    fn eval(p: &[f64], x: &[f64; 3], _v: &[f64; 3], m: f64, _q: f64) -> Result<([f64; 3], f64), &'static str> {
        let gmm = p[0] * p[1] * m;
        // central() takes d = (other − self): here the well's centre minus the body
        central(std::array::from_fn(|c| p[2 + c] - x[c]), |r| (-gmm / r, gmm / (r * r)))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(g in 0.1f64..10.0, mass in 0.1f64..10.0, c in prop::array::uniform3(4.0f64..6.0), seed in any::<u64>()) {
            assert_matches_definition(Kind::GravityWell, &[g, mass, c[0], c[1], c[2]], seed, 1.0);
        }
    }
}
