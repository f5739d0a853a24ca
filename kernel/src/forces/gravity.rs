//! Newtonian gravity: V = −G mᵢ mⱼ / r.

use super::{central, Paired};

pub struct Fast;

impl Paired for Fast {
    type Row = f64;
    const BODIES: bool = true;
    fn row(p: &[f64]) -> f64 {
        p[0]
    }
    #[inline(always)]
    fn eval(g: &f64, d: [f64; 3], [mi, mj, _, _]: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let gmm = g * mi * mj;
        central(d, |r| (-gmm / r, gmm / (r * r)))
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
