//! The cluster-pair Verlet list, after GROMACS's nbnxm: bodies are grouped four to a cluster of
//! nearby bodies, and the list holds pairs of clusters whose bounding boxes lie within
//! reach + skin, each pair once (Newton's third law), with the periodic image it was found at.
//! The kernel (`forces::clusters`) computes all sixteen body pairs of a cluster pair in four-lane
//! arithmetic and masks those beyond the cutoff.
//!
//! At a build the bodies are wrapped into the box (their wrap offsets kept) and binned into
//! columns along x and y about (4/ρ)^(1/3) wide, so that four bodies in a column sorted by z
//! fill a roughly cubic box; each column's bodies, sorted by z, are cut into clusters (the last
//! padded with empty slots). Between builds the kernel reads positions minus the fixed offsets,
//! gathered into cluster order every step, which move continuously, so a listed image stays
//! right. The list is rebuilt once the two bodies that moved most since the last build have
//! together moved more than the skin: until then no unlisted pair can have come within reach.
//! Everything here depends on the positions alone, never on the number of threads.

use crate::lanes::F64x4;
use crate::pieces::Pieces;
use crate::spread::{self, each, SPREAD_FROM};
use crate::step::BLOCK;
use lagra_checker::model::Cell;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::ops::Range;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
use std::time::{Duration, Instant};

mod search;
use search::{far, joined, Bounds, Columns, Search};

/// The skin as a fraction of the reach (LAMMPS's 0.3 for a 2.5 cutoff).
const SKIN: f64 = 0.12;

/// Bodies per cluster: the lanes of `F64x4`.
pub const LANES: usize = 4;

/// A slot of a cluster that holds no body.
pub const EMPTY: u32 = u32::MAX;

/// The index of the zero image shift.
pub const CENTRE: usize = 13;

/// A cluster's four positions (or forces), coordinate-major: `[c]` holds coordinate c of the
/// four slots, so that one load gives a coordinate of all four.
pub type Cluster = [F64x4; 3];

/// A listed j-cluster: its index in the low 27 bits, the index of the image shift to add to
/// its positions (`Neighbours::shifts`) in the high 5.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair(u32);

impl Pair {
    /// Clusters a list can index (larger scenes get no list).
    pub const CLUSTERS: usize = 1 << 27;
    fn new(j: usize, image: usize) -> Pair {
        Pair(j as u32 | (image as u32) << 27)
    }
    #[inline(always)]
    pub fn j(self) -> usize {
        (self.0 & (Self::CLUSTERS as u32 - 1)) as usize
    }
    #[inline(always)]
    pub fn image(self) -> usize {
        (self.0 >> 27) as usize
    }
}

pub struct Neighbours {
    pub reach: f64,
    pub skin: f64,
    /// The body in each slot (cluster c holds slots 4c..4c + 4), or `EMPTY`.
    pub bodies: Vec<u32>,
    /// The j-clusters of i-cluster c are `pairs[start[c]..start[c + 1]]`.
    pub start: Vec<usize>,
    pub pairs: Vec<Pair>,
    /// The periodic image shifts by index: n₀ + 3n₁ + 9n₂ for nₐ − 1 box lengths along axis a
    /// (27 used; 32, so that any 5-bit index is in bounds).
    pub shifts: [[f64; 3]; 32],
    /// Positions at the last build, by body.
    at: Vec<[f64; 3]>,
    /// What was taken off each slot's body to wrap it into the box at the last build.
    offset: Vec<[f64; 3]>,
    /// The positions minus `offset`, by cluster, as of the last `update`: what the kernel reads.
    /// An empty slot sits far from every body and every other slot (`far`), so that the cutoff
    /// leaves it out with no mask of its own.
    pub x: Vec<Cluster>,
    /// Each body's slot (the inverse of `bodies`).
    pub slot: Vec<u32>,
    /// The i-clusters cut into pieces for the threads (`pieces`), with the list.
    pub pieces: Pieces,
    pub builds: u64,
    /// Wall time on the calling thread in the list's passes (`--explain`).
    pub spent: Spent,
    /// Bodies from this one on are ghosts, whose forces the caller drops: a cluster pair with
    /// only ghosts in both is left out (`leave_out_pairs_among`).
    ghosts_from: usize,
}

