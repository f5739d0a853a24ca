//! Springs, with damping along the bond: F₁ = −(k(r − r₀) + γṙ) r̂, F₀ = −F₁.

use super::Bonded;

pub struct Fast;

impl Bonded<2> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 2], v: &[[f64; 3]; 2]) -> Result<([[f64; 3]; 2], f64), &'static str> {
        let (k, r0, gamma) = (p[0], p[1], p[2]);
        let d: [f64; 3] = std::array::from_fn(|c| x[1][c] - x[0][c]);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if r == 0.0 {
            return Err("at the same point, where the bond's direction is undefined");
        }
        // one division per bond; the damping's ṙ only where there is damping (not even a + 0)
        let inv = 1.0 / r;
        let stretch = r - r0;
        let spring = k * stretch;
        let s = if gamma == 0.0 {
            spring * inv
        } else {
            (spring + gamma * (0..3).map(|c| (v[1][c] - v[0][c]) * d[c]).sum::<f64>() * inv) * inv
        };
        let a = d.map(|c| c * s);
        Ok(([a, a.map(|c| -c)], 0.5 * k * stretch * stretch))
    }

    fn velocity_dependent(p: &[f64]) -> bool {
        p[2] != 0.0
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient_plus_dissipation(k in 0.1f64..100.0, r0 in 0.0f64..3.0, gamma in 0.0f64..2.0, seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicBond, &[k, r0, gamma], seed, 1.0);
        }

        #[test]
        fn near_collapse_is_finite(k in 0.1f64..100.0, r0 in 0.5f64..3.0, tiny in 1e-140f64..1e-6, seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicBond, &[k, r0, 0.5], seed, tiny);
        }
    }
}
