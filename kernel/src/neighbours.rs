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

use crate::lanes::{norm2, F64x4, Lane};
use crate::pieces::Pieces;
use crate::step::BLOCK;
use lagra_checker::model::Cell;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::ops::Range;

/// Bodies from which the passes over them spread over the pool's threads, a thread taking
/// `BLOCK` at once (below, waking them costs more than the pass).
const SPREAD_FROM: usize = 4 * BLOCK;

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

#[derive(Clone)]
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
}

impl Neighbours {
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
        let spread = pool.filter(|_| x.len() >= SPREAD_FROM);
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
        let (first, second) = match spread {
            Some(pool) => pool.install(|| {
                x.par_iter()
                    .zip(&self.at)
                    .with_min_len(BLOCK)
                    .fold(|| (0.0, 0.0), |t, pq| top_two(t, moved(pq)))
                    .reduce(|| (0.0, 0.0), |a, b| top_two(top_two(a, b.0), b.1))
            }),
            None => x.iter().zip(&self.at).fold((0.0, 0.0), |t, pq| top_two(t, moved(pq))),
        };
        if self.at.len() != x.len() || !(first.sqrt() + second.sqrt() < self.skin * (1.0 - 1e-9)) {
            self.build(x, cell, pool);
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
        match spread {
            Some(pool) => {
                pool.install(|| self.x.par_iter_mut().enumerate().with_min_len(BLOCK / LANES).for_each(gather))
            }
            None => self.x.iter_mut().enumerate().for_each(gather),
        }
    }

    /// The positions the list was last built at (empty before the first build): with them a
    /// list rebuilt elsewhere (`build`) is this one, the same pairs in the same order.
    pub fn built_at(&self) -> &[[f64; 3]] {
        &self.at
    }

