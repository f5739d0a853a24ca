//! Dihedral: V = k (1 + cos(nφ − δ)), φ = atan2(|b₂| b₁·n₂, n₁·n₂). With the gradients of φ
//! (after Blondel & Karplus 1996, for bᵢ = xᵢ − xᵢ₋₁): ∂φ/∂x₀ = −|b₂| n₁/|n₁|²,
//! ∂φ/∂x₃ = |b₂| n₂/|n₂|², and with p = b₁·b₂/|b₂|², q = b₃·b₂/|b₂|²:
//! ∂φ/∂x₁ = −(p + 1) ∂φ/∂x₀ + q ∂φ/∂x₃, ∂φ/∂x₂ = p ∂φ/∂x₀ − (q + 1) ∂φ/∂x₃
//! (they sum to zero: translation invariance).

use super::{cross, dot, sub, Bonded};

pub struct Fast;

impl Bonded<4> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 4], _v: &[[f64; 3]; 4]) -> Result<([[f64; 3]; 4], f64), &'static str> {
        let (k, n, phase) = (p[0], p[1], p[2]);
        let (b1, b2, b3) = (sub(&x[1], &x[0]), sub(&x[2], &x[1]), sub(&x[3], &x[2]));
        let (n1, n2) = (cross(&b1, &b2), cross(&b2, &b3));
        let (b22, n11, n22) = (dot(&b2, &b2), dot(&n1, &n1), dot(&n2, &n2));
        if b22 == 0.0 || n11 == 0.0 || n22 == 0.0 {
            return Err("three bodies in a line: the dihedral is undefined");
        }
        let lb2 = b22.sqrt();
        let phi = (lb2 * dot(&b1, &n2)).atan2(dot(&n1, &n2));
        let dv = -k * n * (n * phi - phase).sin();
        let g0 = n1.map(|c| -lb2 / n11 * c);
        let g3 = n2.map(|c| lb2 / n22 * c);
        let (pp, qq) = (dot(&b1, &b2) / b22, dot(&b3, &b2) / b22);
        let g1: [f64; 3] = std::array::from_fn(|c| -(pp + 1.0) * g0[c] + qq * g3[c]);
        let g2: [f64; 3] = std::array::from_fn(|c| pp * g0[c] - (qq + 1.0) * g3[c]);
        let f = |g: [f64; 3]| g.map(|c| -dv * c);
        Ok(([f(g0), f(g1), f(g2), f(g3)], k * (1.0 + (n * phi - phase).cos())))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 0.1f64..10.0, n in 1u8..=6, phase in 0.0f64..std::f64::consts::TAU, seed in any::<u64>()) {
            assert_matches_definition(Kind::Dihedral, &[k, f64::from(n), phase], seed, 1.0);
        }
    }
}
