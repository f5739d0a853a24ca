//! Intervals with MPFR endpoints at a chosen precision, every operation rounded outward (the
//! lower endpoint down, the upper up), so a result is an enclosure like inari's, only narrower.
//! An interval with a NaN endpoint encloses nothing; every operation on it stays so.

use crate::real::Real;
use inari::Interval;
use rug::float::Round;
use rug::ops::{AssignRound, Pow};
use rug::Float;
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Debug)]
pub struct Mpfi {
    lo: Float,
    hi: Float,
}

fn down<T>(prec: u32, v: T) -> Float
where
    Float: AssignRound<T, Round = Round, Ordering = std::cmp::Ordering>,
{
    Float::with_val_round(prec, v, Round::Down).0
}

fn up<T>(prec: u32, v: T) -> Float
where
    Float: AssignRound<T, Round = Round, Ordering = std::cmp::Ordering>,
{
    Float::with_val_round(prec, v, Round::Up).0
}

impl Mpfi {
    /// The binary64 interval `[lo, hi]` (exactly: every binary64 value is representable at ≥ 53
    /// bits); empty unless lo ≤ hi.
    pub fn from_bounds(prec: u32, (lo, hi): (f64, f64)) -> Mpfi {
        if !(lo <= hi) {
            return Mpfi::empty(prec);
        }
        Mpfi { lo: Float::with_val(prec, lo), hi: Float::with_val(prec, hi) }
    }

    pub fn point(prec: u32, c: f64) -> Mpfi {
        Mpfi { lo: Float::with_val(prec, c), hi: Float::with_val(prec, c) }
    }

    fn empty(prec: u32) -> Mpfi {
        Mpfi { lo: Float::with_val(prec, f64::NAN), hi: Float::with_val(prec, f64::NAN) }
    }

    fn prec(&self) -> u32 {
        self.lo.prec()
    }

    fn is_empty(&self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }

    /// The smallest interval holding all of `candidates`, each given rounded down and up.
    fn hull(prec: u32, candidates: [(Float, Float); 4]) -> Mpfi {
        if candidates.iter().any(|(l, h)| l.is_nan() || h.is_nan()) {
            return Mpfi::empty(prec);
        }
        let lo = candidates.iter().map(|c| &c.0).min_by(|a, b| a.total_cmp(b)).cloned();
        let hi = candidates.iter().map(|c| &c.1).max_by(|a, b| a.total_cmp(b)).cloned();
        Mpfi {
            lo: lo.unwrap_or_else(|| Float::with_val(prec, f64::NAN)),
            hi: hi.unwrap_or_else(|| Float::with_val(prec, f64::NAN)),
        }
    }

    pub fn abs(self) -> Mpfi {
        if self.is_empty() || self.lo >= 0 {
            self
        } else if self.hi <= 0 {
            -self
        } else {
            let hi = if -self.lo.clone() > self.hi { -self.lo } else { self.hi };
            Mpfi { lo: Float::with_val(hi.prec(), 0), hi }
        }
    }

    pub fn max(self, o: Mpfi) -> Mpfi {
        if self.is_empty() || o.is_empty() {
            return Mpfi::empty(self.prec());
        }
        Mpfi { lo: self.lo.max(&o.lo), hi: self.hi.max(&o.hi) }
    }

    /// `f` applied to a non-decreasing function's endpoints, each rounded outward.
    fn increasing(self, f: impl Fn(&Float, Round) -> Float) -> Mpfi {
        if self.is_empty() {
            return self;
        }
        Mpfi { lo: f(&self.lo, Round::Down), hi: f(&self.hi, Round::Up) }
    }

    /// Through a binary64 interval: sound, but no narrower than binary64 (for functions the
    /// definitions apply only to parameters, such as a dihedral's phase).
    fn via_binary64(self, f: impl Fn(Interval) -> Interval) -> Mpfi {
        let p = self.prec();
        let (lo, hi) = self.bounds();
        match Interval::try_from((lo, hi)) {
            Ok(iv) => Mpfi::from_bounds(p, (f(iv).inf(), f(iv).sup())),
            Err(_) => Mpfi::empty(p),
        }
    }

    pub fn bounds(&self) -> (f64, f64) {
        if self.is_empty() {
            (f64::NAN, f64::NAN)
        } else {
            (self.lo.to_f64_round(Round::Down), self.hi.to_f64_round(Round::Up))
        }
    }
}

