//! The state file: every exact binary64 state the checker was shown, so a re-check can evaluate
//! every claim again without the kernel.
//!
//! Layout, all integers and floats little-endian:
//! `lagra-states/1\0\0` (16 bytes), bodies (u64), then per state: step (u64), t (f64),
//! positions (3·bodies f64), velocities (3·bodies f64); then the number of states (u64) and
//! the FNV-1a 64 checksum (u64) of every byte before it. A model with a thermostat chain writes
//! `lagra-states/2\0\0`, bodies (u64), links (u64), and after each state's velocities its
//! links' (η, ξ) (2·links f64). A model with rigid bodies writes `lagra-states/3\0\0`, bodies,
//! links and spins (u64 each), and after the links each rigid body's spin: q (4 f64), π (3 f64)
//! and a zero, 64 bytes, so that a spin is four links' worth of bytes and the length arithmetic
//! is the linked format's with links + 4·spins (`slots`).

use crate::checksum::Fnv;
use crate::model::Snapshot;
use std::io::{self, Write};

pub const MAGIC: &[u8; 16] = b"lagra-states/1\0\0";
/// The magic of a file whose states also hold thermostat links.
pub const MAGIC_LINKED: &[u8; 16] = b"lagra-states/2\0\0";
/// The magic of a file whose states also hold rigid bodies' spins (and any links).
pub const MAGIC_SPUN: &[u8; 16] = b"lagra-states/3\0\0";
const TRAILER: u64 = 16;

/// Magic and counts: bodies, then links in the linked format, links and spins in the spun one.
fn header(links: u64, spins: u64) -> u64 {
    if spins > 0 {
        16 + 24
    } else if links == 0 {
        16 + 8
    } else {
        16 + 16
    }
}

/// What follows a state's velocities, in 16-byte slots: a link is one, a spin four.
fn slots(links: u64, spins: u64) -> Option<u64> {
    links.checked_add(spins.checked_mul(4)?)
}

/// The exact length of a file of `count` states of `bodies` bodies, `links` thermostat links
/// and `spins` rigid bodies, or `None` if it does not fit in a u64.
pub fn file_len(bodies: u64, links: u64, spins: u64, count: u64) -> Option<u64> {
    record_len(bodies, slots(links, spins)?)?.checked_mul(count)?.checked_add(header(links, spins) + TRAILER)
}

fn record_len(bodies: u64, slots: u64) -> Option<u64> {
    bodies.checked_mul(48)?.checked_add(slots.checked_mul(16)?)?.checked_add(16)
}

/// The number of states in a file of `len` bytes for `bodies` bodies, `links` links and `spins`
/// rigid bodies, if the length fits.
pub fn count_for(bodies: u64, links: u64, spins: u64, len: u64) -> Option<u64> {
    let record = record_len(bodies, slots(links, spins)?)?;
    let body = len.checked_sub(header(links, spins) + TRAILER)?;
    (body % record == 0).then_some(body / record)
}

/// `file_len` and `count_for` agree with exact (128-bit) arithmetic, for every u64 input: a
/// length is given exactly when it fits, and it gives the count back. One property body, run by
/// proptest and exhaustively here and by Kani where Kani is installed (`proofs`).
#[cfg(any(test, kani, kani_typecheck))]
pub fn lengths_are_exact(bodies: u64, links: u64, spins: u64, count: u64) -> bool {
    // (2⁶⁴·64 + 16)·2⁶⁴ overflows even u128: the oracle checks its own arithmetic too (Kani would)
    let record = u128::from(bodies) * 48 + (u128::from(links) + 4 * u128::from(spins)) * 16 + 16;
    let framing = u128::from(header(links, spins) + TRAILER);
    let exact = record.checked_mul(u128::from(count)).and_then(|b| b.checked_add(framing));
    match file_len(bodies, links, spins, count) {
        Some(len) => exact == Some(u128::from(len)) && count_for(bodies, links, spins, len) == Some(count),
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
        assert!(super::lengths_are_exact(any(), any(), any(), any()));
    }

    /// Any length the reader accepts for any body and link count holds whole states.
    #[cfg_attr(kani, kani::proof)]
    pub fn an_accepted_length_holds_whole_states() {
        let (bodies, links, spins, len): (u64, u64, u64, u64) = (any(), any(), any(), any());
        if let Some(count) = super::count_for(bodies, links, spins, len) {
            assert_eq!(super::file_len(bodies, links, spins, count), Some(len));
        }
    }
}

pub struct StateWriter<W: Write> {
    w: W,
    hash: Fnv,
    bodies: usize,
    links: usize,
    spins: usize,
    count: u64,
}

impl<W: Write> StateWriter<W> {
    pub fn new(w: W, bodies: usize, links: usize, spins: usize) -> io::Result<Self> {
        let mut s = StateWriter { w, hash: Fnv::default(), bodies, links, spins, count: 0 };
        let (magic, counts) = match (links, spins) {
            (0, 0) => (MAGIC, &[bodies][..]),
            (_, 0) => (MAGIC_LINKED, &[bodies, links][..]),
            _ => (MAGIC_SPUN, &[bodies, links, spins][..]),
        };
        s.put(magic)?;
        for c in counts {
            s.put(&(*c as u64).to_le_bytes())?;
        }
        Ok(s)
    }

