//! A whole from its parts. A run cut into domains (each rank owning some bodies and holding as
//! ghosts the others' within reach) encloses on each rank its own part of the additive
//! quantities, energy and momentum, with this crate's arithmetic (`Part::enclose`); rank 0 adds
//! the parts outward (`Parts::whole`). A sum of enclosures encloses the sum, so the whole's
//! enclosure is as rigorous as one evaluated on one machine, if the parts cover every term
//! exactly once. That is what the checker verifies before it uses them, each rank of its own
//! part and rank 0 of all of them:
//!
//! - a rank's local model is the whole's restricted to its bodies: each local body is the
//!   whole's of its number (numbers distinct), the pair terms are the whole's, each bonded
//!   instance is the whole's of its number on the bodies of those numbers, the box is the same;
//! - a pair counts whole between two owned bodies, half between an owned body and a ghost, not
//!   between two ghosts; so each pair within reach counts once in the sum over ranks if every
//!   body within reach of a rank's owned bodies is there. Each rank checks it for the others:
//!   every owned body that may lie within reach of another rank's region (an interval per axis
//!   holding that rank's owned bodies, checked by that rank, with margins that cover binary64's
//!   rounding) must have been sent to it as a ghost;
//! - a bonded instance counts on the rank owning its first site; the counted instances' numbers
//!   are distinct on each rank, the ranks' owned bodies are a partition of the whole's (rank 0
//!   checks the numbers gathered), so the instances counted are distinct across ranks, and
//!   their count being the whole's makes them every instance.
//!
//! What the checker takes on trust: that a ghost's position is its owner's (the exchange's
//! bits, as the gather's are), and that a rank's part is of the bodies it sent to the gather.
//! A part that fails a check is refused, and rank 0 evaluates the whole state instead.

use super::pair_sums::{asked_reach, sum_exactly, Summed};
use super::Lifted;
use crate::broad_phase::Neighbourhood;
use crate::enclosure::Enclosure;
use crate::exact_sum::ExactSum;
use crate::model::{Cell, Model, Snapshot, TermInstance};
use crate::outward::Outward;
use crate::terms::{Kind, Shape, Site};
use rug::float::Round;

/// The margin, relative to the magnitudes involved, that covers the rounding of a position's
/// offset from a region's centre to its nearest image (a few ulps, ~1e-15 relative).
const MARGIN: f64 = 1e-9;

/// Where a rank's owned bodies lie: along each axis an interval of offsets from a centre, each
/// offset taken to its nearest periodic image and widened by the margin of its rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    centre: [f64; 3],
    lo: [f64; 3],
    hi: [f64; 3],
}

/// The nearest-image offset of `x` from `c` along an axis of length `l` (0: open), and the
/// margin that covers its rounding.
fn offset(x: f64, c: f64, l: f64) -> (f64, f64) {
    let d = x - c;
    let k = if l > 0.0 { (d / l).round_ties_even() } else { 0.0 };
    (d - k * l, MARGIN * (x.abs() + c.abs() + l))
}

