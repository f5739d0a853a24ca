//! The decision: the only code that can make a [`Pass`].
//!
//! A [`Judge`] is fed, checkpoint by checkpoint, a rigorous enclosure of how far the claimed
//! quantity has moved and the tolerance it must stay within. A checkpoint whose enclosure lies
//! wholly above the tolerance is a certified failure; one that straddles it leaves the claim
//! undecided; only when every checkpoint lies wholly within does `finish` return a `Pass`.
//! `Pass` has private fields and no constructor outside this module (LCF style).

use crate::claims::ClaimKind;
use serde::{Deserialize, Serialize};

/// Where an enclosure `[lo, hi]` of a deviation lies against its tolerance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// hi ≤ tol: every enclosed value is within tolerance.
    Within,
    /// lo > tol: every enclosed value breaks it.
    Beyond,
    /// Neither, or the enclosure or tolerance is not a number: undecided.
    Straddles,
}

/// The one comparison every verdict rests on. NaN anywhere is `Straddles`, never `Within`.
pub fn classify(lo: f64, hi: f64, tol: f64) -> Class {
    if lo.is_nan() || hi.is_nan() || tol.is_nan() || lo > hi || tol < 0.0 || tol == f64::INFINITY {
        Class::Straddles
    } else if hi <= tol {
        Class::Within
    } else if lo > tol {
        Class::Beyond
    } else {
        Class::Straddles
    }
}

/// The soundness of [`classify`], one property body run four ways: by proptest and by
/// exhaustive enumeration (the tests below), by Kani (`proofs`, where Kani is installed), and as
/// an SMT-LIB model by z3 (`checker/proofs/classify.smt2`). For any enclosure `[lo, hi]`, any
/// tolerance and any value `x` in the enclosure: `Within` ⇒ x ≤ tol, `Beyond` ⇒ x > tol, and a
/// NaN anywhere ⇒ `Straddles`. (Comparisons of binary64 values are exact, so what holds for
/// every binary64 x in the enclosure holds for every real x in it.)
#[cfg(any(test, kani, kani_typecheck))]
pub fn classify_is_sound(lo: f64, hi: f64, tol: f64, x: f64) -> bool {
    let c = classify(lo, hi, tol);
    let inside = lo <= x && x <= hi;
    let sound = match c {
        Class::Within => !inside || x <= tol,
        Class::Beyond => !inside || x > tol,
        Class::Straddles => true,
    };
    sound && (!(lo.is_nan() || hi.is_nan() || tol.is_nan()) || c == Class::Straddles)
}

#[cfg(any(kani, kani_typecheck))]
mod proofs {
    // Under kani_typecheck nothing calls the harnesses; under kani, Kani does.
    #![cfg_attr(kani_typecheck, allow(dead_code))]
    use crate::any;

    /// For every binary64 lo, hi, tol and x.
    #[cfg_attr(kani, kani::proof)]
    pub fn classify_is_sound_for_every_binary64() {
        assert!(super::classify_is_sound(any(), any(), any(), any()));
    }
}

/// The binary precision of the arithmetic that decided a checkpoint: 53 for binary64
/// intervals, more for MPFR intervals.
pub type Precision = u32;
pub const BINARY64: Precision = 53;
/// Binary64 intervals added up from the ranks' parts of a run in domains (`quantities::Parts`).
/// Numbered below binary64, so that a verdict's precision (the highest any checkpoint needed)
/// stays binary64's; a re-check from the whole states derives another enclosure of the same
/// quantity, which must meet this one.
pub const PARTS: Precision = 52;

#[derive(Clone, Debug, Serialize)]
pub struct Pass {
    claim: ClaimKind,
    /// Certified upper bound of the deviation over all checkpoints.
    bound: f64,
    /// The largest tolerance any checkpoint was held to.
    tol: f64,
    checkpoints: u64,
    /// The highest precision any checkpoint needed to be decided.
    precision: Precision,
}

impl Pass {
    pub fn claim(&self) -> ClaimKind {
        self.claim
    }
    pub fn bound(&self) -> f64 {
        self.bound
    }
    pub fn tol(&self) -> f64 {
        self.tol
    }
    pub fn checkpoints(&self) -> u64 {
        self.checkpoints
    }
    pub fn precision(&self) -> Precision {
        self.precision
    }
}

