//! The state file: every exact binary64 state the checker was shown, so a re-check can evaluate
//! every claim again without the kernel.
//!
//! Layout, all integers and floats little-endian:
//! `lagra-states/1\0\0` (16 bytes), bodies (u64), then per state: step (u64), t (f64),
//! positions (3·bodies f64), velocities (3·bodies f64); then the number of states (u64) and
//! the FNV-1a 64 checksum (u64) of every byte before it.

use crate::checksum::Fnv;
use crate::model::Snapshot;
use std::io::{self, Write};

pub const MAGIC: &[u8; 16] = b"lagra-states/1\0\0";
const HEADER: u64 = 16 + 8;
const TRAILER: u64 = 16;

/// The exact length of a file of `count` states of `bodies` bodies, or `None` if it does not
/// fit in a u64.
pub fn file_len(bodies: u64, count: u64) -> Option<u64> {
    record_len(bodies)?.checked_mul(count)?.checked_add(HEADER + TRAILER)
}

fn record_len(bodies: u64) -> Option<u64> {
    bodies.checked_mul(48)?.checked_add(16)
}

/// The number of states in a file of `len` bytes for `bodies` bodies, if the length fits.
pub fn count_for(bodies: u64, len: u64) -> Option<u64> {
    let record = record_len(bodies)?;
    let body = len.checked_sub(HEADER + TRAILER)?;
    (body % record == 0).then_some(body / record)
}

/// `file_len` and `count_for` agree with exact (128-bit) arithmetic, for every u64 input: a
/// length is given exactly when it fits, and it gives the count back. One property body, run by
/// proptest and exhaustively here and by Kani where Kani is installed (`proofs`).
#[cfg(any(test, kani, kani_typecheck))]
pub fn lengths_are_exact(bodies: u64, count: u64) -> bool {
    // (2⁶⁴·48 + 16)·2⁶⁴ overflows even u128: the oracle checks its own arithmetic too (Kani would)
    let record = u128::from(bodies) * 48 + 16;
    let exact = record.checked_mul(u128::from(count)).and_then(|b| b.checked_add(u128::from(HEADER + TRAILER)));
    match file_len(bodies, count) {
        Some(len) => exact == Some(u128::from(len)) && count_for(bodies, len) == Some(count),
        None => exact.is_none_or(|e| e > u128::from(u64::MAX)) || record > u128::from(u64::MAX),
    }
}

#[cfg(any(kani, kani_typecheck))]
mod proofs {
    // Under kani_typecheck nothing calls the harnesses; under kani, Kani does.
    #![cfg_attr(kani_typecheck, allow(dead_code))]
    use crate::any;

    #[cfg_attr(kani, kani::proof)]
    pub fn lengths_are_exact_for_every_u64() {
        assert!(super::lengths_are_exact(any(), any()));
    }

    /// Any length the reader accepts for any body count holds whole states.
    #[cfg_attr(kani, kani::proof)]
    pub fn an_accepted_length_holds_whole_states() {
        let (bodies, len): (u64, u64) = (any(), any());
        if let Some(count) = super::count_for(bodies, len) {
            assert_eq!(super::file_len(bodies, count), Some(len));
        }
    }
}

pub struct StateWriter<W: Write> {
    w: W,
    hash: Fnv,
    bodies: usize,
    count: u64,
}

impl<W: Write> StateWriter<W> {
    pub fn new(w: W, bodies: usize) -> io::Result<Self> {
        let mut s = StateWriter { w, hash: Fnv::default(), bodies, count: 0 };
        s.put(MAGIC)?;
        s.put(&(bodies as u64).to_le_bytes())?;
        Ok(s)
    }

    fn put(&mut self, b: &[u8]) -> io::Result<()> {
        self.hash.write(b);
        self.w.write_all(b)
    }

    pub fn push(&mut self, s: &Snapshot) -> io::Result<()> {
        if s.x.len() != self.bodies || s.v.len() != self.bodies {
            return Err(io::Error::other("a state of the wrong size"));
        }
        let mut rec = Vec::with_capacity(16 + 48 * self.bodies);
        rec.extend(s.step.to_le_bytes());
        rec.extend(s.t.to_le_bytes());
        for c in s.x.iter().chain(s.v).flatten() {
            rec.extend(c.to_le_bytes());
        }
        self.count += 1;
        self.put(&rec)
    }

    /// Writes the trailer; returns the checksum.
    pub fn finish(mut self) -> io::Result<u64> {
        self.put(&self.count.to_le_bytes())?;
        let sum = self.hash.value();
        self.w.write_all(&sum.to_le_bytes())?;
        self.w.flush()?;
        Ok(sum)
    }
}

/// A state file read whole and verified: magic, length, count and checksum.
#[derive(Debug)]
pub struct States {
    bytes: Vec<u8>,
    pub bodies: usize,
    pub count: u64,
    pub checksum: u64,
}

/// One state, owned: what a state file holds, and what the kernel steps.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    pub step: u64,
    pub t: f64,
    pub x: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
}

impl State {
    pub fn snapshot(&self) -> Snapshot<'_> {
        Snapshot { step: self.step, t: self.t, x: &self.x, v: &self.v }
    }
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

