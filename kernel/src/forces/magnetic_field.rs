//! A uniform magnetic field: F = q v × B = m ω × v with ω = −qB/m (velocity Verlet solves its
//! closing kick implicitly; with the explicit opening kick the pair keeps |v⊥| exactly; Boris
//! rotates by ω instead).

use super::{cross, Field};

pub struct Fast;

impl Field for Fast {
    fn eval(b: &[f64], _x: &[f64; 3], v: &[f64; 3], _m: f64, q: f64) -> Result<([f64; 3], f64), &'static str> {
        Ok((cross(v, &[b[0], b[1], b[2]]).map(|c| q * c), 0.0))
    }
    fn velocity_dependent(b: &[f64]) -> bool {
        b.iter().any(|&c| c != 0.0)
    }
    const GYROSCOPIC: bool = true;
    fn gyration(b: &[f64], _x: &[f64; 3], m: f64, q: f64) -> [f64; 3] {
        [b[0], b[1], b[2]].map(|c| -q * c / m)
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

        /// The rotation Boris applies is the force: m ω × v = q v × B.
        #[test]
        fn the_gyration_is_the_force(
            b in prop::array::uniform3(-5.0f64..5.0),
            v in prop::array::uniform3(-5.0f64..5.0),
            m in 0.1f64..10.0,
            q in -3.0f64..3.0,
        ) {
            use crate::forces::{cross, Field};
            let w = super::Fast::gyration(&b, &[0.0; 3], m, q);
            let (f, _) = super::Fast::eval(&b, &[0.0; 3], &v, m, q).unwrap();
            for (a, e) in cross(&w, &v).map(|c| m * c).iter().zip(f) {
                prop_assert!((a - e).abs() <= 1e-13 * (1.0 + e.abs()), "{a} vs {e}");
            }
        }
    }
}
