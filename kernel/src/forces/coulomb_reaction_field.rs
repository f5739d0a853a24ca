//! Reaction-field Coulomb: V = k qᵢ qⱼ (1/r + k_rf r² − c_rf) inside r_c;
//! dV/dr / r = k qᵢ qⱼ (2 k_rf − 1/r³).

use super::{Lane, Paired};

pub struct Fast;

/// k, r_c² and the reaction-field constants k_rf, c_rf.
#[derive(Clone, Copy)]
pub struct Row {
    k: f64,
    rc2: f64,
    krf: f64,
    crf: f64,
}

impl Paired for Fast {
    type Row = Row;
    const BODIES: bool = true;
    fn row(p: &[f64]) -> Row {
        let (rc, e) = (p[1], p[2]);
        let krf = (e - 1.0) / ((2.0 * e + 1.0) * rc * rc * rc);
        Row { k: p[0], rc2: rc * rc, krf, crf: 1.0 / rc + krf * rc * rc }
    }
    fn reach2(p: &Row) -> f64 {
        p.rc2
    }
    #[inline(always)]
    fn radial<L: Lane>(p: &Row, r2: L, [_, _, qi, qj]: [L; 4], _colour: L) -> (L, L) {
        let (a, r, one) = (qi * p.k * qj, r2.sqrt(), L::splat(1.0));
        (a * (one / r + r2 * p.krf - p.crf), a * (L::splat(2.0 * p.krf) - one / (r2 * r)))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 0.1f64..10.0, rc in 2.0f64..12.0, e in 1.0f64..100.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::CoulombReactionField, &[k, rc, e], seed, 1.0);
        }
    }
}
