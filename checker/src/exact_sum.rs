//! Sums of binary64 values with no rounding until the end, so that the order of the terms
//! cannot change a bit of the result.
//!
//! Why it is exact: a finite binary64 value is an integer m (|m| < 2⁵³) times 2^(e − 1075), e
//! being its biased exponent (1 for the subnormals and zero). Each value adds its m to the
//! 128-bit integer of its exponent, which 2⁷⁴ values would be needed to overflow (at one a
//! nanosecond, 600 million years). The exact sum is then
//! Σ_e bin_e·2^(e − 1075), formed as one MPFR integer and rounded once, in the direction asked.
//! Infinities are kept apart (a +∞ makes the sum +∞ and so on); a NaN makes it NaN.

use rug::float::Round;
use rug::{Float, Integer};

/// Exponents 0..2047 (2047 is ∞ and NaN, kept apart).
const EXPONENTS: usize = 2047;

#[derive(Clone)]
pub struct ExactSum {
    bins: Box<[i128; EXPONENTS]>,
    pos_inf: bool,
    neg_inf: bool,
    nan: bool,
}

impl Default for ExactSum {
    fn default() -> Self {
        ExactSum { bins: Box::new([0; EXPONENTS]), pos_inf: false, neg_inf: false, nan: false }
    }
}

impl ExactSum {
    #[inline(always)]
    pub fn add(&mut self, x: f64) {
        let bits = x.to_bits();
        let e = (bits >> 52 & 0x7ff) as usize;
        if e == EXPONENTS {
            self.nan |= x.is_nan();
            self.pos_inf |= x == f64::INFINITY;
            self.neg_inf |= x == f64::NEG_INFINITY;
            return;
        }
        let m = (bits & ((1 << 52) - 1) | u64::from(e != 0) << 52) as i128;
        self.bins[e] += if bits >> 63 == 1 { -m } else { m };
    }

    /// Adds another sum's terms.
    pub fn merge(&mut self, o: &ExactSum) {
        self.bins.iter_mut().zip(o.bins.iter()).for_each(|(a, b)| *a += b);
        (self.pos_inf, self.neg_inf, self.nan) = (self.pos_inf | o.pos_inf, self.neg_inf | o.neg_inf, self.nan | o.nan);
    }

    /// The exact sum rounded once toward `round` (NaN for a NaN term or ∞ − ∞).
    pub fn total(&self, round: Round) -> f64 {
        match (self.nan, self.pos_inf, self.neg_inf) {
            (true, _, _) | (_, true, true) => return f64::NAN,
            (_, true, _) => return f64::INFINITY,
            (_, _, true) => return f64::NEG_INFINITY,
            _ => {}
        }
        // Σ bin_e·2^(max(e, 1) − 1), in units of 2⁻¹⁰⁷⁴
        let mut units = Integer::new();
        for (e, &b) in self.bins.iter().enumerate().filter(|(_, b)| **b != 0) {
            units += Integer::from(b) << (e.max(1) - 1) as u32;
        }
        let exact = Float::with_val(units.significant_bits().max(2), &units) >> 1074u32;
        exact.to_f64_round(round)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Any binary64 value, finite or not, from its bits (subnormals, zeros, extremes included).
    fn any_value() -> impl Strategy<Value = f64> {
        prop_oneof![any::<u64>().prop_map(f64::from_bits), -1e3f64..1e3, Just(f64::MIN_POSITIVE / 3.0)]
    }

    fn sum_of(xs: &[f64]) -> ExactSum {
        let mut s = ExactSum::default();
        xs.iter().for_each(|&x| s.add(x));
        s
    }

    proptest! {
        /// The total is the exact sum (MPFR at a width that spans every exponent) rounded
        /// each way, and does not depend on the order of the terms nor on how they were split.
        #[test]
        fn the_total_is_the_exact_sum_rounded_once(mut xs in prop::collection::vec(any_value(), 0..40), cut in 0usize..40) {
            let finite: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
            let exact = finite.iter().fold(Float::with_val(2200, 0), |a, &x| a + x);
            let s = sum_of(&finite);
            prop_assert_eq!(s.total(Round::Down), exact.to_f64_round(Round::Down));
            prop_assert_eq!(s.total(Round::Up), exact.to_f64_round(Round::Up));
            let whole = sum_of(&xs);
            xs.reverse();
            let (a, b) = xs.split_at(cut.min(xs.len()));
            let mut split = sum_of(a);
            split.merge(&sum_of(b));
            for round in [Round::Down, Round::Up] {
                prop_assert_eq!(whole.total(round).to_bits(), split.total(round).to_bits());
            }
        }
    }

    #[test]
    fn infinities_and_nan_are_kept_apart() {
        assert_eq!(sum_of(&[1.0, f64::INFINITY]).total(Round::Down), f64::INFINITY);
        assert_eq!(sum_of(&[f64::NEG_INFINITY, 1e308]).total(Round::Up), f64::NEG_INFINITY);
        assert!(sum_of(&[f64::NEG_INFINITY, f64::INFINITY]).total(Round::Up).is_nan());
        assert!(sum_of(&[1.0, f64::NAN]).total(Round::Down).is_nan());
        // cancellation a running binary64 sum would lose
        assert_eq!(sum_of(&[1e300, 1.0, -1e300, 2f64.powi(-1074)]).total(Round::Up), 1.0f64.next_up());
        assert_eq!(sum_of(&[1e300, 1.0, -1e300, 2f64.powi(-1074)]).total(Round::Down), 1.0);
        assert_eq!(sum_of(&[f64::MAX, f64::MAX]).total(Round::Down), f64::MAX);
        assert_eq!(sum_of(&[f64::MAX, f64::MAX]).total(Round::Up), f64::INFINITY);
        assert_eq!(sum_of(&[]).total(Round::Up), 0.0);
    }
}
