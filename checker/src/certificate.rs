//! The certificate: what was run (the canonical model, the claims, the solver settings), what the
//! checker saw (every checkpoint's enclosure of every claim's deviation) and what it concluded.
//! `docs/certificate.md` documents the format field by field.

use crate::checksum::{label, Fnv};
use crate::claims::Claim;
use crate::model::Model;
use crate::monitor::Trail;
use serde::{Deserialize, Serialize};

pub const FORMAT: &str = "lagra-certificate/1";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    pub integrator: String,
    pub dt: f64,
    /// The run length asked for; the last of these steps is always a checkpoint.
    pub planned_steps: u64,
    /// The steps taken (fewer when the run halted).
    pub steps: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Certificate {
    pub format: String,
    pub scene: String,
    /// `sha256:` and the digest of the scene's source text, as the front computed it.
    pub source_digest: String,
    pub model: Model,
    pub claims: Vec<Claim>,
    pub run: Run,
    /// One trail per claim, in the order of the claims.
    pub trails: Vec<Trail>,
    /// One verdict line per claim, as printed.
    pub verdicts: Vec<String>,
    /// The checksum of the state file written with this certificate, if one was.
    pub states_checksum: Option<String>,
    /// FNV-1a 64 of the canonical JSON of the certificate with this field empty.
    pub checksum: String,
}

impl Certificate {
    /// Sets the checksum over the canonical form of everything else.
    pub fn seal(mut self) -> Certificate {
        self.checksum = label(self.content_hash());
        self
    }

    fn content_hash(&self) -> u64 {
        let unsealed = Certificate { checksum: String::new(), ..self.clone() };
        Fnv::of(&serde_json::to_vec(&unsealed).expect("a certificate is plain data"))
    }

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
        let c: Certificate = serde_json::from_value(version).map_err(|e| format!("malformed certificate: {e}"))?;
        if label(c.content_hash()) != c.checksum {
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
            claim.validate(c.model.bodies.len())?;
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
        if !(c.run.dt.is_finite() && c.run.dt > 0.0) || c.run.steps > c.run.planned_steps {
            return Err("run: dt must be finite and positive, steps at most planned_steps".into());
        }
        Ok(c)
    }
}