    fn put(&mut self, b: &[u8]) -> io::Result<()> {
        self.hash.write(b);
        self.w.write_all(b)
    }

    pub fn push(&mut self, s: &Snapshot) -> io::Result<()> {
        let sizes = [s.x.len(), s.v.len(), s.chain.len(), s.spin.len()];
        if sizes != [self.bodies, self.bodies, self.links, self.spins] {
            return Err(io::Error::other("a state of the wrong size"));
        }
        let mut rec = Vec::with_capacity(16 + 48 * self.bodies + 16 * self.links + 64 * self.spins);
        rec.extend(s.step.to_le_bytes());
        rec.extend(s.t.to_le_bytes());
        let spins = s.spin.iter().flat_map(|r| r.iter().chain(&[0.0]));
        for c in s.x.iter().chain(s.v).flatten().chain(s.chain.iter().flatten()).chain(spins) {
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
    pub links: usize,
    pub spins: usize,
    pub count: u64,
    pub checksum: u64,
}

/// One state, owned: what a state file holds, and what the kernel steps.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct State {
    pub step: u64,
    pub t: f64,
    pub x: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
    /// A thermostat chain's links (η_j, ξ_j), empty without one.
    pub chain: Vec<[f64; 2]>,
    /// Each rigid body's orientation and body-frame angular momentum (`Snapshot::spin`).
    pub spin: Vec<[f64; 7]>,
}

impl State {
    pub fn snapshot(&self) -> Snapshot<'_> {
        Snapshot { step: self.step, t: self.t, x: &self.x, v: &self.v, chain: &self.chain, spin: &self.spin }
    }
}