/// A checkpoint where the deviation is certainly (`Fail`) or possibly (`Undecided`) too large.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Breach {
    pub claim: ClaimKind,
    pub step: u64,
    pub lower: f64,
    pub upper: f64,
    pub tol: f64,
    pub precision: Precision,
}

#[derive(Clone, Debug, Serialize)]
#[serde(tag = "status")]
pub enum Verdict {
    #[serde(rename = "PASS")]
    Pass(Pass),
    #[serde(rename = "FAIL")]
    Fail(Breach),
    #[serde(rename = "UNDECIDED")]
    Undecided(Breach),
    /// A claim about the model, not the trajectory, that does not hold.
    #[serde(rename = "FAIL")]
    Refuted { claim: ClaimKind, reason: String },
}

impl Verdict {
    pub fn claim(&self) -> ClaimKind {
        match self {
            Verdict::Pass(p) => p.claim,
            Verdict::Fail(b) | Verdict::Undecided(b) => b.claim,
            Verdict::Refuted { claim, .. } => *claim,
        }
    }
    pub fn is_pass(&self) -> bool {
        matches!(self, Verdict::Pass(_))
    }
}

/// A claim's running summary: its checkpoints, the worst bound and tolerance of those within
/// it, and the first it could not decide. A restart file carries it (`monitor::Carried`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Judge {
    claim: ClaimKind,
    checkpoints: u64,
    bound: f64,
    tol: f64,
    precision: Precision,
    undecided: Option<Breach>,
}

impl Judge {
    pub fn new(claim: ClaimKind) -> Self {
        // A deviation may be negative (a distance inside its bounds): the bound starts at −∞.
        Judge { claim, checkpoints: 0, bound: f64::NEG_INFINITY, tol: 0.0, precision: BINARY64, undecided: None }
    }

    pub fn claim(&self) -> ClaimKind {
        self.claim
    }

    /// Admits one checkpoint: `[lo, hi]` encloses the deviation, which must be ≤ `tol`;
    /// `precision` is that of the arithmetic that produced the enclosure.
    pub fn admit(&mut self, step: u64, (lo, hi): (f64, f64), tol: f64, precision: Precision) -> Result<(), Breach> {
        self.checkpoints += 1;
        let breach = Breach { claim: self.claim, step, lower: lo, upper: hi, tol, precision };
        match classify(lo, hi, tol) {
            Class::Beyond => return Err(breach),
            Class::Straddles => {
                self.undecided.get_or_insert(breach);
            }
            Class::Within => {
                self.bound = self.bound.max(hi);
                self.tol = self.tol.max(tol);
                self.precision = self.precision.max(precision);
            }
        }
        Ok(())
    }

    pub fn finish(self) -> Verdict {
        match self.undecided {
            Some(b) => Verdict::Undecided(b),
            None if self.checkpoints == 0 => Verdict::Undecided(Breach {
                claim: self.claim,
                step: 0,
                lower: f64::NAN,
                upper: f64::NAN,
                tol: self.tol,
                precision: self.precision,
            }),
            None => Verdict::Pass(Pass {
                claim: self.claim,
                bound: self.bound,
                tol: self.tol,
                checkpoints: self.checkpoints,
                precision: self.precision,
            }),
        }
    }
}

