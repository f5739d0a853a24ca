//! The certificate: what was run (the canonical model, the claims, the solver settings), what the
//! checker saw (every checkpoint's enclosure of every claim's deviation, as exact binary64
//! values that survive JSON, so a re-check compares them bit for bit) and what it concluded.
//! `docs/certificate.md` documents the format field by field.

use crate::checksum::{label, Fnv};
use crate::claims::{Claim, ClaimKind};
use crate::decision::{Precision, PARTS};
use crate::model::Model;
use serde::{Deserialize, Serialize};

pub const FORMAT: &str = "lagra-certificate/1";

/// The revision of the checker's arithmetic (its enclosures' every bit: the rounding step, the
/// order and exactness of sums) that a certificate's marks were computed in. A re-check
/// re-derives the marks bit for bit only in the same; a change that moves any bit of an
/// enclosure gets a new name (`tests::the_arithmetic_revision_names_these_bits` holds one
/// enclosure's bits to this name, and fails until both are updated). A date, with a letter
/// for a later revision the same day: "2026-11-26b" chose periodic images with ties to even (a
/// pair exactly half a box apart along an axis, which moves a bit only where a term reaches
/// exactly that far); "2026-11-26c" steps outward by at least 2⁻⁵¹¹ instead of 2⁻¹⁰²² (which
/// moves only the ends of enclosures within ~10⁻¹⁵³ of zero); "2026-11-29" sums the kinetic
/// energy, momentum and angular momentum exactly, rounded once (`pair_sums::sum_exactly`).
pub const ARITHMETIC: &str = "2026-11-29";

/// One checkpoint's enclosure `[lo, hi]` of a claim's deviation, the tolerance it was held to
/// (declared, or the round-off budget at that step) and the precision that produced the
/// enclosure. Written as `[step, lo, hi, tol, precision]`; the numbers as exact binary64 JSON
/// numbers, the infinities as the strings "inf" and "-inf", an empty enclosure as "nan".
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "MarkRepr", try_from = "MarkRepr")]
pub struct Mark {
    pub step: u64,
    pub lo: f64,
    pub hi: f64,
    pub tol: f64,
    pub precision: Precision,
}

impl Mark {
    /// Equal to the last bit, NaN included.
    pub fn same(&self, o: &Mark) -> bool {
        let bits = |m: &Mark| (m.step, m.lo.to_bits(), m.hi.to_bits(), m.tol.to_bits(), m.precision);
        bits(self) == bits(o)
    }

    /// A mark added up from the ranks' parts of a run in domains (`PARTS`) and `o`, re-derived
    /// from the whole state at the same step against the same tolerance: two enclosures of one
    /// quantity, so they must meet.
    pub fn meets(&self, o: &Mark) -> bool {
        self.precision == PARTS
            && self.step == o.step
            && self.tol.to_bits() == o.tol.to_bits()
            && self.lo <= o.hi
            && o.lo <= self.hi
    }
}

#[derive(Serialize, Deserialize)]
struct MarkRepr(u64, Exact, Exact, Exact, Precision);

/// A binary64 value that survives JSON: finite values as numbers, the rest as strings.
#[derive(Serialize, Deserialize)]
#[serde(untagged)]
enum Exact {
    Finite(f64),
    Special(String),
}

impl From<Mark> for MarkRepr {
    fn from(m: Mark) -> Self {
        let e = |x: f64| match x {
            x if x.is_finite() => Exact::Finite(x),
            x if x > 0.0 => Exact::Special("inf".into()),
            x if x < 0.0 => Exact::Special("-inf".into()),
            _ => Exact::Special("nan".into()),
        };
        MarkRepr(m.step, e(m.lo), e(m.hi), e(m.tol), m.precision)
    }
}

