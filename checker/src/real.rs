//! The scalar every term definition is written over.
//!
//! A definition is written once, generic over [`Real`], and instantiated as `f64` (reference
//! value), [`Outward`](crate::outward::Outward) (the checker's rigorous binary64 enclosure),
//! [`Mpfi`](crate::mpfi::Mpfi) (its MPFR enclosure), [`rug::Float`] (high-precision reference)
//! and [`Dimension`](crate::units::Dimension) (its dimensional type). The trait holds only what
//! the definitions use; each operation must be exact for `f64`-like instances up to their own
//! rounding and *sound* (an enclosure) for the enclosures.

#[cfg(test)]
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
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    /// The angle in [0, π] whose cosine is `self` (clamped to [−1, 1]).
    fn acos(self) -> Self;
    fn cos(self) -> Self;
    fn sin(self) -> Self;
    /// The angle of the point (x, self) in (−π, π].
    fn atan2(self, x: Self) -> Self;
    /// Whether `self < bound`: always decided for a point, `None` when an enclosure straddles.
    fn lt(&self, bound: &Self) -> Option<bool>;
    /// The smallest value of the kind holding both; only reached when `lt` was undecided.
    fn hull(self, o: Self) -> Self;
}

/// `yes()` if `cond`, `no()` if not, and for an undecided enclosure the hull of both: the cutoff
/// primitive, exact for points and sound for intervals. Lazy: a pair beyond its cutoff costs
/// one comparison.
#[inline]
pub fn select<R: Real>(cond: Option<bool>, yes: impl FnOnce() -> R, no: impl FnOnce() -> R) -> R {
    match cond {
        Some(true) => yes(),
        Some(false) => no(),
        None => yes().hull(no()),
    }
}

/// The methods a type already has under the same name and signature.
macro_rules! same_named {
    ($t:ty: $($unary:ident),*) => {
        $(fn $unary(self) -> Self {
            <$t>::$unary(self)
        })*
        fn atan2(self, x: Self) -> Self {
            <$t>::atan2(self, x)
        }
    };
}

impl Real for f64 {
    same_named!(f64: sqrt, exp, ln, cos, sin);
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
    fn lift(&self, c: f64) -> Self {
        c
    }
    fn acos(self) -> Self {
        f64::acos(self.clamp(-1.0, 1.0))
    }
    fn lt(&self, bound: &Self) -> Option<bool> {
        (!self.is_nan() && !bound.is_nan()).then(|| self < bound)
    }
    fn hull(self, _: Self) -> Self {
        f64::NAN
    }
}

/// The 1024-bit reference of the soundness tests (round-to-nearest: a value, not an enclosure;
/// the checker's own high precision is `mpfi::Mpfi`, which rounds outward).
#[cfg(test)]
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
    fn exp(self) -> Self {
        Float::exp(self)
    }
    fn ln(self) -> Self {
        Float::ln(self)
    }
    fn acos(self) -> Self {
        Float::acos(self.clamp(&-1, &1))
    }
    fn cos(self) -> Self {
        Float::cos(self)
    }
    fn sin(self) -> Self {
        Float::sin(self)
    }
    fn atan2(self, x: Self) -> Self {
        Float::atan2(self, &x)
    }
    fn lt(&self, bound: &Self) -> Option<bool> {
        (!self.is_nan() && !bound.is_nan()).then(|| self < bound)
    }
    fn hull(self, o: Self) -> Self {
        Float::with_val(self.prec(), f64::NAN) + o
    }
}

/// A point in space as three reals.
pub type Vec3<R> = [R; 3];

#[inline(always)]
pub fn sub3<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> Vec3<R> {
    [a[0].clone() - b[0].clone(), a[1].clone() - b[1].clone(), a[2].clone() - b[2].clone()]
}

#[inline]
pub fn dot3<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> R {
    a[0].clone() * b[0].clone() + a[1].clone() * b[1].clone() + a[2].clone() * b[2].clone()
}

pub fn cross3<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> Vec3<R> {
    std::array::from_fn(|c| {
        let (i, j) = ((c + 1) % 3, (c + 2) % 3);
        a[i].clone() * b[j].clone() - a[j].clone() * b[i].clone()
    })
}

/// |a|², written with `powi` so that an interval enclosure stays non-negative and tight.
#[inline(always)]
pub fn norm2<R: Real>(a: &Vec3<R>) -> R {
    a[0].clone().powi(2) + a[1].clone().powi(2) + a[2].clone().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lift_keeps_precision() {
        let x = Float::with_val(300, 1.5);
        assert_eq!(x.lift(0.1).prec(), 300);
        assert_eq!(x.lift(0.1).to_f64(), 0.1);
    }
}