impl Region {
    /// The region of the bodies at `x`, about `centre` (any point: a centre near them keeps the
    /// region small). Without bodies, an empty region (lo > hi) that nothing is near.
    pub fn of(x: &[[f64; 3]], centre: [f64; 3], cell: &Option<Cell>) -> Region {
        let l = lengths(cell);
        let mut r = Region { centre, lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] };
        for p in x {
            for a in 0..3 {
                let (e, m) = offset(p[a], centre[a], l[a]);
                r.lo[a] = r.lo[a].min(e - m);
                r.hi[a] = r.hi[a].max(e + m);
            }
        }
        r
    }

    pub fn to_bits(&self) -> [f64; 9] {
        [self.centre, self.lo, self.hi].concat().try_into().expect("nine")
    }

    pub fn from_bits(b: &[f64]) -> Region {
        let three = |k: usize| [b[k], b[k + 1], b[k + 2]];
        Region { centre: three(0), lo: three(3), hi: three(6) }
    }

    /// Whether a body at `x` may lie within `reach` of a point of the region (true when in
    /// doubt): along each axis the gap from x's nearest images to the interval, less the
    /// margins of its rounding.
    fn near(&self, x: [f64; 3], reach: f64, cell: &Option<Cell>) -> bool {
        let l = lengths(cell);
        let mut gap2 = 0.0;
        for a in 0..3 {
            if self.lo[a] > self.hi[a] {
                return false;
            }
            let (e, m) = offset(x[a], self.centre[a], l[a]);
            let images: &[f64] = if l[a] > 0.0 { &[-1.0, 0.0, 1.0] } else { &[0.0] };
            let gap = images
                .iter()
                .map(|k| {
                    let y = e + k * l[a];
                    (self.lo[a] - y).max(y - self.hi[a]).max(0.0)
                })
                .fold(f64::INFINITY, f64::min);
            let gap = (gap - 2.0 * m - MARGIN * l[a]).max(0.0);
            gap2 += gap * gap;
        }
        gap2 <= reach * reach * (1.0 + MARGIN)
    }

    /// Whether some point of this region may lie within `reach` of some point of `other`
    /// (true when in doubt): along each axis the gap between the two intervals, `other`'s seen
    /// from this centre at each of its images, less the margins of both regions and of the
    /// centres' offset. Where two regions do not meet, no body of one is near the other, so a
    /// rank tests its bodies one by one only against the regions its own meets (its
    /// neighbours'), not against every rank's.
    fn meets(&self, other: &Region, reach: f64, cell: &Option<Cell>) -> bool {
        let l = lengths(cell);
        let mut gap2 = 0.0;
        for a in 0..3 {
            if self.lo[a] > self.hi[a] || other.lo[a] > other.hi[a] {
                return false;
            }
            let (d, m) = offset(other.centre[a], self.centre[a], l[a]);
            // each interval is within about half a box of its centre, so the images two boxes
            // either way bring every near copy of `other` into view
            let images: &[f64] = if l[a] > 0.0 { &[-2.0, -1.0, 0.0, 1.0, 2.0] } else { &[0.0] };
            let gap = images
                .iter()
                .map(|k| {
                    let (lo, hi) = (d + other.lo[a] + k * l[a], d + other.hi[a] + k * l[a]);
                    (lo - self.hi[a]).max(self.lo[a] - hi).max(0.0)
                })
                .fold(f64::INFINITY, f64::min);
            let sizes = [self.lo[a], self.hi[a], other.lo[a], other.hi[a]].map(f64::abs).iter().sum::<f64>();
            let gap = (gap - 2.0 * m - MARGIN * (sizes + 2.0 * l[a])).max(0.0);
            gap2 += gap * gap;
        }
        gap2 <= reach * reach * (1.0 + MARGIN)
    }
}

/// The box's periodic lengths (0 along an open axis).
fn lengths(cell: &Option<Cell>) -> [f64; 3] {
    cell.map_or([0.0; 3], |c| std::array::from_fn(|a| if c.periodic[a] { c.size[a] } else { 0.0 }))
}

/// What a rank knows of its share of a run cut into domains, at one state.
pub struct Local<'a> {
    /// The whole scene's model, which every rank holds.
    pub whole: &'a Model,
    /// The rank's model: its bodies (owned, then ghosts), the whole's pair terms and the
    /// bonded instances it holds.
    pub model: &'a Model,
    pub state: Snapshot<'a>,
    /// How many of the bodies, the first, the rank owns.
    pub owned: usize,
    /// Each local body's number in the whole.
    pub numbers: &'a [usize],
    /// Each local bonded instance's number among the whole's bonded instances (its instances
    /// with sites, in order).
    pub instances: &'a [usize],
    pub rank: usize,
    /// Every rank's region (`Region::of` its owned bodies), in rank order.
    pub regions: &'a [Region],
    /// For each rank, the places among the owned bodies of those sent it as ghosts.
    pub sent: &'a [Vec<usize>],
    /// Threads for the pair sums.
    pub threads: usize,
}

/// One rank's enclosure of its part of the energy (kinetic and potential; a thermostat's share
/// is rank 0's to add) and of the momentum, with what `Parts::whole` checks them by.
#[derive(Clone, Debug)]
pub struct Part {
    /// The bodies owned, and the bonded instances counted.
    pub bodies: usize,
    pub instances: usize,
    pub energy: Outward,
    pub momentum: [Outward; 3],
    /// Why the part cannot stand for its share, if it cannot.
    pub flaw: Option<String>,
}

/// How many f64s a part travels as (`Part::to_bits`).
pub const PART_BITS: usize = 11;