/// A claim about the model alone: it passes with zero deviation or is refuted with a reason.
pub fn decide_static(claim: ClaimKind, holds: Result<(), String>) -> Verdict {
    match holds {
        Ok(()) => Verdict::Pass(Pass { claim, bound: 0.0, tol: 0.0, checkpoints: 0, precision: BINARY64 }),
        Err(reason) => Verdict::Refuted { claim, reason },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn iv(a: f64, b: f64) -> (f64, f64) {
        (a, b)
    }

    #[test]
    fn inside_passes_with_the_largest_upper_bound() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        j.admit(1, iv(0.0, 1e-7), 1e-5, BINARY64).unwrap();
        j.admit(2, iv(1e-7, 3e-7), 1e-5, BINARY64).unwrap();
        let Verdict::Pass(p) = j.finish() else { panic!("expected PASS") };
        assert_eq!((p.bound(), p.checkpoints()), (3e-7, 2));
    }

    #[test]
    fn wholly_above_fails_at_that_step() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        let b = j.admit(7, iv(2e-5, 3e-5), 1e-5, BINARY64).unwrap_err();
        assert_eq!((b.step, b.lower), (7, 2e-5));
    }

    #[test]
    fn straddling_is_undecided_never_pass() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        j.admit(3, iv(0.5e-5, 2e-5), 1e-5, BINARY64).unwrap();
        j.admit(4, iv(0.0, 1e-9), 1e-5, 256).unwrap();
        assert!(matches!(j.finish(), Verdict::Undecided(Breach { step: 3, .. })));
    }

    #[test]
    fn empty_enclosure_or_no_checkpoint_is_never_pass() {
        let mut j = Judge::new(ClaimKind::MomentumConservation);
        j.admit(1, (f64::NAN, f64::NAN), 1.0, BINARY64).unwrap();
        assert!(!j.finish().is_pass());
        assert!(!Judge::new(ClaimKind::MomentumConservation).finish().is_pass());
    }

    #[test]
    fn the_highest_deciding_precision_is_reported() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        j.admit(1, iv(0.0, 1e-7), 1e-5, BINARY64).unwrap();
        j.admit(2, iv(0.0, 1e-7), 1e-5, 256).unwrap();
        let Verdict::Pass(p) = j.finish() else { panic!("expected PASS") };
        assert_eq!(p.precision(), 256);
    }

    /// Values where a comparison can go wrong: zeros, subnormals, neighbours of 1, the extremes.
    fn special() -> Vec<f64> {
        let one = [1.0f64.next_down(), 1.0, 1.0f64.next_up(), 2.0];
        let small = [0.0, 5e-324, 1e-310, f64::MIN_POSITIVE, 1e-300];
        let big = [1e300, f64::MAX, f64::INFINITY];
        let pos: Vec<f64> = one.iter().chain(&small).chain(&big).copied().collect();
        pos.iter().flat_map(|&x| [x, -x]).chain([f64::NAN]).collect()
    }

    #[test]
    fn classify_is_sound_on_every_quadruple_of_special_values() {
        let s = special();
        let mut n = 0u64;
        for &lo in &s {
            for &hi in &s {
                for &tol in &s {
                    for &x in &s {
                        assert!(classify_is_sound(lo, hi, tol, x), "{lo} {hi} {tol} {x}");
                        n += 1;
                    }
                }
            }
        }
        assert_eq!(n, (s.len() as u64).pow(4));
    }

    /// Every binary32 value, widened, as the enclosure's upper end and as the value in it.
    #[test]
    fn classify_is_sound_for_every_binary32() {
        for bits in 0..=u32::MAX {
            // black_box: without it the optimiser folds the whole loop away
            let x = std::hint::black_box(f64::from(f32::from_bits(bits)));
            assert!(
                classify_is_sound(0.0, x, 1.0, x)
                    && classify_is_sound(x, x, x, x)
                    && classify_is_sound(-1.0, 1.0, x, x)
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(100_000))]
        #[test]
        fn classify_is_sound_for_random_binary64(lo: f64, hi: f64, tol: f64, x: f64) {
            proptest::prop_assert!(classify_is_sound(lo, hi, tol, x));
        }
    }

    #[test]
    fn classify_never_calls_nan_within() {
        for (lo, hi, tol) in [(f64::NAN, 0.0, 1.0), (0.0, f64::NAN, 1.0), (0.0, 0.0, f64::NAN), (1.0, 0.0, 2.0)] {
            assert_eq!(classify(lo, hi, tol), Class::Straddles);
        }
        assert_eq!(classify(0.0, 1.0, 1.0), Class::Within);
        assert_eq!(classify(1.0, 2.0, 1.0), Class::Straddles);
        assert_eq!(classify(1.5, 2.0, 1.0), Class::Beyond);
    }

    #[test]
    fn nan_tolerance_is_never_pass() {
        let mut j = Judge::new(ClaimKind::MomentumConservation);
        j.admit(1, iv(0.0, 0.0), f64::NAN, BINARY64).unwrap();
        assert!(!j.finish().is_pass());
    }
}