impl Add for Mpfi {
    type Output = Mpfi;
    fn add(self, o: Mpfi) -> Mpfi {
        let p = self.prec();
        Mpfi { lo: down(p, &self.lo + &o.lo), hi: up(p, &self.hi + &o.hi) }
    }
}

impl Sub for Mpfi {
    type Output = Mpfi;
    fn sub(self, o: Mpfi) -> Mpfi {
        let p = self.prec();
        Mpfi { lo: down(p, &self.lo - &o.hi), hi: up(p, &self.hi - &o.lo) }
    }
}

impl Neg for Mpfi {
    type Output = Mpfi;
    fn neg(self) -> Mpfi {
        Mpfi { lo: -self.hi, hi: -self.lo }
    }
}

impl Mul for Mpfi {
    type Output = Mpfi;
    fn mul(self, o: Mpfi) -> Mpfi {
        let p = self.prec();
        let prod = |a: &Float, b: &Float| (down(p, a * b), up(p, a * b));
        Mpfi::hull(p, [prod(&self.lo, &o.lo), prod(&self.lo, &o.hi), prod(&self.hi, &o.lo), prod(&self.hi, &o.hi)])
    }
}

impl Div for Mpfi {
    type Output = Mpfi;
    fn div(self, o: Mpfi) -> Mpfi {
        let p = self.prec();
        if o.is_empty() || self.is_empty() {
            return Mpfi::empty(p);
        }
        if o.lo <= 0 && o.hi >= 0 {
            return Mpfi { lo: Float::with_val(p, f64::NEG_INFINITY), hi: Float::with_val(p, f64::INFINITY) };
        }
        let quo = |a: &Float, b: &Float| (down(p, a / b), up(p, a / b));
        Mpfi::hull(p, [quo(&self.lo, &o.lo), quo(&self.lo, &o.hi), quo(&self.hi, &o.lo), quo(&self.hi, &o.hi)])
    }
}

impl Real for Mpfi {
    fn lift(&self, c: f64) -> Self {
        Mpfi::point(self.prec(), c)
    }

    fn exp(self) -> Self {
        let p = self.prec();
        self.increasing(|x, r| Float::with_val_round(p, x.exp_ref(), r).0)
    }

    fn ln(self) -> Self {
        let p = self.prec();
        if self.is_empty() || self.hi < 0 {
            return Mpfi::empty(p);
        }
        let lo = if self.lo > 0 { down(p, self.lo.ln_ref()) } else { Float::with_val(p, f64::NEG_INFINITY) };
        Mpfi { lo, hi: up(p, self.hi.ln_ref()) }
    }

    fn acos(self) -> Self {
        let p = self.prec();
        if self.is_empty() || self.lo > 1 || self.hi < -1 {
            return Mpfi::empty(p);
        }
        // decreasing on [−1, 1]: the upper end gives the lower bound
        let clamp = |x: &Float| x.clone().clamp(&-1, &1);
        Mpfi { lo: down(p, clamp(&self.hi).acos_ref()), hi: up(p, clamp(&self.lo).acos_ref()) }
    }

    fn cos(self) -> Self {
        self.via_binary64(Interval::cos)
    }

    fn sin(self) -> Self {
        self.via_binary64(Interval::sin)
    }

    fn atan2(self, x: Self) -> Self {
        let (lo, hi) = x.bounds();
        match Interval::try_from((lo, hi)) {
            Ok(xi) => self.via_binary64(|y| y.atan2(xi)),
            Err(_) => Mpfi::empty(self.prec()),
        }
    }

    fn lt(&self, bound: &Self) -> Option<bool> {
        if self.is_empty() || bound.is_empty() {
            None
        } else if self.hi < bound.lo {
            Some(true)
        } else if self.lo >= bound.hi {
            Some(false)
        } else {
            None
        }
    }

    fn hull(self, o: Self) -> Self {
        if self.is_empty() || o.is_empty() {
            return Mpfi::empty(self.prec());
        }
        Mpfi { lo: self.lo.min(&o.lo), hi: self.hi.max(&o.hi) }
    }