impl Part {
    /// The rank's part at its state, or a part with the flaw found.
    pub fn enclose(l: &Local) -> Part {
        let flawed = |flaw: String| Part {
            bodies: l.owned,
            instances: 0,
            energy: Outward::NAN,
            momentum: [Outward::NAN; 3],
            flaw: Some(flaw),
        };
        if let Err(flaw) = restricts(l).and_then(|()| covers(l)) {
            return flawed(flaw);
        }
        let q = Lifted::new(l.model, &l.state, &Outward::NAN).on_threads(l.threads);
        let owned = &q.sites[..l.owned];
        let half = Outward::point(0.5);
        let kinetic = sum_exactly(owned.iter().map(|s| half * s.m * crate::real::norm2(&s.v)));
        let momentum = std::array::from_fn(|c| sum_exactly(owned.iter().map(|s| s.m * s.v[c])));
        let mut potential = Outward::point(0.0);
        let mut instances = 0;
        for (n, t) in l.model.terms.iter().enumerate() {
            if t.sites.is_empty() {
                let near = Neighbourhood::new(&q.x, &q.cell, asked_reach(t), &[]);
                potential = potential + q.pairs_part(t.kind, n, &near, l.owned);
            } else if t.sites[0] < l.owned {
                let seen: Vec<Site<Outward>> =
                    t.sites.iter().map(|&j| q.seen_from(t.sites[0], j).into_owned()).collect();
                potential = potential + t.kind.potential(&q.params[n], &seen.iter().collect::<Vec<_>>());
                instances += 1;
            }
        }
        Part { bodies: l.owned, instances, energy: kinetic + potential, momentum, flaw: None }
    }

    /// The part as f64s, to travel between ranks (counts are exact in f64 below 2^53); a flaw
    /// travels as its presence, its words staying on the rank that found it.
    pub fn to_bits(&self) -> [f64; PART_BITS] {
        let (e, p) = (self.energy.bounds(), self.momentum.map(|c| c.bounds()));
        let flawed = if self.flaw.is_some() { 1.0 } else { 0.0 };
        let counts = [self.bodies as f64, self.instances as f64, flawed];
        [counts[0], counts[1], counts[2], e.0, e.1, p[0].0, p[0].1, p[1].0, p[1].1, p[2].0, p[2].1]
    }

    pub fn from_bits(b: &[f64], rank: usize) -> Part {
        let at = |k: usize| Outward::from_bounds(b[k], b[k + 1]);
        let flaw =
            (b[2] != 0.0).then(|| format!("rank {rank}'s part failed its own checks (it says why on its stderr)"));
        Part { bodies: b[0] as usize, instances: b[1] as usize, energy: at(3), momentum: [at(5), at(7), at(9)], flaw }
    }
}

/// Every rank's part at one state, in rank order, and the numbers of the bodies rank 0
/// gathered there (each rank's owned, one after another).
#[derive(Clone, Debug)]
pub struct Parts {
    pub parts: Vec<Part>,
    pub numbers: Vec<usize>,
}

/// The whole's energy (without a thermostat's share) and momentum, enclosed from the parts.
#[derive(Clone, Copy, Debug)]
pub struct Whole {
    pub energy: Outward,
    pub momentum: [Outward; 3],
}

impl Parts {
    /// The parts added outward in rank order, if they stand for the whole `model`: none has a
    /// flaw, the owned bodies are every body once, the instances counted are every bonded
    /// instance, and no term adds a share to the momentum.
    pub fn whole(&self, model: &Model) -> Result<Whole, String> {
        if let Some(f) = self.parts.iter().find_map(|p| p.flaw.as_ref()) {
            return Err(f.clone());
        }
        let n = model.bodies.len();
        let owned: usize = self.parts.iter().map(|p| p.bodies).sum();
        let mut seen = vec![false; n];
        let once = self.numbers.iter().all(|&i| i < n && !std::mem::replace(&mut seen[i], true));
        if owned != n || self.numbers.len() != n || !once {
            return Err(format!("the ranks' bodies are not the {n} bodies each once"));
        }
        let bonded = model.terms.iter().filter(|t| !t.sites.is_empty()).count();
        let counted: usize = self.parts.iter().map(|p| p.instances).sum();
        if counted != bonded {
            return Err(format!("the ranks counted {counted} bonded instances of {bonded}"));
        }
        if let Some(t) = model.terms.iter().find(|t| t.kind.has_charge_share()) {
            return Err(format!("a {} term adds a share to the momentum", t.kind.name()));
        }
        if model.bodies.iter().any(|b| b.moments.is_some()) {
            return Err("rigid bodies' spin is not in the parts".into());
        }
        let zero = Outward::point(0.0);
        let energy = self.parts.iter().fold(zero, |acc, p| acc + p.energy);
        let momentum = std::array::from_fn(|c| self.parts.iter().fold(zero, |acc, p| acc + p.momentum[c]));
        Ok(Whole { energy, momentum })
    }
}

