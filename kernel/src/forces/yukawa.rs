//! Screened Coulomb: V = k qᵢ qⱼ e^{−r/λ} / r.

use super::{central, Paired};

pub struct Fast;

impl Paired for Fast {
    /// k and λ.
    type Row = [f64; 2];
    const BODIES: bool = true;
    fn row(p: &[f64]) -> [f64; 2] {
        [p[0], p[1]]
    }
    #[inline(always)]
    fn eval(
        p: &[f64; 2],
        d: [f64; 3],
        [_, _, qi, qj]: [f64; 4],
        _colour: f64,
    ) -> Result<([f64; 3], f64), &'static str> {
        screened(p[0] * qi * qj, p[1], d)
    }
}

/// V = a e^{−r/λ}/r, dV/dr = −V (1/λ + 1/r).
#[inline(always)]
pub(crate) fn screened(a: f64, range: f64, d: [f64; 3]) -> Result<([f64; 3], f64), &'static str> {
    central(d, |r| {
        let v = a * (-r / range).exp() / r;
        (v, -v * (1.0 / range + 1.0 / r))
    })
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 1e-3f64..10.0, range in 0.1f64..10.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::Yukawa, &[k, range], seed, 1.0);
        }
    }
}