    fn sqrt(self) -> Self {
        let p = self.prec();
        if self.is_empty() || self.hi < 0 {
            return Mpfi::empty(p);
        }
        let lo = if self.lo > 0 { down(p, self.lo.sqrt_ref()) } else { Float::with_val(p, 0) };
        Mpfi { lo, hi: up(p, self.hi.sqrt_ref()) }
    }

    fn powi(self, n: i32) -> Self {
        let p = self.prec();
        if n < 0 {
            return Mpfi::point(p, 1.0) / self.powi(-n);
        }
        if self.is_empty() {
            return self;
        }
        let pow = |x: &Float, r: Round| Float::with_val_round(p, x.pow(n), r).0;
        if n % 2 == 1 || self.lo >= 0 {
            Mpfi { lo: pow(&self.lo, Round::Down), hi: pow(&self.hi, Round::Up) }
        } else if self.hi <= 0 {
            Mpfi { lo: pow(&self.hi, Round::Down), hi: pow(&self.lo, Round::Up) }
        } else {
            let m = self.clone().abs().hi;
            Mpfi { lo: Float::with_val(p, 0), hi: pow(&m, Round::Up) }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn contains(m: &Mpfi, x: &Float) -> bool {
        m.lo <= *x && *x <= m.hi
    }

    proptest! {
        /// Each operation's result encloses the 2048-bit value of the operation on the midpoints.
        #[test]
        fn operations_enclose(a in -1e6f64..1e6, b in -1e6f64..1e6, n in -4i32..5) {
            let (x, y) = (Mpfi::point(64, a), Mpfi::point(64, b));
            let (fa, fb) = (Float::with_val(2048, a), Float::with_val(2048, b));
            prop_assert!(contains(&(x.clone() + y.clone()), &Float::with_val(2048, &fa + &fb)));
            prop_assert!(contains(&(x.clone() - y.clone()), &Float::with_val(2048, &fa - &fb)));
            prop_assert!(contains(&(x.clone() * y.clone()), &Float::with_val(2048, &fa * &fb)));
            if b != 0.0 {
                prop_assert!(contains(&(x.clone() / y.clone()), &Float::with_val(2048, &fa / &fb)));
            }
            if a >= 0.0 {
                prop_assert!(contains(&x.clone().sqrt(), &Float::with_val(2048, fa.sqrt_ref())));
            }
            if a != 0.0 || n >= 0 {
                prop_assert!(contains(&x.clone().powi(n), &Float::with_val(2048, (&fa).pow(n))));
            }
            let small = Mpfi::point(64, a / 1e5);
            prop_assert!(contains(&small.exp(), &Float::with_val(2048, Float::with_val(2048, a / 1e5).exp_ref())));
            if a > 0.0 {
                prop_assert!(contains(&x.clone().ln(), &Float::with_val(2048, fa.ln_ref())));
            }
            let c = Mpfi::point(64, (a / 1e6).clamp(-1.0, 1.0));
            prop_assert!(contains(&c.clone().acos(), &Float::with_val(2048, Float::with_val(2048, (a / 1e6).clamp(-1.0, 1.0)).acos_ref())));
            prop_assert!(contains(&x.clone().cos(), &Float::with_val(2048, fa.cos_ref())));
            prop_assert!(contains(&x.clone().sin(), &Float::with_val(2048, fa.sin_ref())));
            prop_assert!(contains(&x.atan2(y), &Float::with_val(2048, fa.atan2_ref(&fb))));
        }
    }

    #[test]
    fn outward_rounding_brackets_a_third() {
        let third = Mpfi::point(128, 1.0) / Mpfi::point(128, 3.0);
        let (lo, hi) = third.bounds();
        assert!(lo < hi && lo <= 1.0 / 3.0 && 1.0 / 3.0 <= hi);
    }

    #[test]
    fn square_of_a_sign_changing_interval_starts_at_zero() {
        let x = Mpfi::from_bounds(64, (-2.0, 1.0));
        assert_eq!(x.powi(2).bounds(), (0.0, 4.0));
    }

    #[test]
    fn division_by_an_interval_holding_zero_is_everything() {
        let x = Mpfi::from_bounds(64, (-1.0, 1.0));
        assert_eq!((Mpfi::point(64, 1.0) / x).bounds(), (f64::NEG_INFINITY, f64::INFINITY));
    }
}
