//! The decision: the only code that can make a [`Pass`].
//!
//! A [`Judge`] is fed, checkpoint by checkpoint, a rigorous enclosure of how far the claimed
//! quantity has moved and the tolerance it must stay within. A checkpoint whose enclosure lies
//! wholly above the tolerance is a certified failure; one that straddles it leaves the claim
//! undecided; only when every checkpoint lies wholly within does `finish` return a `Pass`.
//! `Pass` has private fields and no constructor outside this module (LCF style).

use crate::claims::ClaimKind;
use inari::Interval;
use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct Pass {
    claim: ClaimKind,
    /// Certified upper bound of the deviation over all checkpoints.
    bound: f64,
    /// The largest tolerance any checkpoint was held to.
    tol: f64,
    checkpoints: u64,
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
}

/// A checkpoint where the deviation is certainly (`Fail`) or possibly (`Undecided`) too large.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breach {
    pub claim: ClaimKind,
    pub step: u64,
    pub lower: f64,
    pub upper: f64,
    pub tol: f64,
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

pub struct Judge {
    claim: ClaimKind,
    checkpoints: u64,
    bound: f64,
    tol: f64,
    undecided: Option<Breach>,
}

impl Judge {
    pub fn new(claim: ClaimKind) -> Self {
        Judge { claim, checkpoints: 0, bound: 0.0, tol: 0.0, undecided: None }
    }

    /// Admits one checkpoint. `deviation` encloses a non-negative quantity that must be ≤ `tol`.
    pub fn admit(&mut self, step: u64, deviation: Interval, tol: f64) -> Result<(), Breach> {
        self.checkpoints += 1;
        let breach = Breach { claim: self.claim, step, lower: deviation.inf(), upper: deviation.sup(), tol };
        // An empty enclosure means the evaluation itself went wrong: never a PASS.
        if deviation.is_empty() || !tol.is_finite() || tol < 0.0 {
            self.undecided.get_or_insert(Breach { lower: f64::NAN, upper: f64::NAN, ..breach });
        } else if breach.lower > tol {
            return Err(breach);
        } else if breach.upper > tol || breach.upper.is_nan() {
            self.undecided.get_or_insert(breach);
        } else {
            self.bound = self.bound.max(breach.upper);
            self.tol = self.tol.max(tol);
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
            }),
            None => Verdict::Pass(Pass {
                claim: self.claim,
                bound: self.bound,
                tol: self.tol,
                checkpoints: self.checkpoints,
            }),
        }
    }
}

/// A claim about the model alone: it passes with zero deviation or is refuted with a reason.
pub fn decide_static(claim: ClaimKind, holds: Result<(), String>) -> Verdict {
    match holds {
        Ok(()) => Verdict::Pass(Pass { claim, bound: 0.0, tol: 0.0, checkpoints: 0 }),
        Err(reason) => Verdict::Refuted { claim, reason },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn iv(a: f64, b: f64) -> Interval {
        Interval::try_from((a, b)).unwrap()
    }

    #[test]
    fn inside_passes_with_the_largest_upper_bound() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        j.admit(1, iv(0.0, 1e-7), 1e-5).unwrap();
        j.admit(2, iv(1e-7, 3e-7), 1e-5).unwrap();
        let Verdict::Pass(p) = j.finish() else { panic!("expected PASS") };
        assert_eq!((p.bound(), p.checkpoints()), (3e-7, 2));
    }

    #[test]
    fn wholly_above_fails_at_that_step() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        let b = j.admit(7, iv(2e-5, 3e-5), 1e-5).unwrap_err();
        assert_eq!((b.step, b.lower), (7, 2e-5));
    }

    #[test]
    fn straddling_is_undecided_never_pass() {
        let mut j = Judge::new(ClaimKind::EnergyConservation);
        j.admit(3, iv(0.5e-5, 2e-5), 1e-5).unwrap();
        j.admit(4, iv(0.0, 1e-9), 1e-5).unwrap();
        assert!(matches!(j.finish(), Verdict::Undecided(Breach { step: 3, .. })));
    }

    #[test]
    fn empty_enclosure_or_no_checkpoint_is_never_pass() {
        let mut j = Judge::new(ClaimKind::MomentumConservation);
        j.admit(1, Interval::EMPTY, 1.0).unwrap();
        assert!(!j.finish().is_pass());
        assert!(!Judge::new(ClaimKind::MomentumConservation).finish().is_pass());
    }

    #[test]
    fn nan_tolerance_is_never_pass() {
        let mut j = Judge::new(ClaimKind::MomentumConservation);
        j.admit(1, iv(0.0, 0.0), f64::NAN).unwrap();
        assert!(!j.finish().is_pass());
    }
}
