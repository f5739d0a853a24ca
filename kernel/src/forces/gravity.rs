//! Newtonian gravity: on body i, G mᵢ mⱼ d / r³ with d = xⱼ − xᵢ.

use super::Paired;

pub struct Fast;

impl Paired for Fast {
    fn eval(p: &[f64], d: [f64; 3], [mi, mj, _, _]: [f64; 4]) -> Result<([f64; 3], f64), &'static str> {
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if r2 == 0.0 {
            return Err("at the same point, where gravity is infinite");
        }
        let r = r2.sqrt();
        let gmm = p[0] * mi * mj;
        let s = gmm / (r2 * r);
        Ok((d.map(|c| c * s), -gmm / r))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(g in 1e-3f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Gravity, &[g], seed, 1.0);
        }
    }
}