    /// Builds the list at positions `x` (a restart's `built_at`, or the state's).
    pub fn build(&mut self, x: &[[f64; 3]], cell: &Option<Cell>, pool: Option<&ThreadPool>) {
        let spread = pool.filter(|_| x.len() >= SPREAD_FROM);
        self.at.clear();
        self.at.extend_from_slice(x);
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
        let far = far(&wrapped, self.reach + self.skin, spread);
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
        let search = Search {
            columns: &columns,
            first: &first,
            boxes: &boxes,
            x: &self.x,
            shifts: &self.shifts,
            r: self.reach + self.skin,
        };
        let n = boxes.len();
        self.start.clear();
        self.pairs.clear();
        // in parts, each listed on its own and joined in order: the same list as one pass makes;
        // as many as there are threads, or one per 1,024 clusters if more, so that a thread
        // done early takes another
        let parts = pool.map_or(1, |p| p.current_num_threads().max(n / 1024));
        let ranges: Vec<Range<usize>> = (0..parts).map(|k| n * k / parts..n * (k + 1) / parts).collect();
        let listed: Vec<(Vec<usize>, Vec<Pair>)> = match pool {
            Some(p) if parts > 1 => p.install(|| ranges.into_par_iter().map(|r| search.part(r)).collect()),
            _ => ranges.into_iter().map(|r| search.part(r)).collect(),
        };
        for (s, p) in listed {
            let base = self.pairs.len();
            self.start.extend(s.into_iter().map(|k| k + base));
            self.pairs.extend_from_slice(&p);
        }
        self.start.push(self.pairs.len());
        self.slot = vec![EMPTY; x.len()];
        for (slot, &b) in self.bodies.iter().enumerate() {
            if b != EMPTY {
                self.slot[b as usize] = slot as u32;
            }
        }
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

/// `f(i)` for i in `0..n`, in order, on the pool's threads if there is one (each value its
/// own: the same values either way).
fn each<U: Send>(spread: Option<&ThreadPool>, n: usize, f: impl Fn(usize) -> U + Sync + Send) -> Vec<U> {
    match spread {
        Some(pool) => pool.install(|| (0..n).into_par_iter().with_min_len(BLOCK / LANES).map(f).collect()),
        None => (0..n).map(f).collect(),
    }
}

/// Where empty slots sit: 10 r beyond the farthest coordinate of any body, 4 r apart along x,
/// so that no body and no other empty slot is within r of one, the bodies' moves between builds
/// (less than the skin) included, and no distance to one squares into a subnormal's range.
fn far(w: &[[f64; 3]], r: f64, spread: Option<&ThreadPool>) -> impl Fn(usize) -> [f64; 3] {
    let largest = |p: &[f64; 3]| p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    // (the largest of a set is the same however it is split)
    let base = match spread {
        Some(pool) => pool.install(|| w.par_iter().with_min_len(BLOCK).map(largest).reduce(|| 0.0, f64::max)),
        None => w.iter().map(largest).fold(0.0, f64::max),
    } + 10.0 * r
        + 1.0;
    move |slot| [base + 4.0 * r * slot as f64, base, base]
}

/// An axis-aligned box around a cluster's bodies.
#[derive(Clone, Copy)]
struct Bounds {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Bounds {
    fn of<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> Bounds {
        points.fold(Bounds { lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] }, |b, p| Bounds {
            lo: std::array::from_fn(|a| b.lo[a].min(p[a])),
            hi: std::array::from_fn(|a| b.hi[a].max(p[a])),
        })
    }
}

/// Columns along x and y over the box (periodic axes) or over the bodies' extent (open axes).
struct Columns {
    n: [usize; 2],
    lo: [f64; 2],
    width: [f64; 2],
    /// Box lengths along periodic axes (x, y, z), 0 along open ones.
    period: [f64; 3],
}

impl Columns {
    fn new(w: &[[f64; 3]], cell: &Option<Cell>) -> Columns {
        let period: [f64; 3] = std::array::from_fn(|a| cell.filter(|c| c.periodic[a]).map_or(0.0, |c| c.size[a]));
        let span = |a: usize| {
            if period[a] > 0.0 {
                (0.0, period[a])
            } else {
                let (lo, hi) =
                    w.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                (lo, (hi - lo).max(f64::MIN_POSITIVE))
            }
        };
        let (x, y, z) = (span(0), span(1), span(2));
        // four bodies to a cube of side (4V/N)^(1/3); no more columns than a quarter of the
        // bodies, however flat or thin their spread (the last two bounds)
        let per = w.len() as f64 / LANES as f64;
        let side = (x.1 * y.1 * z.1 / per).cbrt().max((x.1 * y.1 / per).sqrt()).max(x.1.max(y.1) / per);
        let count = |side: f64, len: f64| ((len / side).floor() as usize).clamp(1, 1 << 20);
        let n = [count(side, x.1), count(side, y.1)];
        Columns { n, lo: [x.0, y.0], width: [x.1 / n[0] as f64, y.1 / n[1] as f64], period }
    }

    /// How many columns along axis a can hold a body within r of a body in a given column (no
    /// more than the columns there are: a flat spread has columns thinner than r).
    fn reach(&self, a: usize, r: f64) -> i64 {
        ((r / self.width[a]).floor() as i64).min(self.n[a] as i64) + 1
    }

    fn index(&self, a: usize, u: f64) -> usize {
        (((u - self.lo[a]) / self.width[a]).floor().max(0.0) as usize).min(self.n[a] - 1)
    }

    /// The bodies by slot, columns in order, each column's sorted by z and cut into clusters;
    /// and each column's first cluster (one more entry, the total, at the end).
    fn clusters(&self, w: &[[f64; 3]], spread: Option<&ThreadPool>) -> (Vec<u32>, Vec<usize>) {
        let columns = self.n[0] * self.n[1];
        let column: Vec<usize> = each(spread, w.len(), |i| self.index(0, w[i][0]) + self.n[0] * self.index(1, w[i][1]));
        let mut count = vec![0usize; columns + 1];
        column.iter().for_each(|&c| count[c + 1] += 1);
        for c in 0..columns {
            count[c + 1] += count[c];
        }
        let mut order = vec![0u32; w.len()];
        let mut next = count.clone();
        for (i, &c) in column.iter().enumerate() {
            order[next[c]] = i as u32;
            next[c] += 1;
        }
        // each column's run sorted by z (then by body: a total order, so the same runs however
        // the columns are shared out)
        let mut runs: Vec<&mut [u32]> = Vec::with_capacity(columns);
        let mut rest = &mut order[..];
        for c in 0..columns {
            let (run, tail) = rest.split_at_mut(count[c + 1] - count[c]);
            runs.push(run);
            rest = tail;
        }
        let by_z = |run: &mut &mut [u32]| {
            run.sort_unstable_by(|&a, &b| w[a as usize][2].total_cmp(&w[b as usize][2]).then(a.cmp(&b)))
        };
        match spread {
            Some(pool) => pool.install(|| runs.par_iter_mut().for_each(by_z)),
            None => runs.iter_mut().for_each(by_z),
        }
        let (mut slots, mut first) = (Vec::with_capacity(w.len() + LANES * columns), Vec::with_capacity(columns + 1));
        for c in 0..columns {
            let run = &order[count[c]..count[c + 1]];
            first.push(slots.len() / LANES);
            slots.extend_from_slice(run);
            slots.resize(slots.len().next_multiple_of(LANES), EMPTY);
        }
        first.push(slots.len() / LANES);
        (slots, first)
    }
}

/// Where the search of each neighbouring column (offset along x and y, image along z) has got
/// to, for the i-clusters of one column, taken in z order.
struct Cursors {
    at: Vec<(usize, usize)>,
    ny: usize,
    reach: [usize; 2],
}

/// What the pair search reads: the clusters by column, their boxes and positions.
struct Search<'a> {
    columns: &'a Columns,
    first: &'a [usize],
    boxes: &'a [Bounds],
    x: &'a [Cluster],
    shifts: &'a [[f64; 3]; 32],
    r: f64,
}

impl Search<'_> {
    /// The i-clusters `part`: where each one's pairs start (from 0) and the pairs.
    fn part(&self, part: Range<usize>) -> (Vec<usize>, Vec<Pair>) {
        let (mut start, mut pairs) = (vec![], vec![]);
        let mut column = self.first.partition_point(|&f| f <= part.start) - 1;
        let reach = [0, 1].map(|a| self.columns.reach(a, self.r) as usize);
        let mut cursors = Cursors { at: vec![], ny: 2 * reach[1] + 1, reach };
        for ic in part {
            if self.first[column + 1] <= ic || cursors.at.is_empty() {
                while self.first[column + 1] <= ic {
                    column += 1;
                }
                cursors.at = vec![(0, 0); (2 * reach[0] + 1) * cursors.ny * 3];
            }
            start.push(pairs.len());
            self.near(ic, column, &mut cursors, &mut pairs);
        }
        (start, pairs)
    }