impl TryFrom<MarkRepr> for Mark {
    type Error = String;
    fn try_from(r: MarkRepr) -> Result<Self, String> {
        let e = |x: Exact| match x {
            Exact::Finite(x) => Ok(x),
            Exact::Special(s) => match s.as_str() {
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                "nan" => Ok(f64::NAN),
                _ => Err(format!("`{s}` is not a binary64 value")),
            },
        };
        Ok(Mark { step: r.0, lo: e(r.1)?, hi: e(r.2)?, tol: e(r.3)?, precision: r.4 })
    }
}

/// A claim's marks in the order of its checkpoints: in memory (`Vec<Mark>`), or any sequence
/// that serializes as one (a long run's, read back from disk as the certificate is written).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trail<M = Vec<Mark>> {
    pub claim: ClaimKind,
    pub marks: M,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    pub integrator: String,
    pub dt: f64,
    /// The run length asked for; the last of these steps is always a checkpoint.
    pub planned_steps: u64,
    /// The steps taken (fewer when the run halted or was stopped).
    pub steps: u64,
    /// Why the run ended before `planned_steps`, as its report said (a halt, a signal); absent
    /// when it ran to the end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// The step this segment of a run started from, a restart file's; absent for 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub first_step: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Certificate<M = Vec<Mark>> {
    pub format: String,
    /// `ARITHMETIC` of the checker that wrote it; empty (and absent from the JSON) in
    /// certificates written before it was recorded.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub arithmetic: String,
    pub scene: String,
    /// `sha256:` and the digest of the scene's source text, as the front computed it.
    pub source_digest: String,
    pub model: Model,
    pub claims: Vec<Claim>,
    pub run: Run,
    /// One trail per claim, in the order of the claims.
    pub trails: Vec<Trail<M>>,
    /// One verdict line per claim, as printed.
    pub verdicts: Vec<String>,
    /// The checksum of the state file written with this certificate, if one was.
    pub states_checksum: Option<String>,
    /// For a run resumed from a restart file, the checksum of the certificate of the segment
    /// before (`recheck::recheck_chain`); absent for a run from its start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub previous: Option<String>,
    /// FNV-1a 64 of the canonical JSON of the certificate with this field empty.
    pub checksum: String,
}

impl<M: Serialize> Certificate<M> {
    /// Sets the checksum over the canonical form of everything else. The error is the marks'
    /// (a trail read back from disk).
    pub fn seal(mut self) -> Result<Self, String> {
        self.checksum = String::new();
        self.checksum = label(self.unsealed_hash()?);
        Ok(self)
    }

    /// The hash of the canonical JSON with the checksum empty, streamed (never held whole).
    fn unsealed_hash(&mut self) -> Result<u64, String> {
        let kept = std::mem::take(&mut self.checksum);
        let mut hash = Fnv::default();
        let written = serde_json::to_writer(&mut hash, self).map_err(|e| e.to_string());
        self.checksum = kept;
        written.map(|_| hash.value())
    }
}

