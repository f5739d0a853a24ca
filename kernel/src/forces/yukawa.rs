//! Screened Coulomb: V = k qᵢ qⱼ e^{−r/λ} / r.

use super::{Lane, Paired};

pub struct Fast;

impl Paired for Fast {
    /// k and λ.
    type Row = [f64; 2];
    const BODIES: bool = true;
    fn row(p: &[f64]) -> [f64; 2] {
        [p[0], p[1]]
    }
    #[inline(always)]
    fn radial<L: Lane>(p: &[f64; 2], r2: L, [_, _, qi, qj]: [L; 4], _colour: L) -> (L, L) {
        screened(qi * p[0] * qj, p[1], r2)
    }
}

/// a·e^(−r/λ)/r and its s, at r².
#[inline(always)]
pub(crate) fn screened<L: Lane>(a: L, range: f64, r2: L) -> (L, L) {
    let r = r2.sqrt();
    let v = a * (-r / L::splat(range)).exp() / r;
    (v, -v * (L::splat(1.0 / range) + L::splat(1.0) / r) / r)
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