/// Whether the rank's model is the whole's restricted to its bodies (see the module's note).
fn restricts(l: &Local) -> Result<(), String> {
    let (m, w) = (l.model, l.whole);
    let len = m.bodies.len();
    if l.state.x.len() != len || l.state.v.len() != len || l.numbers.len() != len || l.owned > len {
        return Err("the rank's state, numbers and bodies differ in length".into());
    }
    if !l.state.x.iter().chain(l.state.v).flatten().all(|c| c.is_finite()) {
        return Err("the rank's state is not finite".into());
    }
    let mut sorted = l.numbers.to_vec();
    sorted.sort_unstable();
    if sorted.windows(2).any(|p| p[0] == p[1]) || sorted.last().is_some_and(|&i| i >= w.bodies.len()) {
        return Err("the rank's bodies are not distinct bodies of the whole".into());
    }
    if m.bodies.iter().zip(l.numbers).any(|(b, &i)| *b != w.bodies[i]) || m.cell != w.cell {
        return Err("a body or the box differs from the whole's".into());
    }
    fn pairs(m: &Model) -> Vec<&TermInstance> {
        m.terms.iter().filter(|t| t.sites.is_empty()).collect()
    }
    if pairs(m) != pairs(w) {
        return Err("the rank's terms on every pair are not the whole's".into());
    }
    let whole_bonded: Vec<&TermInstance> = w.terms.iter().filter(|t| !t.sites.is_empty()).collect();
    let local_bonded: Vec<&TermInstance> = m.terms.iter().filter(|t| !t.sites.is_empty()).collect();
    if local_bonded.len() != l.instances.len() || l.instances.windows(2).any(|p| p[0] >= p[1]) {
        return Err("the rank's bonded instances are not numbered in increasing order".into());
    }
    for (t, &k) in local_bonded.iter().zip(l.instances) {
        let same = whole_bonded.get(k).is_some_and(|o| {
            o.kind == t.kind
                && o.params == t.params
                && o.sites.len() == t.sites.len()
                && o.sites.iter().zip(&t.sites).all(|(&i, &j)| j < len && l.numbers[j] == i)
        });
        if !same {
            return Err(format!("the rank's bonded instance {k} is not the whole's"));
        }
    }
    for t in &m.terms {
        let fits = match t.kind.spec().shape {
            Shape::Pairwise => t.sites.is_empty() && asked_reach(t).is_some(),
            Shape::Bond(_) => !t.sites.is_empty(),
            _ => false,
        };
        if !fits {
            return Err(format!("a {} term is not summed in parts", t.kind.name()));
        }
    }
    Ok(())
}

/// Whether every owned body that may lie within the pair terms' reach of another rank's region
/// was sent there, and this rank's region holds its owned bodies.
fn covers(l: &Local) -> Result<(), String> {
    let cell = &l.model.cell;
    let owned = &l.state.x[..l.owned];
    let mine = l.regions.get(l.rank).ok_or("no region for this rank")?;
    if Region::of(owned, mine.centre, cell) != *mine || l.sent.len() != l.regions.len() {
        return Err("the rank's region is not that of its bodies".into());
    }
    let reach = l.model.terms.iter().filter(|t| t.sites.is_empty()).filter_map(asked_reach).fold(0.0, f64::max);
    let near = l.regions.iter().enumerate().filter(|(r, region)| *r != l.rank && mine.meets(region, reach, cell));
    for (r, region) in near {
        let mut sent = l.sent[r].clone();
        sent.sort_unstable();
        if let Some(k) = (0..l.owned).find(|&k| region.near(owned[k], reach, cell) && sent.binary_search(&k).is_err()) {
            return Err(format!("body {} may be within reach of rank {r}'s bodies but is not its ghost", l.numbers[k]));
        }
    }
    Ok(())
}

impl Lifted<Outward> {
    /// Σ over the pairs `near` holds of instance `n`'s potential, a pair of two owned bodies
    /// (`i < owned`) whole, of one owned body half, of none not at all: as
    /// `PairSum::add_potentials` sums, sixteen pairs at a time and exactly, in two sums.
    fn pairs_part(&self, kind: Kind, n: usize, near: &Neighbourhood, owned: usize) -> Outward {
        // [halves, wholes]: a pair counts by how many of its bodies are owned, none not at all
        let [halves, wholes] = self.exact_lane_sums((kind, Summed::Potential), n, near, |q| {
            (usize::from(q.i < owned) + usize::from(q.j < owned)).checked_sub(1)
        });
        let sum = |(lo, hi): (ExactSum, ExactSum)| Outward::from_bounds(lo.total(Round::Down), hi.total(Round::Up));
        sum(wholes) + sum(halves) * Outward::point(0.5)
    }
}

#[cfg(test)]
mod tests;
