//! Restart files: a run's exact state between two steps and everything it carries to the next
//! — the solver's forces and warm starts, where each neighbour list was built, the checker's
//! reference state and running summaries, what the meters and the observer gathered — so that
//! a run resumed from one takes the same steps, to the bit, as the run that wrote it would have.
//!
//! Layout: `lagra-restart/2\n` (16 bytes; /2 since the solver carries AVBD's stiffnesses),
//! the `Restart` in postcard (serde's compact binary form, every f64 as its eight bytes: every
//! bit survives, infinities included), then the SHA-256 of every byte before it (32 bytes). A
//! file is written to a temporary name beside its target, synced and renamed: it is whole or
//! absent.

use crate::observables::Observer;
use crate::predict::Meter;
use lagra_checker::checksum::{label, Fnv};
use lagra_checker::monitor;
use lagra_kernel::solvers::Carried;
use lagra_kernel::state::State;
use lagra_lang::scene::Scene;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::Path;

pub const MAGIC: &[u8; 16] = b"lagra-restart/2\n";
const DIGEST: usize = 32;

#[derive(Serialize, Deserialize)]
pub struct Restart {
    /// `sha256:` and the digest of the source of the scene it belongs to.
    pub scene: String,
    /// The digest of what the run was set up to be (`setup_of`): the compiled model and claims,
    /// the integrator and the time step, which `--set` and `--dt` change and the source does not.
    pub setup: String,
    /// The run length it was planned for.
    pub planned_steps: u64,
    pub state: State,
    pub solver: Carried,
    /// Where each term group's neighbour list was last built, in the order of the groups.
    pub lists: Vec<Option<Vec<[f64; 3]>>>,
    pub monitor: monitor::Carried,
    pub observer: Option<Observer>,
    /// One per prediction, in the scene's order.
    pub meters: Vec<Meter>,
    /// The checksum of the certificate of the run up to here, where one was written: the
    /// certificate of the run resumed from here names it (`Certificate::previous`).
    pub certificate: Option<String>,
}

impl Restart {
    /// The file's bytes: magic, payload, digest.
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let mut bytes = MAGIC.to_vec();
        bytes = postcard::to_extend(self, bytes).map_err(|e| format!("encoding the restart: {e}"))?;
        let digest = Sha256::digest(&bytes);
        bytes.extend_from_slice(&digest);
        Ok(bytes)
    }

    /// Reads a restart file's bytes back, refusing anything but a whole, unedited one.
    pub fn from_bytes(bytes: &[u8]) -> Result<Restart, String> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err("not a lagra restart file (it does not start with `lagra-restart/2`)".into());
        }
        if bytes.len() < MAGIC.len() + DIGEST {
            return Err(format!("truncated: {} bytes, shorter than any restart file", bytes.len()));
        }
        let (body, digest) = bytes.split_at(bytes.len() - DIGEST);
        if Sha256::digest(body).as_slice() != digest {
            return Err("its digest does not match its contents: the file is truncated, damaged or edited".into());
        }
        match postcard::take_from_bytes::<Restart>(&body[MAGIC.len()..]) {
            Ok((r, [])) => Ok(r),
            Ok((_, rest)) => Err(format!("{} bytes follow the restart", rest.len())),
            Err(e) => Err(format!("malformed restart ({e}): written by another version of lagra?")),
        }
    }

    /// Writes it to `path` atomically: a temporary file beside it, synced, renamed.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let bytes = self.to_bytes()?;
        let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let said = |e: std::io::Error| format!("writing the restart file {}: {e}", path.display());
        let mut file = tempfile::Builder::new().prefix(".lagra-restart").tempfile_in(folder).map_err(said)?;
        file.write_all(&bytes).and_then(|_| file.as_file().sync_all()).map_err(said)?;
        file.persist(path).map_err(|e| said(e.error))?;
        Ok(())
    }

    pub fn read(path: &Path) -> Result<Restart, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Restart::from_bytes(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Refuses a restart of another scene (`digest`: the scene source's `sha256:`).
    pub fn belongs_to(&self, digest: &str) -> Result<(), String> {
        match self.scene == digest {
            true => Ok(()),
            false => Err(format!("it belongs to another scene (source {}, this one {digest})", self.scene)),
        }
    }
}

/// The FNV-1a digest of a scene as set up to run: its canonical model and claims, integrator
/// and time step (what a restart must be resumed with).
pub fn setup_of(scene: &Scene) -> String {
    let setup = (&*scene.model, &scene.claims, scene.solver.integrator.name(), scene.solver.dt.to_bits());
    let json = serde_json::to_vec(&setup).expect("a model is plain data");
    label(Fnv::of(&json))
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::claims::ClaimKind;
    use lagra_checker::decision::Judge;

    fn restart() -> Restart {
        let state = State {
            step: 7,
            t: 0.07,
            x: vec![[1.0, -0.0, f64::MIN_POSITIVE]],
            v: vec![[0.1, 5e-324, -3.0]],
            chain: vec![],
            spin: vec![],
        };
        Restart {
            scene: "sha256:ab".into(),
            setup: "fnv1a64:0".into(),
            planned_steps: 10,
            state: state.clone(),
            solver: Carried { forces: vec![[0.5, 0.25, -1e300]], potential: 2.0, warm: vec![], stiffness: vec![] },
            lists: vec![None, Some(vec![[0.0; 3]])],
            monitor: monitor::Carried {
                reference: Some(state),
                judges: vec![(Judge::new(ClaimKind::EnergyConservation), 0.0)],
                ledger: Some([0.0, f64::NEG_INFINITY, f64::INFINITY, -0.0, 1.0]),
            },
            observer: None,
            meters: vec![],
            certificate: None,
        }
    }

    #[test]
    fn every_bit_comes_back() {
        let bytes = restart().to_bytes().unwrap();
        let back = Restart::from_bytes(&bytes).unwrap();
        assert_eq!(back.to_bytes().unwrap(), bytes);
        assert_eq!(back.state, restart().state);
        assert_eq!(back.monitor.ledger.unwrap()[1], f64::NEG_INFINITY);
        assert!(back.state.x[0][1].is_sign_negative());
    }

    #[test]
    fn a_truncated_or_edited_file_is_refused() {
        let bytes = restart().to_bytes().unwrap();
        for cut in [0, 10, 16, 40, bytes.len() - 1] {
            assert!(Restart::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut edited = bytes.clone();
        edited[30] ^= 1;
        assert!(Restart::from_bytes(&edited).err().is_some_and(|e| e.contains("digest")));
        assert!(restart().belongs_to("sha256:cd").unwrap_err().contains("another scene"));
    }
}