/// Where a list's time went, as the calling thread's wall clock sees it: the builds, and the
/// updates between builds (the displacement test and the positions' gather).
#[derive(Clone, Copy, Debug, Default)]
pub struct Spent {
    pub builds: Duration,
    pub updates: Duration,
}

impl Neighbours {
    /// A copy of the list, made on the pool's threads (`spread::copy`): a gradient saves one at
    /// each checkpoint and at each rebuild of its replays.
    pub fn copied(&self, pool: Option<&ThreadPool>) -> Neighbours {
        let mut into = Neighbours {
            bodies: vec![],
            start: vec![],
            pairs: vec![],
            at: vec![],
            offset: vec![],
            x: vec![],
            slot: vec![],
            pieces: Pieces::default(),
            ..*self
        };
        into.copy_from(self, pool);
        into
    }

    /// This list made a copy of `from` in the memory it holds, on the pool's threads: a
    /// gradient's backward pass puts a saved list back dozens of times. Every field is named, so
    /// that a field added is a compile error here.
    pub fn copy_from(&mut self, from: &Neighbours, pool: Option<&ThreadPool>) {
        let Neighbours {
            reach,
            skin,
            bodies,
            start,
            pairs,
            shifts,
            at,
            offset,
            x,
            slot,
            pieces,
            builds,
            spent,
            ghosts_from,
        } = self;
        (*reach, *skin, *shifts, *builds, *spent, *ghosts_from) =
            (from.reach, from.skin, from.shifts, from.builds, from.spent, from.ghosts_from);
        spread::copy(pool, bodies, &from.bodies);
        spread::copy(pool, start, &from.start);
        spread::copy(pool, pairs, &from.pairs);
        spread::copy(pool, at, &from.at);
        spread::copy(pool, offset, &from.offset);
        spread::copy(pool, x, &from.x);
        spread::copy(pool, slot, &from.slot);
        pieces.copy_from(&from.pieces, pool);
    }

    /// `None` where a list could pick the wrong image: a periodic axis shorter than twice
    /// reach + skin.
    pub fn new(cell: &Option<Cell>, reach: f64) -> Option<Neighbours> {
        let skin = SKIN * reach;
        let mut shifts = [[0.0; 3]; 32];
        if let Some(c) = cell {
            for a in 0..3 {
                if c.periodic[a] && c.size[a] <= 2.0 * (reach + skin) {
                    return None;
                }
            }
            for (k, s) in shifts.iter_mut().enumerate().take(27) {
                let n = [k % 3, (k / 3) % 3, k / 9];
                *s = std::array::from_fn(|a| (n[a] as f64 - 1.0) * c.size[a]);
            }
        }
        Some(Neighbours {
            reach,
            skin,
            bodies: vec![],
            start: vec![],
            pairs: vec![],
            shifts,
            at: vec![],
            offset: vec![],
            x: vec![],
            slot: vec![],
            pieces: Pieces::default(),
            builds: 0,
            spent: Spent::default(),
            ghosts_from: usize::MAX,
        })
    }

    pub fn clusters(&self) -> usize {
        self.x.len()
    }

    /// Listed cluster pairs.
    pub fn count(&self) -> usize {
        self.pairs.len()
    }

