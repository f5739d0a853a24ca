//! Dual numbers over any `Real`: v + d·ε with ε² = 0. A term's one definition evaluated on them
//! gives its exact first derivative along the seeded direction; nested (`Dual<Dual<f64>>`) it
//! gives second derivatives — the force's own derivatives, which gradients need — with no
//! hand-written derivative anywhere.

use lagra_checker::real::Real;
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<T> {
    pub v: T,
    pub d: T,
}

/// `Real` for the parts of a dual: what `Dual<T>` needs of its `T` beyond the field
/// operations (a zero, to lift constants with).
pub trait Part: Real + Copy {
    fn zero(&self) -> Self {
        self.lift(0.0)
    }
}

impl<T: Real + Copy> Part for T {}

impl<T: Part> Dual<T> {
    /// A constant: no derivative.
    pub fn constant(v: T) -> Self {
        let d = v.zero();
        Dual { v, d }
    }

    pub fn new(v: T, d: T) -> Self {
        Dual { v, d }
    }

    /// f(self) from f(v) and f′(v): v' + f′(v)·d.
    fn chain(self, f: T, df: T) -> Self {
        Dual { v: f, d: df * self.d }
    }
}

impl<T: Part> Add for Dual<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Dual { v: self.v + o.v, d: self.d + o.d }
    }
}

impl<T: Part> Sub for Dual<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Dual { v: self.v - o.v, d: self.d - o.d }
    }
}

impl<T: Part> Mul for Dual<T> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Dual { v: self.v * o.v, d: self.d * o.v + self.v * o.d }
    }
}

impl<T: Part> Div for Dual<T> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        Dual { v: q, d: (self.d - q * o.d) / o.v }
    }
}

impl<T: Part> Neg for Dual<T> {
    type Output = Self;
    fn neg(self) -> Self {
        Dual { v: -self.v, d: -self.d }
    }
}

impl<T: Part> Real for Dual<T> {
    fn lift(&self, c: f64) -> Self {
        Dual::constant(self.v.lift(c))
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, s.lift(0.5) / s)
    }
    fn powi(self, n: i32) -> Self {
        let lower = if n == 0 { self.v.lift(0.0) } else { self.v.lift(n as f64) * self.v.powi(n - 1) };
        self.chain(self.v.powi(n), lower)
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), self.v.lift(1.0) / self.v)
    }
    /// Inside [−1, 1]; the clamp's flat parts outside have no slope.
    fn acos(self) -> Self {
        let one = self.v.lift(1.0);
        match (self.v.lt(&one.lift(-1.0)), one.lt(&self.v)) {
            (Some(false), Some(false)) => self.chain(self.v.acos(), -one / (one - self.v * self.v).sqrt()),
            _ => Dual::constant(self.v.acos()),
        }
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn atan2(self, x: Self) -> Self {
        let r2 = x.v * x.v + self.v * self.v;
        Dual { v: self.v.atan2(x.v), d: (x.v * self.d - self.v * x.d) / r2 }
    }
    /// A cutoff is decided on the values: the derivative is that of the branch taken (a pair
    /// at exactly its cutoff has none, and gets the one inside or beyond as the value says).
    fn lt(&self, bound: &Self) -> Option<bool> {
        self.v.lt(&bound.v)
    }
    fn hull(self, _: Self) -> Self {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type D2 = Dual<Dual<f64>>;

    /// x with first seed a and second seed b: the ε₁ε₂ part of f(x) is f″(x)·a·b.
    fn jet(x: f64) -> D2 {
        Dual::new(Dual::new(x, 1.0), Dual::new(1.0, 0.0))
    }

    #[test]
    fn nested_duals_give_second_derivatives() {
        let x = 0.7;
        for (f, d1, d2) in [
            ((jet(x).powi(-6)), -6.0 * x.powi(-7), 42.0 * x.powi(-8)),
            ((jet(x).exp()), x.exp(), x.exp()),
            ((jet(x).ln()), 1.0 / x, -1.0 / (x * x)),
            ((jet(x).sqrt()), 0.5 / x.sqrt(), -0.25 * x.powf(-1.5)),
            ((jet(x).cos()), -x.sin(), -x.cos()),
            ((jet(x).acos()), -1.0 / (1.0 - x * x).sqrt(), -x * (1.0 - x * x).powf(-1.5)),
            ((jet(x) / jet(x).sin()), (x.sin() - x * x.cos()) / x.sin().powi(2), {
                let (s, c) = (x.sin(), x.cos());
                (x * (1.0 + c * c) - 2.0 * s * c) / s.powi(3)
            }),
        ] {
            assert!((f.v.d - d1).abs() < 1e-12 * d1.abs().max(1.0), "{f:?} {d1}");
            assert!((f.d.v - d1).abs() < 1e-12 * d1.abs().max(1.0), "{f:?} {d1}");
            assert!((f.d.d - d2).abs() < 1e-11 * d2.abs().max(1.0), "{f:?} {d2}");
        }
    }

    #[test]
    fn atan2_has_the_slope_of_the_angle() {
        let (y, x) = (Dual::new(0.3, 1.0), Dual::constant(-0.8));
        let a = y.atan2(x);
        assert!((a.d - (-0.8) / (0.64 + 0.09)).abs() < 1e-15);
    }
}
