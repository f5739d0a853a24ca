//! Where a run's marks go, so that its memory does not grow with its length: to disk when a
//! certificate will hold them (each claim's marks spilled to a file of its own as they are made,
//! read back in order as the certificate is written), thinned in memory for a plot, or nowhere
//! (the verdicts are the checker's running summaries either way).

use crate::thinned::Thinned;
use lagra_checker::certificate::{Mark, Trail};
use lagra_checker::claims::Claim;
use lagra_checker::monitor::MarkSink;
use serde::ser::{Error, SerializeSeq};
use serde::{Serialize, Serializer};
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

/// A mark on disk: step, lo, hi, tol (their bits) and precision, little-endian.
const RECORD: usize = 36;

/// Marks a plot keeps per claim (thinned past it).
pub const PLOTTED: usize = 20_000;

/// What the sink fills: each claim's marks on disk, and (for a page) thinned in memory.
struct Store {
    files: Vec<(BufWriter<File>, u64)>,
    plotted: Option<Vec<Thinned<Mark>>>,
    error: Option<io::Error>,
}

/// The marks of a run, written as they are made.
#[derive(Clone)]
pub struct Spill(Arc<Mutex<Store>>);

impl Spill {
    /// With `dir`, one unnamed file per claim there (removed by the system when the run ends,
    /// however it ends); with `plot`, a thinned copy in memory (`PLOTTED` marks per claim).
    pub fn new(claims: usize, dir: Option<&Path>, plot: bool) -> io::Result<Spill> {
        let file = |dir| Ok((BufWriter::new(tempfile::tempfile_in(dir)?), 0));
        let files = dir.map_or(Ok(vec![]), |d| (0..claims).map(|_| file(d)).collect::<io::Result<_>>())?;
        let plotted = plot.then(|| (0..claims).map(|_| Thinned::new(PLOTTED)).collect());
        Ok(Spill(Arc::new(Mutex::new(Store { files, plotted, error: None }))))
    }

    /// The monitor's end of it.
    pub fn sink(&self) -> MarkSink {
        let store = self.0.clone();
        Box::new(move |claim, m: Mark| {
            let mut s = store.lock().unwrap_or_else(PoisonError::into_inner);
            if let Some(p) = s.plotted.as_mut() {
                p[claim].push(m);
            }
            let Some((file, count)) = s.files.get_mut(claim) else { return };
            let mut record = [0u8; RECORD];
            record[..8].copy_from_slice(&m.step.to_le_bytes());
            for (k, v) in [m.lo, m.hi, m.tol].into_iter().enumerate() {
                record[8 + 8 * k..16 + 8 * k].copy_from_slice(&v.to_bits().to_le_bytes());
            }
            record[32..].copy_from_slice(&m.precision.to_le_bytes());
            *count += 1;
            if let Err(e) = file.write_all(&record) {
                s.error.get_or_insert(e);
            }
        })
    }

    /// The trails, ready to be serialized from disk (none without a `dir`), and the thinned ones
    /// for a plot (none without `plot`).
    pub fn finish(self, claims: &[Claim]) -> io::Result<(Vec<Trail<OnDisk>>, Vec<Trail>)> {
        let mut s = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(e) = s.error.take() {
            return Err(e);
        }
        let files = std::mem::take(&mut s.files);
        let plotted = s.plotted.take().unwrap_or_default();
        let trails = claims
            .iter()
            .zip(files)
            .map(|(c, (w, count))| {
                let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
                Ok(Trail { claim: c.kind, marks: OnDisk { file, count } })
            })
            .collect::<io::Result<_>>()?;
        let plots = claims.iter().zip(plotted).map(|(c, t)| Trail { claim: c.kind, marks: t.into_items() }).collect();
        Ok((trails, plots))
    }
}

/// A sink for a run whose marks nobody reads.
pub fn dropped() -> MarkSink {
    Box::new(|_, _| {})
}

/// One claim's marks on disk, serialized as the certificate's JSON array of them.
pub struct OnDisk {
    file: File,
    count: u64,
}

impl Serialize for OnDisk {
    fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        let mut file = &self.file;
        file.rewind().map_err(S::Error::custom)?;
        let mut read = BufReader::new(file);
        let mut seq = ser.serialize_seq(Some(self.count as usize))?;
        let mut r = [0u8; RECORD];
        for _ in 0..self.count {
            read.read_exact(&mut r).map_err(|e| S::Error::custom(format!("reading the marks back: {e}")))?;
            let bits = |k: usize| f64::from_bits(u64::from_le_bytes(r[k..k + 8].try_into().expect("8 bytes")));
            let step = u64::from_le_bytes(r[..8].try_into().expect("8 bytes"));
            let precision = u32::from_le_bytes(r[32..].try_into().expect("4 bytes"));
            seq.serialize_element(&Mark { step, lo: bits(8), hi: bits(16), tol: bits(24), precision })?;
        }
        seq.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::claims::ClaimKind;

    fn claim(kind: ClaimKind) -> Claim {
        serde_json::from_value(serde_json::json!({ "kind": kind, "tol": 1e-5, "every": 1 })).unwrap()
    }

    #[test]
    fn marks_read_back_from_disk_serialize_as_the_same_json() {
        let claims = [claim(ClaimKind::EnergyConservation), claim(ClaimKind::MomentumConservation)];
        let spill = Spill::new(2, Some(&std::env::temp_dir()), true).unwrap();
        let mut sink = spill.sink();
        let mut kept = vec![vec![], vec![]];
        for step in 0..1000u64 {
            let m =
                Mark { step, lo: -(step as f64) * 1e-17, hi: f64::INFINITY, tol: 1e-5, precision: 53 + step as u32 };
            let m = if step == 7 { Mark { lo: f64::NAN, hi: f64::NAN, ..m } } else { m };
            sink((step % 2) as usize, m);
            kept[(step % 2) as usize].push(m);
        }
        drop(sink);
        let (disk, plots) = spill.finish(&claims).unwrap();
        let memory: Vec<Trail> = claims.iter().zip(kept).map(|(c, marks)| Trail { claim: c.kind, marks }).collect();
        // twice: the certificate is serialized once for its checksum and once to its file
        for _ in 0..2 {
            assert_eq!(serde_json::to_string(&disk).unwrap(), serde_json::to_string(&memory).unwrap());
        }
        assert_eq!(plots.len(), 2);
        assert_eq!(plots[0].marks.len(), 500);
    }
}
