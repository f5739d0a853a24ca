//! Reaction-field Coulomb: V = k qᵢ qⱼ (1/r + k_rf r² − c_rf) inside r_c;
//! dV/dr / r = k qᵢ qⱼ (2 k_rf − 1/r³).

use super::lennard_jones::cut;
use super::Paired;

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
    #[inline(always)]
    fn eval(p: &Row, d: [f64; 3], [_, _, qi, qj]: [f64; 4], _colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let (krf, crf) = (p.krf, p.crf);
        let a = p.k * qi * qj;
        cut(d, p.rc2, |r2| {
            let r = r2.sqrt();
            (a * (1.0 / r + krf * r2 - crf), a * (2.0 * krf - 1.0 / (r2 * r)))
        })
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
