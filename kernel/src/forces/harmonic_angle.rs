//! Harmonic angle: V = ½ k (θ − θ₀)², θ at the middle body. With u = x₀ − x₁, w = x₂ − x₁,
//! c = cos θ: ∂c/∂x₀ = (ŵ − c û)/|u|, ∂c/∂x₂ = (û − c ŵ)/|w|, ∂c/∂x₁ = −(the two), and
//! F = k (θ − θ₀)/sin θ · ∂c/∂x.

use super::{cross, dot, sub, Bonded};

pub struct Fast;

impl Bonded<3> for Fast {
    fn eval(p: &[f64], x: &[[f64; 3]; 3], _v: &[[f64; 3]; 3]) -> Result<([[f64; 3]; 3], f64), &'static str> {
        let (k, theta0) = (p[0], p[1]);
        let (u, w) = (sub(&x[0], &x[1]), sub(&x[2], &x[1]));
        let (lu, lw) = (dot(&u, &u).sqrt(), dot(&w, &w).sqrt());
        if lu == 0.0 || lw == 0.0 {
            return Err("two bodies at the same point: the angle is undefined");
        }
        let (uh, wh) = (u.map(|c| c / lu), w.map(|c| c / lw));
        let cos = dot(&u, &w) / (dot(&u, &u) * dot(&w, &w)).sqrt();
        let sin = dot(&cross(&uh, &wh), &cross(&uh, &wh)).sqrt();
        if sin == 0.0 {
            return Err("in a line: the direction of the angle's force is undefined");
        }
        let theta = cos.clamp(-1.0, 1.0).acos();
        let s = k * (theta - theta0) / sin;
        let f0: [f64; 3] = std::array::from_fn(|c| s * (wh[c] - cos * uh[c]) / lu);
        let f2: [f64; 3] = std::array::from_fn(|c| s * (uh[c] - cos * wh[c]) / lw);
        let f1 = std::array::from_fn(|c| -(f0[c] + f2[c]));
        Ok(([f0, f1, f2], 0.5 * k * (theta - theta0) * (theta - theta0)))
    }
}

#[cfg(test)]
mod tests {
    use crate::forces::dual::assert_matches_definition;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn force_is_minus_gradient(k in 0.1f64..100.0, theta0 in 0.0f64..std::f64::consts::PI, seed in any::<u64>()) {
            assert_matches_definition(Kind::HarmonicAngle, &[k, theta0], seed, 1.0);
        }
    }

    #[test]
    fn a_straight_angle_is_a_clear_error() {
        use super::{Bonded, Fast};
        let x = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(
            Fast::eval(&[1.0, 2.0], &x, &[[0.0; 3]; 3]).unwrap_err(),
            "in a line: the direction of the angle's force is undefined"
        );
    }
}