impl States {
    pub fn read(bytes: Vec<u8>) -> Result<States, String> {
        let len = bytes.len() as u64;
        if len < HEADER + TRAILER || &bytes[..16] != MAGIC {
            return Err("not a lagra state file (lagra-states/1): bad header or too short".into());
        }
        let bodies = u64_at(&bytes, 16);
        let count = count_for(bodies, len).ok_or_else(|| {
            format!("state file of {len} bytes cannot hold whole states of {bodies} bodies: truncated or corrupt")
        })?;
        let n = bytes.len();
        let (said, sum) = (u64_at(&bytes, n - 16), u64_at(&bytes, n - 8));
        if said != count {
            return Err(format!("state file says {said} states but holds {count}: truncated or corrupt"));
        }
        if Fnv::of(&bytes[..n - 8]) != sum {
            return Err("state file checksum does not match its contents".into());
        }
        let bodies = usize::try_from(bodies).map_err(|_| "too many bodies for this machine".to_string())?;
        Ok(States { bytes, bodies, count, checksum: sum })
    }

    pub fn iter(&self) -> impl Iterator<Item = State> + '_ {
        let record = 16 + 48 * self.bodies;
        let f = |b: &[u8], at: usize| f64::from_bits(u64_at(b, at));
        self.bytes[HEADER as usize..self.bytes.len() - TRAILER as usize].chunks_exact(record).map(move |r| {
            let vec3 = |base: usize| -> Vec<[f64; 3]> {
                (0..self.bodies).map(|i| std::array::from_fn(|c| f(r, base + 8 * (3 * i + c)))).collect()
            };
            State { step: u64_at(r, 0), t: f(r, 8), x: vec3(16), v: vec3(16 + 24 * self.bodies) }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn file(states: &[(u64, f64, [f64; 3], [f64; 3])]) -> Vec<u8> {
        let mut out = vec![];
        let mut w = StateWriter::new(&mut out, 1).unwrap();
        for (step, t, x, v) in states {
            w.push(&Snapshot { step: *step, t: *t, x: &[*x], v: &[*v] }).unwrap();
        }
        w.finish().unwrap();
        out
    }

    #[test]
    fn lengths_are_exact_on_small_and_boundary_values() {
        for bodies in 0..2048 {
            for count in 0..2048 {
                assert!(lengths_are_exact(bodies, count));
            }
        }
        // around where record·count + 40 stops fitting in a u64
        let edges = |m: u64| [0, 1, 2, m.saturating_sub(1), m, m.saturating_add(1), u64::MAX - 1, u64::MAX];
        for bodies in edges((u64::MAX - 16) / 48) {
            let record = bodies.saturating_mul(48).saturating_add(16);
            for count in edges((u64::MAX - 40) / record.max(1)) {
                assert!(lengths_are_exact(bodies, count), "{bodies} {count}");
            }
        }
    }

    #[test]
    fn states_round_trip_bit_for_bit() {
        let s = [(0, 0.0, [1.0, -0.0, 5e-324], [f64::MAX, 1e-310, -2.5]), (1, 0.1, [0.1, 0.2, 0.3], [0.0; 3])];
        let read = States::read(file(&s)).unwrap();
        assert_eq!(read.count, 2);
        for (a, b) in read.iter().zip(&s) {
            assert_eq!((a.step, a.t.to_bits()), (b.0, b.1.to_bits()));
            assert!(a.x[0].iter().zip(&b.2).all(|(p, q)| p.to_bits() == q.to_bits()));
            assert!(a.v[0].iter().zip(&b.3).all(|(p, q)| p.to_bits() == q.to_bits()));
        }
    }

    #[test]
    fn one_flipped_bit_is_caught() {
        let mut f = file(&[(0, 0.0, [1.0; 3], [2.0; 3])]);
        f[40] ^= 1;
        assert_eq!(States::read(f).err().unwrap(), "state file checksum does not match its contents");
    }

    #[test]
    fn truncation_is_caught() {
        let f = file(&[(0, 0.0, [1.0; 3], [2.0; 3]), (1, 1.0, [1.0; 3], [2.0; 3])]);
        for cut in [1, 8, 64, f.len() - 30] {
            assert!(States::read(f[..f.len() - cut].to_vec()).is_err(), "cut {cut}");
        }
    }

    #[test]
    fn a_million_bodies_header_with_no_data_is_rejected_without_allocating() {
        let mut f = MAGIC.to_vec();
        f.extend(1_000_000u64.to_le_bytes());
        f.extend(0u64.to_le_bytes());
        f.extend(Fnv::of(&f).to_le_bytes());
        // 0 states of a million bodies is a valid length: an empty trajectory, no allocation.
        assert_eq!(States::read(f.clone()).unwrap().count, 0);
        f.extend([0u8; 64]);
        assert!(States::read(f).unwrap_err().contains("cannot hold whole states"));
        let mut huge = MAGIC.to_vec();
        huge.extend(u64::MAX.to_le_bytes());
        huge.extend([0u8; 16]);
        assert!(States::read(huge).is_err());
    }

    proptest! {
        #[test]
        fn the_reader_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..512), keep_magic in any::<bool>()) {
            let mut b = bytes;
            if keep_magic && b.len() >= 16 {
                b[..16].copy_from_slice(MAGIC);
            }
            let _ = States::read(b);
        }

        #[test]
        fn lengths_are_exact_for_random_u64(bodies: u64, count: u64) {
            prop_assert!(lengths_are_exact(bodies, count));
            prop_assert!(lengths_are_exact(bodies >> 20, count >> 40));
        }
    }
}