impl Certificate {
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a certificate is plain data")
    }

    /// Parses and checks a certificate: format, checksum, model and claims.
    pub fn read(text: &str) -> Result<Certificate, String> {
        let version: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("not JSON: {e} (truncated?)"))?;
        match version.get("format").and_then(|f| f.as_str()) {
            Some(FORMAT) => {}
            Some(other) => return Err(format!("format `{other}` is not supported; this checker reads {FORMAT}")),
            None => return Err("no `format` field: not a lagra certificate".into()),
        }
        let mut c: Certificate = serde_json::from_value(version).map_err(|e| format!("malformed certificate: {e}"))?;
        if c.unsealed_hash().map(label).as_ref() != Ok(&c.checksum) {
            return Err("checksum does not match the contents: the certificate was edited or damaged".into());
        }
        c.model.validate()?;
        if c.claims.len() != c.trails.len() || c.claims.len() != c.verdicts.len() {
            return Err("claims, trails and verdicts differ in number".into());
        }
        for (claim, trail) in c.claims.iter().zip(&c.trails) {
            if claim.kind != trail.claim {
                return Err(format!("trail for {} stands where {} is claimed", trail.claim.name(), claim.kind.name()));
            }
            claim.validate(&c.model)?;
            if let Some(m) = trail.marks.iter().find(|m| m.lo > m.hi) {
                return Err(format!(
                    "{} at step {}: enclosure [{}, {}] is upside down",
                    claim.kind.name(),
                    m.step,
                    m.lo,
                    m.hi
                ));
            }
        }
        if !(c.run.dt.is_finite() && c.run.dt > 0.0)
            || c.run.steps > c.run.planned_steps
            || c.run.first_step > c.run.steps
        {
            return Err("run: dt must be finite and positive, first_step ≤ steps ≤ planned_steps".into());
        }
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Body, Snapshot, TermInstance, UnitSystem};
    use crate::monitor::Monitor;
    use crate::terms::Kind;

    /// An energy mark of a small scene (Lennard-Jones pairs, a bond, kinetic energy) at its
    /// second state, and a momentum mark of the same scene at rest (an enclosure of zero, so of
    /// the step outward's floor): if any bit of them moves, the checker's arithmetic changed,
    /// and `ARITHMETIC` must get a new name along with the bits written here (certificates of
    /// the old name can then no longer be re-checked to the bit, and `recheck` says why).
    #[test]
    fn the_arithmetic_revision_names_these_bits() {
        let body = Body { mass: 1.5, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![body; 5],
            terms: vec![
                TermInstance { kind: Kind::LennardJones, sites: vec![], params: vec![1.0, 1.0, 2.5] },
                TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![30.0, 1.1, 0.0] },
            ],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        let x = |d: f64| [[0.0, 0.0, 0.0], [1.1 + d, 0.1, 0.0], [0.3, 1.2, -0.1], [1.4, 1.1, 0.9], [-0.8, 0.6, 1.3]];
        let mark = |kind: ClaimKind, v: &[[f64; 3]]| {
            let mut monitor = Monitor::new(model.clone(), vec![Claim::new(kind, Some(1e-3), 1)], 1).unwrap();
            for (step, d) in [(0, 0.0), (1, 1e-4)] {
                let x = x(d);
                monitor.observe(&Snapshot { step, t: step as f64 * 0.01, x: &x, v, chain: &[], spin: &[] }).unwrap();
            }
            let mark = monitor.finish().trails[0].marks[0];
            assert_eq!(mark.step, 1);
            (mark.lo.to_bits(), mark.hi.to_bits())
        };
        let v = [[0.1, -0.2, 0.3], [0.0, 0.5, -0.1], [-0.3, 0.1, 0.2], [0.2, 0.2, -0.4], [0.0, -0.3, 0.1]];
        let moved = "the arithmetic moved: name a new ARITHMETIC";
        assert_eq!(mark(ClaimKind::EnergyConservation, &v), (0x3ee6_4c9e_2838_55fb, 0x3ee6_4c9e_2a8f_903d), "{moved}");
        assert_eq!(mark(ClaimKind::MomentumConservation, &[[0.0; 3]; 5]), (0, 0x203a_0000_0000_0003), "{moved}");
        assert_eq!(ARITHMETIC, "2026-11-29");
    }

    #[test]
    fn marks_round_trip_through_json_exactly() {
        let marks = [
            Mark { step: 3, lo: 1.0000000000000002e-300, hi: f64::INFINITY, tol: 1e-5, precision: 53 },
            Mark { step: 4, lo: f64::NEG_INFINITY, hi: 4.9e-324, tol: 0.1, precision: 1024 },
        ];
        let text = serde_json::to_string(&marks).unwrap();
        assert_eq!(text, r#"[[3,1.0000000000000002e-300,"inf",0.00001,53],[4,"-inf",5e-324,0.1,1024]]"#);
        let back: Vec<Mark> = serde_json::from_str(&text).unwrap();
        assert_eq!(back, marks);
        let nan: Mark = serde_json::from_str(r#"[1,"nan","nan",1,53]"#).unwrap();
        assert!(nan.lo.is_nan() && nan.same(&nan));
        assert!(serde_json::from_str::<Mark>(r#"[1,"zero",0,1,53]"#).is_err());
    }
}