    /// Whether some body of cluster `ic` lies within r of one of cluster `jc` moved by `s` (empty
    /// slots are far from everything): boxes within r whose bodies are not (a third of them on a
    /// dense liquid) are left out. Sixteen distances, no branch.
    #[inline(always)]
    fn touch(&self, ic: usize, jc: usize, s: &[f64; 3]) -> bool {
        let (xi, xj) = (&self.x[ic], &self.x[jc]);
        let xs = [xj[0] + s[0], xj[1] + s[1], xj[2] + s[2]];
        let mut least = F64x4::splat(f64::INFINITY);
        for a in 0..LANES {
            let d = [xs[0] - xi[0].lane(a), xs[1] - xi[1].lane(a), xs[2] - xi[2].lane(a)];
            least = least.min(norm2(&d));
        }
        least.least() < self.r * self.r
    }

    /// The clusters whose boxes lie within r of cluster `ic`'s (in column `column`), each
    /// cluster pair once: j after i, or i itself at the zero image or a later one.
    fn near(&self, ic: usize, column: usize, cursors: &mut Cursors, out: &mut Vec<Pair>) {
        let g = self.columns;
        let b = &self.boxes[ic];
        let (cx, cy) = ((column % g.n[0]) as i64, (column / g.n[0]) as i64);
        // offsets along an axis: all within r of the column (and one wrap at most, since the
        // box is longer than 2r); on an open axis, only columns that exist
        let offsets = |a: usize, c: i64| {
            let (n, reach) = (g.n[a] as i64, cursors.reach[a] as i64);
            let (lo, hi) =
                if g.period[a] > 0.0 { (c - reach, c + reach) } else { ((c - reach).max(0), (c + reach).min(n - 1)) };
            // each with its place among the 2·reach + 1 offsets, for its cursors
            (lo..=hi).map(move |j| (j.rem_euclid(n) as usize, j.div_euclid(n), (j - c + reach) as usize))
        };
        // along a periodic z, the image below (above) can reach only a box within r of the
        // bottom (top) of the box
        let z = g.period[2];
        let z_images: &[i64] = match (z > 0.0 && b.lo[2] < self.r, z > 0.0 && b.hi[2] + self.r > z) {
            (true, true) => &[-1, 0, 1],
            (true, false) => &[-1, 0],
            (false, true) => &[0, 1],
            (false, false) => &[0],
        };
        for (jx, nx, ix) in offsets(0, cx) {
            let sx = nx as f64 * g.period[0];
            let (lo, hi) = (g.lo[0] + jx as f64 * g.width[0] + sx, g.lo[0] + (jx + 1) as f64 * g.width[0] + sx);
            let gx = (lo - b.hi[0]).max(b.lo[0] - hi).max(0.0);
            for (jy, ny, iy) in offsets(1, cy) {
                let sy = ny as f64 * g.period[1];
                let (lo, hi) = (g.lo[1] + jy as f64 * g.width[1] + sy, g.lo[1] + (jy + 1) as f64 * g.width[1] + sy);
                let gy = (lo - b.hi[1]).max(b.lo[1] - hi).max(0.0);
                if gx * gx + gy * gy >= self.r * self.r {
                    continue;
                }
                let col = jx + g.n[0] * jy;
                // clusters are numbered column by column: an earlier column's come before ic's
                if col < column {
                    continue;
                }
                let run = &self.boxes[self.first[col]..self.first[col + 1]];
                for &nz in z_images {
                    let sz = nz as f64 * g.period[2];
                    let image = (nx + 1) as usize + 3 * (ny + 1) as usize + 9 * (nz + 1) as usize;
                    let s = &self.shifts[image];
                    // the column's clusters are in z order, their lower and upper bounds both, and
                    // so are ic's column's: the range only moves up, cluster by cluster
                    let (from, to) = &mut cursors.at[((ix * cursors.ny) + iy) * 3 + (nz + 1) as usize];
                    while *from < run.len() && run[*from].hi[2] + sz < b.lo[2] - self.r {
                        *from += 1;
                    }
                    *to = (*to).max(*from);
                    while *to < run.len() && run[*to].lo[2] + sz <= b.hi[2] + self.r {
                        *to += 1;
                    }
                    // bodies within r imply boxes within r: the sixteen distances alone decide,
                    // each candidate written and kept by advancing the end (no branch to miss)
                    let base = self.first[col];
                    let from = (*from + base).max(if image >= CENTRE { ic } else { ic + 1 });
                    let to = *to + base;
                    let mut end = out.len();
                    out.resize(end + to.saturating_sub(from), Pair(0));
                    for jc in from..to {
                        out[end] = Pair::new(jc, image);
                        end += usize::from(self.touch(ic, jc, s));
                    }
                    out.truncate(end);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::dual::Rng;
    use crate::traverse;
    use proptest::prelude::*;

    /// Every pair of bodies the list holds within `reach`, as (smaller, larger), sorted, each
    /// with its displacement checked against the minimum image of the positions.
    fn listed_within(list: &Neighbours, x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<(usize, usize)> {
        let mut listed = vec![];
        list.each_pair::<()>(|i, j, d| {
            if d.iter().map(|c| c * c).sum::<f64>() < reach * reach {
                let exact = Cell::image(cell, std::array::from_fn(|a| x[j][a] - x[i][a]));
                assert!((0..3).all(|a| (exact[a] - d[a]).abs() < 1e-9), "{i} {j}: {d:?} vs {exact:?}");
                listed.push((i.min(j), i.max(j)));
            }
            Ok(())
        })
        .unwrap();
        listed.sort();
        listed
    }

    fn all_within(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<(usize, usize)> {
        let mut all = vec![];
        traverse::pairs::<()>(x, cell, None, |i, j, d| {
            if d.iter().map(|c| c * c).sum::<f64>() < reach * reach {
                all.push((i.min(j), i.max(j)));
            }
            Ok(())
        })
        .unwrap();
        all.sort();
        all
    }

    proptest! {
        /// After the bodies move so that no two together moved the skin (one up to 0.7 of it, the
        /// rest up to 0.29), the stale list still holds every pair within reach exactly once,
        /// and its stored image gives the minimum-image displacement.
        #[test]
        fn a_stale_list_still_holds_every_pair_within_reach_once(seed in any::<u64>(), n in 64usize..300, side in 6.0f64..14.0, periodic in any::<bool>()) {
            let mut rng = Rng::new(seed);
            let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, rng.uniform(0.0, 1.0) < 0.7, rng.uniform(0.0, 1.0) < 0.5] });
            let reach = 2.5;
            // bodies that have drifted out of the box, as unwrapped positions do in a long run
            let mut x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-3.0 * side, 4.0 * side))).collect();
            let mut list = Neighbours::new(&cell, reach).unwrap();
            list.update(&x, &cell, None);
            let far = rng.uniform(0.0, n as f64) as usize;
            for (i, p) in x.iter_mut().enumerate() {
                let most = if i == far { 0.7 } else { 0.29 } * list.skin / 3f64.sqrt();
                p.iter_mut().for_each(|c| *c += rng.uniform(-most, most));
            }
            list.update(&x, &cell, None);
            prop_assert_eq!(list.builds, 1);
            prop_assert_eq!(list.bodies.iter().filter(|&&b| b != EMPTY).count(), n);
            prop_assert_eq!(listed_within(&list, &x, &cell, reach), all_within(&x, &cell, reach));
        }
    }

