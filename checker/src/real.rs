//! The scalar every term definition is written over.
//!
//! A definition is written once, generic over [`Real`], and instantiated as `f64` (reference
//! value), [`Interval`] (the checker's rigorous enclosure), [`rug::Float`] (high-precision
//! reference) and [`Dimension`](crate::units::Dimension) (its dimensional type). The trait holds
//! only what the definitions use; each operation must be exact for `f64`-like instances up to
//! their own rounding and *sound* (an enclosure) for `Interval`.

use inari::Interval;
use rug::Float;
use std::ops::{Add, Div, Mul, Neg, Sub};

pub trait Real:
    Clone + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// The exact binary64 value `c` as a constant of the same kind (and precision) as `self`.
    fn lift(&self, c: f64) -> Self;
    fn sqrt(self) -> Self;
    /// `self^n`; for intervals this is tighter than repeated multiplication (x² ≥ 0).
    fn powi(self, n: i32) -> Self;
}

impl Real for f64 {
    fn lift(&self, c: f64) -> Self {
        c
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
}

impl Real for Interval {
    fn lift(&self, c: f64) -> Self {
        point(c)
    }
    fn sqrt(self) -> Self {
        Interval::sqrt(self)
    }
    fn powi(self, n: i32) -> Self {
        Interval::powi(self, n)
    }
}

/// The degenerate interval `[c, c]`; `c` must be finite (the model and states are checked first).
pub fn point(c: f64) -> Interval {
    Interval::try_from((c, c)).unwrap_or(Interval::ENTIRE)
}

impl Real for Float {
    fn lift(&self, c: f64) -> Self {
        Float::with_val(self.prec(), c)
    }
    fn sqrt(self) -> Self {
        Float::sqrt(self)
    }
    fn powi(self, n: i32) -> Self {
        rug::ops::Pow::pow(self, n)
    }
}

/// A point in space as three reals.
pub type Vec3<R> = [R; 3];

pub fn sub3<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> Vec3<R> {
    [a[0].clone() - b[0].clone(), a[1].clone() - b[1].clone(), a[2].clone() - b[2].clone()]
}

pub fn dot3<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> R {
    a[0].clone() * b[0].clone() + a[1].clone() * b[1].clone() + a[2].clone() * b[2].clone()
}

/// |a|², written with `powi` so that an interval enclosure stays non-negative and tight.
pub fn norm2<R: Real>(a: &Vec3<R>) -> R {
    a[0].clone().powi(2) + a[1].clone().powi(2) + a[2].clone().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_square_is_tighter_than_product() {
        let x = Interval::try_from((-1.0, 2.0)).unwrap();
        assert_eq!(x.powi(2).inf(), 0.0);
        assert_eq!((x * x).inf(), -2.0);
    }

    #[test]
    fn lift_keeps_precision() {
        let x = Float::with_val(300, 1.5);
        assert_eq!(x.lift(0.1).prec(), 300);
        assert_eq!(x.lift(0.1).to_f64(), 0.1);
    }

    #[test]
    fn point_of_nonfinite_is_entire() {
        assert!(point(f64::NAN).is_entire());
    }
}
