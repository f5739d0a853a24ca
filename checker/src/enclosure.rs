//! What the monitor needs of a rigorous number beyond [`Real`]: absolute value, maximum, and
//! its bounds as binary64 rounded outward. Two instances: binary64 intervals
//! ([`Outward`](crate::outward::Outward), fast) and MPFR intervals at a chosen precision (for
//! deciding what binary64 intervals cannot).

use crate::mpfi::Mpfi;
use crate::real::Real;

pub trait Enclosure: Real {
    fn abs(self) -> Self;
    fn max(self, o: Self) -> Self;
    /// `(lo, hi)` with lo ≤ every enclosed value ≤ hi; `(NaN, NaN)` when nothing is enclosed.
    fn bounds(&self) -> (f64, f64);
}

impl Enclosure for Mpfi {
    fn abs(self) -> Self {
        Mpfi::abs(self)
    }
    fn max(self, o: Self) -> Self {
        Mpfi::max(self, o)
    }
    fn bounds(&self) -> (f64, f64) {
        Mpfi::bounds(self)
    }
}
