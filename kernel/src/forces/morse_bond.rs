//! Morse bond: V = D (1 − e)², e = e^{−a(r − r₀)}; dV/dr = 2 D a e (1 − e).

use super::{central, Bonded};

pub struct Fast;

impl Bonded<2> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 2], _v: &[[f64; 3]; 2]) -> Result<([[f64; 3]; 2], f64), &'static str> {
        let (dd, a, r0) = (p[0], p[1], p[2]);
        let d: [f64; 3] = std::array::from_fn(|c| x[1][c] - x[0][c]);
        let (f0, v) = central(d, |r| {
            let e = (-a * (r - r0)).exp();
            (dd * (1.0 - e) * (1.0 - e), 2.0 * dd * a * e * (1.0 - e))
        })?;
        Ok(([f0, f0.map(|c| -c)], v))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(d in 0.1f64..10.0, a in 0.3f64..3.0, r0 in 0.5f64..3.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::MorseBond, &[d, a, r0], seed, 1.0);
        }
    }
}
