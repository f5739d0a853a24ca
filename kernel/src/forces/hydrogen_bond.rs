//! Hydrogen bond: V = E(r) c⁴, E = D(5s¹² − 6s¹⁰), s = R₀/r, c = cos θ at the hydrogen;
//! ∂V/∂x = c⁴ E′(r) ∂r/∂x + 4c³ E ∂c/∂x, E′(r) = 60D(s¹⁰ − s¹²)/r.

use super::{dot, sub, Bonded};

pub struct Fast;

impl Bonded<3> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 3], _v: &[[f64; 3]; 3]) -> Result<([[f64; 3]; 3], f64), &'static str> {
        let (d, r0) = (p[0], p[1]);
        let (u, w, da) = (sub(&x[0], &x[1]), sub(&x[2], &x[1]), sub(&x[2], &x[0]));
        let (lu, lw, r) = (dot(&u, &u).sqrt(), dot(&w, &w).sqrt(), dot(&da, &da).sqrt());
        if lu == 0.0 || lw == 0.0 || r == 0.0 {
            return Err("two bodies at the same point: the hydrogen bond is undefined");
        }
        let (uh, wh) = (u.map(|k| k / lu), w.map(|k| k / lw));
        let c = dot(&uh, &wh);
        let s2 = r0 * r0 / (r * r);
        let (s10, s12) = (s2.powi(5), s2.powi(6));
        let radial = d * (5.0 * s12 - 6.0 * s10);
        let slope = 60.0 * d * (s10 - s12) / r;
        let (c3, c4) = (c * c * c, c * c * c * c);
        // −∂V/∂x for the donor (0) and acceptor (2); the hydrogen takes the rest
        let along = c4 * slope / r;
        let f0: [f64; 3] = std::array::from_fn(|k| along * da[k] - 4.0 * c3 * radial * (wh[k] - c * uh[k]) / lu);
        let f2: [f64; 3] = std::array::from_fn(|k| -along * da[k] - 4.0 * c3 * radial * (uh[k] - c * wh[k]) / lw);
        let f1 = std::array::from_fn(|k| -(f0[k] + f2[k]));
        Ok(([f0, f1, f2], radial * c4))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(d in 0.1f64..10.0, r0 in 0.5f64..4.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::HydrogenBond, &[d, r0], seed, 1.0);
        }
    }
}