impl From<&Snapshot<'_>> for State {
    fn from(s: &Snapshot) -> State {
        State { step: s.step, t: s.t, x: s.x.to_vec(), v: s.v.to_vec(), chain: s.chain.to_vec(), spin: s.spin.to_vec() }
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
        let magic = bytes.get(..16);
        let (linked, spun) = (magic == Some(MAGIC_LINKED), magic == Some(MAGIC_SPUN));
        let counts = 1 + u64::from(linked) + 2 * u64::from(spun);
        if len < 16 + 8 * counts + TRAILER || !(linked || spun || magic == Some(MAGIC)) {
            return Err("not a lagra state file (lagra-states/1, /2 or /3): bad header or too short".into());
        }
        let bodies = u64_at(&bytes, 16);
        let links = if linked || spun { u64_at(&bytes, 24) } else { 0 };
        let spins = if spun { u64_at(&bytes, 32) } else { 0 };
        if linked && links == 0 {
            return Err("state file in the linked format holds no thermostat link: corrupt".into());
        }
        if spun && spins == 0 {
            return Err("state file in the spun format holds no rigid body: corrupt".into());
        }
        let count = count_for(bodies, links, spins, len).ok_or_else(|| {
            format!("state file of {len} bytes cannot hold whole states of {bodies} bodies, {links} thermostat links and {spins} rigid bodies: truncated or corrupt")
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
        let links = usize::try_from(links).map_err(|_| "too many links for this machine".to_string())?;
        let spins = usize::try_from(spins).map_err(|_| "too many rigid bodies for this machine".to_string())?;
        Ok(States { bytes, bodies, links, spins, count, checksum: sum })
    }

    pub fn iter(&self) -> impl Iterator<Item = State> + '_ {
        let record = 16 + 48 * self.bodies + 16 * self.links + 64 * self.spins;
        let f = |b: &[u8], at: usize| f64::from_bits(u64_at(b, at));
        let start = header(self.links as u64, self.spins as u64) as usize;
        self.bytes[start..self.bytes.len() - TRAILER as usize].chunks_exact(record).map(move |r| {
            fn vecs<const N: usize>(n: usize, at: impl Fn(usize) -> f64) -> Vec<[f64; N]> {
                (0..n).map(|i| std::array::from_fn(|c| at(N * i + c))).collect()
            }
            let from = |base: usize| move |k: usize| f(r, base + 8 * k);
            State {
                step: u64_at(r, 0),
                t: f(r, 8),
                x: vecs(self.bodies, from(16)),
                v: vecs(self.bodies, from(16 + 24 * self.bodies)),
                chain: vecs(self.links, from(16 + 48 * self.bodies)),
                // each spin's eight words, the last a zero
                spin: (0..self.spins)
                    .map(|i| std::array::from_fn(|c| f(r, 16 + 48 * self.bodies + 16 * self.links + 64 * i + 8 * c)))
                    .collect(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn file(states: &[(u64, f64, [f64; 3], [f64; 3])]) -> Vec<u8> {
        let mut out = vec![];
        let mut w = StateWriter::new(&mut out, 1, 0, 0).unwrap();
        for (step, t, x, v) in states {
            w.push(&Snapshot { step: *step, t: *t, x: &[*x], v: &[*v], chain: &[], spin: &[] }).unwrap();
        }
        w.finish().unwrap();
        out
    }

    #[test]
    fn lengths_are_exact_on_small_and_boundary_values() {
        for bodies in 0..2048 {
            for count in 0..2048 {
                assert!(lengths_are_exact(bodies, 0, 0, count));
            }
        }
        for bodies in 0..256 {
            for links in 0..8 {
                for spins in u64::from(links == 0)..4 {
                    for count in 0..128 {
                        assert!(lengths_are_exact(bodies, links, spins, count));
                    }
                }
            }
        }
        // around where record·count + header + trailer stops fitting in a u64
        let edges = |m: u64| [0, 1, 2, m.saturating_sub(1), m, m.saturating_add(1), u64::MAX - 1, u64::MAX];
        for bodies in edges((u64::MAX - 16) / 48) {
            for links in edges((u64::MAX - 16) / 16) {
                for spins in edges((u64::MAX - 16) / 64) {
                    let slots = links.saturating_add(spins.saturating_mul(4));
                    let record = bodies.saturating_mul(48).saturating_add(slots.saturating_mul(16)).saturating_add(16);
                    for count in edges((u64::MAX - 56) / record.max(1)) {
                        assert!(lengths_are_exact(bodies, links, spins, count), "{bodies} {links} {spins} {count}");
                    }
                }
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
    fn thermostat_links_round_trip_after_the_velocities() {
        let chain = [[0.25, -1e-300], [f64::MIN_POSITIVE, 3.0]];
        let mut out = vec![];
        let mut w = StateWriter::new(&mut out, 1, 2, 0).unwrap();
        w.push(&Snapshot { step: 7, t: 0.5, x: &[[1.0; 3]], v: &[[2.0; 3]], chain: &chain, spin: &[] }).unwrap();
        assert!(w.push(&Snapshot { step: 8, t: 0.5, x: &[[1.0; 3]], v: &[[2.0; 3]], chain: &[], spin: &[] }).is_err());
        w.finish().unwrap();
        assert_eq!(&out[..16], MAGIC_LINKED);
        let read = States::read(out.clone()).unwrap();
        assert_eq!((read.bodies, read.links, read.count), (1, 2, 1));
        let s = read.iter().next().unwrap();
        assert_eq!((s.step, s.x, s.v), (7, vec![[1.0; 3]], vec![[2.0; 3]]));
        assert_eq!(
            s.chain.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>(),
            chain.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>()
        );
        // claiming no links in the linked format is corrupt, whatever the checksum says
        let mut none = out[..24].to_vec();
        none.extend(0u64.to_le_bytes());
        none.extend(0u64.to_le_bytes());
        none.extend(Fnv::of(&none).to_le_bytes());
        assert!(States::read(none).unwrap_err().contains("no thermostat link"));
    }

    #[test]
    fn spins_round_trip_after_the_links() {
        let (chain, spin) =
            ([[0.25, -1e-300]], [[0.5, -0.5, 0.5, 0.5, 1e-310, 2.0, -3.0], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 7.5]]);
        let mut out = vec![];
        let mut w = StateWriter::new(&mut out, 2, 1, 2).unwrap();
        let x = [[1.0; 3], [2.0; 3]];
        w.push(&Snapshot { step: 3, t: 0.5, x: &x, v: &x, chain: &chain, spin: &spin }).unwrap();
        assert!(w.push(&Snapshot { step: 4, t: 0.5, x: &x, v: &x, chain: &chain, spin: &spin[..1] }).is_err());
        w.finish().unwrap();
        assert_eq!(&out[..16], MAGIC_SPUN);
        let read = States::read(out.clone()).unwrap();
        assert_eq!((read.bodies, read.links, read.spins, read.count), (2, 1, 2, 1));
        let s = read.iter().next().unwrap();
        assert_eq!((s.x, s.chain), (x.to_vec(), chain.to_vec()));
        let bits = |v: &[[f64; 7]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&s.spin), bits(&spin));
        // claiming no spin in the spun format is corrupt, and a file one byte short does not fit
        let mut none = out[..32].to_vec();
        none.extend([0u8; 16]);
        none.extend(Fnv::of(&none).to_le_bytes());
        assert!(States::read(none).unwrap_err().contains("no rigid body"));
        assert!(States::read(out[..out.len() - 1].to_vec()).unwrap_err().contains("truncated or corrupt"));
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
                let linked = b[16..].first().is_some_and(|c| c % 2 == 1);
                b[..16].copy_from_slice(if linked { MAGIC_LINKED } else { MAGIC });
            }
            let _ = States::read(b);
        }

        #[test]
        fn lengths_are_exact_for_random_u64(bodies: u64, links: u64, spins: u64, count: u64) {
            prop_assert!(lengths_are_exact(bodies, links, spins, count));
            prop_assert!(lengths_are_exact(bodies >> 20, links >> 60, spins >> 60, count >> 40));
        }
    }
}