    /// Rebuilds the list if two bodies together moved more than the skin since the last build,
    /// and gathers the wrapped positions into cluster order.
    pub fn update(&mut self, x: &[[f64; 3]], cell: &Option<Cell>, pool: Option<&ThreadPool>) {
        // A pair the list left out was at least reach + skin apart at the build; it can have
        // come within reach only if its two bodies together moved more than the skin, so the
        // two largest displacements decide (less often than "one body moved half the skin",
        // and as exact). The 1e-9 keeps the test on the safe side of rounding.
        let updating = Instant::now();
        let top_two = |(first, second): (f64, f64), d2: f64| {
            if d2 > second {
                if d2 > first {
                    (d2, first)
                } else {
                    (first, d2)
                }
            } else {
                (first, second)
            }
        };
        let moved =
            |(p, q): (&[f64; 3], &[f64; 3])| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
        // (the two largest of a set are the same whichever way it is split)
        let (first, second) = spread::over(pool, x.len(), |on_pool| match on_pool {
            true => x
                .par_iter()
                .zip(&self.at)
                .with_min_len(BLOCK)
                .fold(|| (0.0, 0.0), |t, pq| top_two(t, moved(pq)))
                .reduce(|| (0.0, 0.0), |a, b| top_two(top_two(a, b.0), b.1)),
            false => x.iter().zip(&self.at).fold((0.0, 0.0), |t, pq| top_two(t, moved(pq))),
        });
        let mut built = Duration::ZERO;
        if self.at.len() != x.len() || !(first.sqrt() + second.sqrt() < self.skin * (1.0 - 1e-9)) {
            let building = Instant::now();
            self.build(x, cell, pool);
            built = building.elapsed();
            self.spent.builds += built;
        }
        let (bodies, offset) = (&self.bodies, &self.offset);
        let gather = |(c, cluster): (usize, &mut Cluster)| {
            let mut lanes = cluster.map(F64x4::to_array);
            for (lane, slot) in (LANES * c..LANES * (c + 1)).enumerate() {
                let b = bodies[slot];
                if b != EMPTY {
                    let (p, o) = (x[b as usize], offset[slot]);
                    (0..3).for_each(|k| lanes[k][lane] = p[k] - o[k]);
                }
            }
            *cluster = lanes.map(F64x4::new);
        };
        spread::over(pool, x.len(), |on_pool| match on_pool {
            true => self.x.par_iter_mut().enumerate().with_min_len(BLOCK / LANES).for_each(gather),
            false => self.x.iter_mut().enumerate().for_each(gather),
        });
        self.spent.updates += updating.elapsed() - built;
    }

    /// The positions the list was last built at (empty before the first build): with them a
    /// list rebuilt elsewhere (`build`) is this one, the same pairs in the same order.
    pub fn built_at(&self) -> &[[f64; 3]] {
        &self.at
    }

    /// Builds the list at positions `x` (a restart's `built_at`, or the state's).
    /// Bodies `first..` are ghosts (a domain's copies of another rank's atoms, `lagra_run::domains`):
    /// from the next build, pairs between clusters that hold only ghosts are not listed. The
    /// forces on the other bodies are the same sums (in another order where the pieces, cut by
    /// size, fall differently); the forces on ghosts and the potential energy leave them out.
    pub fn leave_out_pairs_among(&mut self, first: usize) {
        self.ghosts_from = first;
        self.at.clear();
    }