    /// Bodies spread along a line in open space: few columns, and still every pair.
    #[test]
    fn bodies_on_a_line_are_listed() {
        let x: Vec<[f64; 3]> = (0..500).map(|i| [i as f64 * 0.7, 0.0, 0.0]).collect();
        let mut list = Neighbours::new(&None, 2.5).unwrap();
        list.update(&x, &None, None);
        assert_eq!(listed_within(&list, &x, &None, 2.5), all_within(&x, &None, 2.5));
    }

    /// A list built in parts on 2 or 3 threads is the list one pass builds.
    #[test]
    fn the_list_is_the_same_on_any_number_of_threads() {
        let mut rng = Rng::new(11);
        // 3,000 bodies (the passes over them on one thread), and 20,000 (spread over the pool)
        for (n, side) in [(3000, 16.0), (20_000, 30.0)] {
            let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
            let x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-4.0, side + 4.0))).collect();
            let built = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let mut list = Neighbours::new(&cell, 2.5).unwrap();
                list.update(&x, &cell, (threads > 1).then_some(&pool));
                let x: Vec<_> = list.x.iter().flatten().flat_map(|v| v.to_array().map(f64::to_bits)).collect();
                (list.bodies, list.start, list.pairs, x, list.offset, list.slot, list.pieces.place)
            };
            let one = built(1);
            assert!(one.2.len() > 3 * n, "{}", one.2.len());
            assert!(built(2) == one && built(3) == one && built(7) == one);
        }
    }

    /// Clusters are compact, and boxes within reach whose bodies are not are left out: on a
    /// dense box at reach 2.5, over a fifth of the body pairs in the listed cluster pairs lie
    /// within reach (26% measured; 18% with boxes alone).
    #[test]
    fn clusters_are_compact_enough_that_most_work_counts() {
        let mut rng = Rng::new(2);
        let side = (4000.0f64 / 0.8442).cbrt();
        let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
        let x: Vec<[f64; 3]> = (0..4000).map(|_| std::array::from_fn(|_| rng.uniform(0.0, side))).collect();
        let mut list = Neighbours::new(&cell, 2.5).unwrap();
        list.update(&x, &cell, None);
        let within = listed_within(&list, &x, &cell, 2.5).len();
        let computed = 16 * list.count();
        assert!(5 * within > computed, "{within} of {computed}");
    }

    /// Two bodies that together moved just over the skin (three quarters and a third of it)
    /// bring a rebuild; either alone does not.
    #[test]
    fn two_bodies_moving_the_skin_together_rebuild_the_list() {
        let mut x: Vec<[f64; 3]> =
            (0..100).map(|i| [(i % 5) as f64 * 3.0, (i / 5 % 5) as f64 * 3.0, (i / 25) as f64 * 3.0]).collect();
        let mut list = Neighbours::new(&None, 2.5).unwrap();
        list.update(&x, &None, None);
        x[7][0] += 0.75 * list.skin;
        list.update(&x, &None, None);
        assert_eq!(list.builds, 1);
        x[40][1] -= 0.34 * list.skin;
        list.update(&x, &None, None);
        assert_eq!(list.builds, 2);
    }

    #[test]
    fn a_box_too_small_for_the_skin_gets_no_list() {
        let cell = Some(Cell { size: [5.0; 3], periodic: [true; 3] });
        assert!(Neighbours::new(&cell, 2.5).is_none());
        assert!(Neighbours::new(&None, 2.5).is_some());
    }
}