    pub fn build(&mut self, x: &[[f64; 3]], cell: &Option<Cell>, pool: Option<&ThreadPool>) {
        let spread = pool.filter(|_| x.len() >= SPREAD_FROM);
        self.at = each(spread, x.len(), |i| x[i]);
        let offset: Vec<[f64; 3]> = each(spread, x.len(), |i| match cell {
            None => [0.0; 3],
            Some(c) => {
                std::array::from_fn(|a| if c.periodic[a] { c.size[a] * (x[i][a] / c.size[a]).floor() } else { 0.0 })
            }
        });
        let wrapped: Vec<[f64; 3]> = each(spread, x.len(), |i| std::array::from_fn(|a| x[i][a] - offset[i][a]));
        let columns = Columns::new(&wrapped, cell);
        let (slots, first) = columns.clusters(&wrapped, spread);
        self.bodies = slots;
        let bodies = &self.bodies;
        self.offset =
            each(spread, bodies.len(), |s| if bodies[s] == EMPTY { [0.0; 3] } else { offset[bodies[s] as usize] });
        let period = cell.map_or(0.0, |c| (0..3).filter(|&a| c.periodic[a]).map(|a| c.size[a]).fold(0.0, f64::max));
        let far = far(&wrapped, self.reach + self.skin, period, spread);
        self.x = each(spread, bodies.len() / LANES, |c| {
            let at = |slot: usize| match bodies[slot] {
                EMPTY => far(slot),
                b => wrapped[b as usize],
            };
            std::array::from_fn(|k| F64x4::new(std::array::from_fn(|l| at(LANES * c + l)[k])))
        });
        let boxes: Vec<Bounds> = each(spread, bodies.len() / LANES, |c| {
            let slots = &bodies[LANES * c..LANES * (c + 1)];
            Bounds::of(slots.iter().filter(|&&b| b != EMPTY).map(|&b| &wrapped[b as usize]))
        });
        let ghostly = (self.ghosts_from < x.len()).then(|| {
            let g = self.ghosts_from;
            each(spread, bodies.len() / LANES, |c| {
                bodies[LANES * c..LANES * (c + 1)].iter().all(|&b| b == EMPTY || b as usize >= g)
            })
        });
        let column_boxes = each(spread, first.len() - 1, |c| Bounds::around(&boxes[first[c]..first[c + 1]]));
        let search = Search {
            columns: &columns,
            first: &first,
            boxes: &boxes,
            column_boxes: &column_boxes,
            x: &self.x,
            shifts: &self.shifts,
            r: self.reach + self.skin,
            ghostly: ghostly.as_deref(),
        };
        let n = boxes.len();
        // in parts, each listed on its own and joined in order: the same list as one pass makes;
        // as many as there are threads, or one per 1,024 clusters if more, so that a thread
        // done early takes another
        let parts = pool.map_or(1, |p| p.current_num_threads().max(n / 1024));
        let ranges: Vec<Range<usize>> = (0..parts).map(|k| n * k / parts..n * (k + 1) / parts).collect();
        let listed: Vec<(Vec<usize>, Vec<Pair>)> = spread::pass(|| match pool {
            Some(p) if parts > 1 => p.install(|| ranges.into_par_iter().map(|r| search.part(r)).collect()),
            _ => ranges.into_iter().map(|r| search.part(r)).collect(),
        });
        let pairs: Vec<&[Pair]> = listed.iter().map(|(_, p)| &p[..]).collect();
        self.pairs = joined(spread, &pairs, |_, p| p);
        let mut base = vec![0];
        base.extend(pairs.iter().scan(0, |total, p| {
            *total += p.len();
            Some(*total)
        }));
        // (each part's starts count from 0; a last part of one, 0 past the total, ends them)
        let starts: Vec<&[usize]> = listed.iter().map(|(s, _)| &s[..]).chain([&[0][..]]).collect();
        self.start = joined(spread, &starts, |part, k| k + base[part]);
        // each body's slot, scattered through atomics (a body has one slot: the same either way)
        let slot: Vec<AtomicU32> = each(spread, x.len(), |_| AtomicU32::new(EMPTY));
        each(spread, bodies.len(), |s| {
            if bodies[s] != EMPTY {
                slot[bodies[s] as usize].store(s as u32, Relaxed)
            }
        });
        self.slot = each(spread, x.len(), |b| slot[b].load(Relaxed));
        let pairs = &self.pairs;
        self.pieces = Pieces::cut(&self.start, |p| pairs[p].j(), pool);
        self.builds += 1;
    }

    /// Every listed pair of bodies, as the kernel sees it: `visit(i, j, d)` with d the
    /// displacement from body i to body j's listed image, computed as the kernel does, in list
    /// order (within or beyond the cutoff: the visitor decides).
    pub fn each_pair<E>(&self, mut visit: impl FnMut(usize, usize, [f64; 3]) -> Result<(), E>) -> Result<(), E> {
        for ic in 0..self.clusters() {
            for p in &self.pairs[self.start[ic]..self.start[ic + 1]] {
                let (jc, sh) = (p.j(), &self.shifts[p.image()]);
                let diagonal = jc == ic && p.image() == CENTRE;
                for a in 0..LANES {
                    let bi = self.bodies[LANES * ic + a];
                    if bi == EMPTY {
                        continue;
                    }
                    for b in if diagonal { a + 1 } else { 0 }..LANES {
                        let bj = self.bodies[LANES * jc + b];
                        if bj != EMPTY {
                            let d = std::array::from_fn(|k| (self.x[jc][k].lane(b) + sh[k]) - self.x[ic][k].lane(a));
                            visit(bi as usize, bj as usize, d)?;
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
