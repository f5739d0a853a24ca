//! Which pairs of bodies a pair term must look at: every pair whose nearest-image distance is
//! within its reach, each with the periodic image it is seen through. A pair left out must be
//! farther than the reach, so the argument is kept simple: bodies are binned into cells wider
//! than the reach by 1% — far more than any rounding in the binning, which is checked — and two
//! bodies whose cells are not adjacent (cyclically, on a periodic axis) are farther apart than
//! the reach; the pairs of adjacent cells are then kept by the nearest image's squared distance
//! in binary64 against the reach widened by what rounding can take off it (`scale`). Where no
//! such grid fits (few bodies, a periodic axis shorter than three cells, bodies scattered so far
//! that cells would outnumber them, coordinates so large that binning could round a body into
//! the wrong cell) every pair is tested. The pairs come out sorted, in the order of the double
//! loop over every pair, so the sums built from them do not depend on the grid.
//!
//! A checkpoint's pairs can also be listed ahead, from a state a few steps before it
//! (`Foreseen`, `foreseen.rs`): the pairs within a wider reach there hold every pair within
//! reach at the checkpoint while no body has moved far, which the checkpoint tests; it then
//! keeps the same pairs by the same distance test, without a grid.

use crate::model::{Cell, Images};
use std::ops::Range;
use std::sync::OnceLock;

mod foreseen;
pub use foreseen::{Foreseen, FORESIGHT};

/// Below this many bodies the double loop is as cheap as the grid.
const GRID_FROM: usize = 64;

/// Bodies `i < j` (j's nearest image is within reach of i).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Near {
    pub i: usize,
    pub j: usize,
}

/// The pairs, sorted, whose nearest images are within `reach` (`None`: unbounded, every pair).
pub fn within(x: &[[f64; 3]], cell: &Option<Cell>, reach: Option<f64>) -> Vec<Near> {
    Neighbourhood::new(x, cell, reach, &[]).of(0..x.len())
}

/// The bodies binned once, or a list made ahead that holds, to list the pairs within reach of
/// any run of bodies.
pub struct Neighbourhood<'a> {
    x: &'a [[f64; 3]],
    cell: &'a Option<Cell>,
    /// The reach asked for (`None`: unbounded).
    reach: Option<f64>,
    images: Images,
    /// The reach squared (∞: unbounded).
    limit: f64,
    bins: Option<Bins>,
    listed: Option<&'a Foreseen>,
    /// With a list made ahead, the grid after all, built the first time sorted pairs are asked
    /// for (`each`), once for every run of bodies.
    gridded: OnceLock<Box<Neighbourhood<'a>>>,
}

/// The grid, each body's cell, and the bodies by cell (cell m's are `members[start[m]..start[m
/// + 1]]`, in increasing order, their coordinates along axis a at `placed[a][start[m]..start[m
/// + 1]]`: a cell's positions sit together, a run of them loads as one vector).
struct Bins {
    grid: Grid,
    cells: Vec<[usize; 3]>,
    start: Vec<usize>,
    members: Vec<usize>,
    placed: [Vec<f64>; 3],
}

impl Bins {
    /// Appends cell n's bodies and their positions.
    fn copy_cell(&self, n: usize, bodies: &mut Vec<usize>, placed: &mut [Vec<f64>; 3]) {
        let cell = self.start[n]..self.start[n + 1];
        bodies.extend_from_slice(&self.members[cell.clone()]);
        placed.iter_mut().zip(&self.placed).for_each(|(to, from)| to.extend_from_slice(&from[cell.clone()]));
    }
}

impl<'a> Neighbourhood<'a> {
    /// The bodies at `x` binned for `reach`, unless one of the lists made `ahead` holds.
    pub fn new(x: &'a [[f64; 3]], cell: &'a Option<Cell>, reach: Option<f64>, ahead: &'a [Foreseen]) -> Self {
        // the rounding slack and the grid's bound on it (`scale`)
        let size = scale(x, cell);
        let limit =
            reach.map_or(f64::INFINITY, |r| ((r + (size + r) * 2f64.powi(-49)) * (1.0 + 2f64.powi(-48))).powi(2));
        let images = Images::of(cell);
        let gridded =
            reach.filter(|r| *r > 0.0 && r.is_finite() && x.len() >= GRID_FROM && size * 2f64.powi(-40) < 1e-3 * r);
        let listed = gridded.and_then(|r| ahead.iter().find(|f| f.holds(x, &images, r)));
        let grid = gridded.filter(|_| listed.is_none()).and_then(|r| Grid::new(x, cell, r * 1.01));
        let bins = grid.map(|grid| {
            let cells: Vec<[usize; 3]> = x.iter().map(|p| grid.cell_of(p)).collect();
            // a counting sort by cell
            let mut start = vec![0; grid.n.iter().product::<usize>() + 1];
            for c in &cells {
                start[grid.index(*c) + 1] += 1;
            }
            for k in 1..start.len() {
                start[k] += start[k - 1];
            }
            let mut members = vec![0; x.len()];
            let mut fill = start.clone();
            for (i, c) in cells.iter().enumerate() {
                members[fill[grid.index(*c)]] = i;
                fill[grid.index(*c)] += 1;
            }
            // a run of padding after the last body, for `test_run`
            let placed = std::array::from_fn(|a| members.iter().map(|&i| x[i][a]).chain([f64::NAN; RUN]).collect());
            Bins { grid, cells, start, members, placed }
        });
        Neighbourhood { x, cell, reach, images, limit, bins, listed, gridded: OnceLock::new() }
    }

    /// Whether `xj`, body j's position, has its nearest image within reach of body i.
    #[inline]
    fn near(&self, i: usize, xj: &[f64; 3]) -> bool {
        let e = self.images.image(std::array::from_fn(|a| xj[a] - self.x[i][a]));
        e[0] * e[0] + e[1] * e[1] + e[2] * e[2] <= self.limit
    }

    /// The pairs (i, j > i) within reach for i in `bodies`, sorted.
    pub fn of(&self, bodies: Range<usize>) -> Vec<Near> {
        let mut pairs = vec![];
        self.each(bodies, |i, js| pairs.extend(js.iter().map(|&j| Near { i, j })));
        pairs
    }

    /// `f(i, js)` for each i in `bodies` in turn, js being the bodies j > i within reach of i,
    /// increasing. A list made ahead holds a pair under either body, so the grid is built here
    /// instead, once (the checker's own sums, which use the list, take their pairs in no order).
    fn each(&self, bodies: Range<usize>, mut f: impl FnMut(usize, &[usize])) {
        if self.listed.is_some() {
            let grid = self.gridded.get_or_init(|| Box::new(Neighbourhood::new(self.x, self.cell, self.reach, &[])));
            return grid.each(bodies, f);
        }
        let mut js = vec![];
        for i in bodies {
            js.clear();
            if let Some(b) = &self.bins {
                b.grid.around(b.cells[i], |m| {
                    let (lo, hi) = (b.start[m], b.start[m + 1]);
                    // the cell's bodies after i (in increasing order): mostly all or none of them
                    let cell = &b.members[lo..hi];
                    let from = match (cell.first(), cell.last()) {
                        (Some(&first), _) if first > i => lo,
                        (_, Some(&last)) if last > i => lo + cell.partition_point(|&j| j <= i),
                        _ => return,
                    };
                    self.test_run(i, &b.members[from..hi], b.placed.each_ref().map(|p| &p[from..]), |j| js.push(j));
                });
                js.sort_unstable();
            } else {
                js.extend((i + 1..self.x.len()).filter(|&j| self.near(i, &self.x[j])));
            }
            f(i, &js);
        }
    }

    /// `keep(j)` for each body j of `bodies` in their order (placed at `placed`, whose
    /// coordinates run on for `RUN` more values, the padding after the last body) whose nearest
    /// image is within reach of body i: a run's tests first, then the passes.
    #[inline(always)]
    fn test_run(&self, i: usize, bodies: &[usize], placed: [&[f64]; 3], mut keep: impl FnMut(usize)) {
        for (at, bodies) in (0..).step_by(RUN).zip(bodies.chunks(RUN)) {
            let run = placed.map(|p| p[at..at + RUN].try_into().expect("placed coordinates are padded by a run"));
            // the bits past the last body are the padding's (or the next cell's) and are dropped
            each_kept(self.passed(i, run) & u32::MAX >> (RUN - bodies.len()), |k| keep(bodies[k]));
        }
    }

    /// Bit k set where the body placed at (xs[k], ys[k], zs[k]) is within reach of body i. A
    /// whole run at a time, into a register: the tests vectorise into compares and masks (one
    /// byte stored per test and read back eight at a time stalled on store forwarding).
    #[inline(always)]
    fn passed(&self, i: usize, [xs, ys, zs]: [&[f64; RUN]; 3]) -> u32 {
        (0..RUN).fold(0, |bits, k| bits | u32::from(self.near(i, &[xs[k], ys[k], zs[k]])) << k)
    }

    /// How many parts `each_unordered` can split the pairs into: the lists made ahead, the
    /// grid's cells, else the bodies.
    pub fn parts(&self) -> usize {
        let cells = self.bins.as_ref().map_or(self.x.len(), |b| b.start.len() - 1);
        self.listed.map_or(cells, Foreseen::lists)
    }

    /// `f(pairs)` for the pairs within reach whose first body (by the double loop), whose list
    /// (by a list made ahead) or whose cell (by the grid) is in `part`, a range of `0..parts()` —
    /// every pair within reach once over all parts, as (i < j), in batches and in no fixed
    /// order: for sums that do not depend on it (`ExactSum`). The grid and the list hold every
    /// pair of adjacent cells once (`half_shells`); the distance test is the same, and gives the
    /// same answer for (j, i) as for (i, j) (a rounded difference, its image and its square are
    /// odd or even in it), so the pairs are exactly those of `of`.
    pub fn each_unordered(&self, part: Range<usize>, mut f: impl FnMut(&[Near])) {
        let mut pairs = vec![];
        // a few bodies' pairs at a time, so that few groups of lanes are left short
        let mut add = |i: usize, j: usize| {
            pairs.push(Near { i: i.min(j), j: i.max(j) });
            if pairs.len() >= 256 {
                f(&pairs);
                pairs.clear();
            }
        };
        match (self.listed, &self.bins) {
            (Some(l), _) => l.each(part, |i, listed| {
                for run in listed.chunks(RUN) {
                    let mut placed = [[f64::NAN; RUN]; 3];
                    for (k, &j) in run.iter().enumerate() {
                        (0..3).for_each(|a| placed[a][k] = self.x[j as usize][a]);
                    }
                    each_kept(self.passed(i, placed.each_ref()), |k| add(i, run[k] as usize));
                }
            }),
            (None, Some(b)) => self.half_shells(b, part, add),
            (None, None) => self.each(part, |i, js| js.iter().for_each(|&j| add(i, j))),
        }
        f(&pairs);
    }

    /// `f(i, j)` for each body i of the cells `cells` in turn and each body j within reach of
    /// it, after i in its cell or in its cell's half shell (`Grid::half_shell`), below or above
    /// i: over every cell, each pair of adjacent cells is paired once, so each pair within reach
    /// comes once.
    fn half_shells(&self, b: &Bins, cells: Range<usize>, mut f: impl FnMut(usize, usize)) {
        // cell m's bodies and then its half shell's, side by side: one run to test each of m's
        // bodies against, instead of one per neighbouring cell
        let (mut near, mut placed): (Vec<usize>, [Vec<f64>; 3]) = Default::default();
        for m in cells {
            near.clear();
            placed.iter_mut().for_each(Vec::clear);
            b.copy_cell(m, &mut near, &mut placed);
            b.grid.half_shell(m, |n| b.copy_cell(n, &mut near, &mut placed));
            placed.iter_mut().for_each(|p| p.extend([f64::NAN; RUN]));
            for (q, &i) in b.members[b.start[m]..b.start[m + 1]].iter().enumerate() {
                self.test_run(i, &near[q + 1..], placed.each_ref().map(|p| &p[q + 1..]), |j| f(i, j));
            }
        }
    }
}

/// Candidates tested at a time (`Neighbourhood::passed`): one bit each in a `u32`.
const RUN: usize = 32;

/// `f(k)` for each k, in increasing order, whose test passed (bit k of `kept` set): the kept
/// candidates read off the bits, with no branch on a test's outcome to mispredict.
#[inline]
fn each_kept(mut kept: u32, mut f: impl FnMut(usize)) {
    while kept != 0 {
        f(kept.trailing_zeros() as usize);
        kept &= kept - 1;
    }
}

/// What rounding can do to a computed image displacement, from M + L (the largest coordinate
/// and the longest box side). For the image k that `Images::shift` picks (the one the sum then
/// evaluates), each component d − k·L is three roundings (the difference, the shift k·L, the
/// two subtracted), each off by at most 2⁻⁵³ of a value below 2M + L + the
/// component, so within η = 2⁻⁵⁰(M + L + r) of the exact one while that is within a reach r;
/// the distance then within √3·η < 2η, and its square, three roundings more, within a relative
/// 2⁻⁵⁰. The bound a computed squared distance is held to is ((r + 2η)(1 + 2⁻⁴⁸))², the last
/// factor above those 2⁻⁵⁰ and the rounding of the bound itself. Near the box η is some 10⁻¹⁴
/// of a reach; 10¹² boxes from it a naive distance can be off by a ten-thousandth. Binning
/// (a wrap into the box, an offset from the grid's corner) rounds a coordinate by a few
/// 2⁻⁵²(M + L): the grid is used only while that is far below the 1% its cells are wider by.
fn scale(x: &[[f64; 3]], cell: &Option<Cell>) -> f64 {
    let l = cell.map_or(0.0, |c| c.size.iter().fold(0.0f64, |m, l| m.max(*l)));
    x.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs())) + l
}

struct Grid {
    lo: [f64; 3],
    width: f64,
    n: [usize; 3],
    periodic: [bool; 3],
    length: [f64; 3],
}

impl Grid {
    fn new(x: &[[f64; 3]], cell: &Option<Cell>, width: f64) -> Option<Grid> {
        let (periodic, length) = cell.map_or(([false; 3], [0.0; 3]), |c| (c.periodic, c.size));
        let mut g = Grid { lo: [0.0; 3], width, n: [1; 3], periodic, length };
        for a in 0..3 {
            if periodic[a] {
                // cells at least `width` wide that tile the box: floor(L / width) of them
                let k = (length[a] / width).floor();
                if !(k >= 3.0) {
                    return None;
                }
                g.n[a] = k as usize;
            } else {
                let (lo, hi) =
                    x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                let k = ((hi - lo) / width).floor() + 1.0;
                if !(k.is_finite() && k <= 4.0 * x.len() as f64) {
                    return None;
                }
                (g.lo[a], g.n[a]) = (lo, k as usize);
            }
        }
        (g.n.iter().map(|&k| k as f64).product::<f64>() <= 8.0 * x.len() as f64).then_some(g)
    }

    /// The cell of a body: on a periodic axis its wrapped coordinate over the cell width
    /// L / n (≥ width), clamped to the last cell against rounding at the edge.
    fn cell_of(&self, p: &[f64; 3]) -> [usize; 3] {
        std::array::from_fn(|a| {
            let (u, w) = if self.periodic[a] {
                let l = self.length[a];
                (p[a] - l * (p[a] / l).floor(), l / self.n[a] as f64)
            } else {
                (p[a] - self.lo[a], self.width)
            };
            ((u / w).floor().max(0.0) as usize).min(self.n[a] - 1)
        })
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.n[1] + c[1]) * self.n[2] + c[2]
    }

    /// Visits the neighbours of cell m whose offset (dx, dy, dz) comes after (0, 0, 0) in
    /// lexicographic order, each once: of two adjacent cells, exactly one is in the other's
    /// half shell (n ≥ 3 on periodic axes makes the offset from one to the other unique, and
    /// the offsets of a half shell hold one of each pair d, −d).
    fn half_shell(&self, m: usize, mut visit: impl FnMut(usize)) {
        let c = [m / (self.n[1] * self.n[2]), m / self.n[2] % self.n[1], m % self.n[2]];
        let step = |a: usize, d: isize| {
            let (k, n) = (c[a] as isize + d, self.n[a] as isize);
            match (0..n).contains(&k) {
                true => Some(k as usize),
                false => self.periodic[a].then_some(k.rem_euclid(n) as usize),
            }
        };
        for d in (-1..=1).flat_map(|x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| [x, y, z]))) {
            if d > [0, 0, 0] {
                if let (Some(i), Some(j), Some(k)) = (step(0, d[0]), step(1, d[1]), step(2, d[2])) {
                    visit(self.index([i, j, k]));
                }
            }
        }
    }

    /// Visits the cell and its neighbours, each once (n ≥ 3 on periodic axes keeps them
    /// distinct).
    fn around(&self, c: [usize; 3], mut visit: impl FnMut(usize)) {
        let axis = |a: usize| {
            let (k, n, periodic) = (c[a], self.n[a], self.periodic[a]);
            // on a periodic axis the neighbours wrap around (compared, not divided: this is hot)
            let (below, above) = (k.checked_sub(1), Some(k + 1).filter(|&v| v < n));
            [below.or(periodic.then(|| n - 1)), Some(k), above.or(periodic.then_some(0))].into_iter().flatten()
        };
        for i in axis(0) {
            for j in axis(1) {
                for k in axis(2) {
                    visit(self.index([i, j, k]));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::foreseen::SKIN;
    use super::*;
    use proptest::prelude::*;

    /// Every pair of the double loop whose nearest image is within `reach`.
    fn double_loop(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<Near> {
        let n = x.len();
        let mut out = vec![];
        for i in 0..n {
            for j in i + 1..n {
                let d = std::array::from_fn(|a| x[j][a] - x[i][a]);
                let e = Cell::image(cell, d);
                if e[0] * e[0] + e[1] * e[1] + e[2] * e[2] <= reach * reach {
                    out.push(Near { i, j });
                }
            }
        }
        out
    }

    /// The pairs `each_unordered` lists over every part, split at `cut`, sorted.
    fn unordered(near: &Neighbourhood, cut: usize) -> Vec<Near> {
        let mut all = vec![];
        let split = cut.min(near.parts());
        near.each_unordered(split..near.parts(), |p| all.extend_from_slice(p));
        near.each_unordered(0..split, |p| all.extend_from_slice(p));
        all.sort_by_key(|p| (p.i, p.j));
        all
    }

    /// Whether sorted `a` is within sorted `b`.
    fn within_list(a: &[Near], b: &[Near]) -> bool {
        let mut b = b.iter();
        a.iter().all(|p| b.any(|q| q == p))
    }

    proptest! {
        /// The grid finds the pairs within reach that the double loop finds, in its order, and
        /// no others but those within the reach's rounding slack — bodies drifted out of the
        /// box, on box edges, open or periodic axes.
        #[test]
        fn the_grid_finds_the_pairs_of_the_double_loop(
            pts in prop::collection::vec(prop::array::uniform3(-30.0f64..60.0), 64..400),
            side in 6.0f64..20.0, periodic in prop::array::uniform3(any::<bool>()), boxed in any::<bool>(), reach in 0.5f64..3.0,
            on_edge in 0usize..64, cut in 0usize..400,
        ) {
            let mut x = pts;
            x[on_edge] = [side, 0.0, -side]; // exactly on cell and box boundaries
            let cell = boxed.then_some(Cell { size: [side; 3], periodic });
            let found = within(&x, &cell, Some(reach));
            prop_assert!(found.windows(2).all(|w| (w[0].i, w[0].j) < (w[1].i, w[1].j)));
            prop_assert!(within_list(&double_loop(&x, &cell, reach), &found));
            prop_assert!(within_list(&found, &double_loop(&x, &cell, reach * (1.0 + 1e-12))));
            // and any run of bodies gets its own pairs
            let near = Neighbourhood::new(&x, &cell, Some(reach), &[]);
            let (a, b) = (cut.min(x.len()), (cut + 17).min(x.len()));
            let run: Vec<Near> = found.iter().copied().filter(|p| (a..b).contains(&p.i)).collect();
            prop_assert_eq!(near.of(a..b), run);
            // and the pairs listed in no order, cell by cell, in any split into parts, are the same
            prop_assert_eq!(unordered(&near, cut), found);
        }
    }

    /// Bodies 10¹¹ boxes apart: their difference rounds by up to 6·10⁻⁵, which a pair at the
    /// edge of its reach must not be dropped for. The reach of each pair is its exact nearest
    /// image's distance (MPFR, no rounding), rounded up; a naive binary64 test drops a quarter of them.
    #[test]
    fn far_out_pairs_at_the_edge_of_reach_are_kept() {
        use rug::{float::Round, Float};
        let cell = Some(Cell { size: [10.0; 3], periodic: [true; 3] });
        let xi = [5e11 + 0.3, 0.0, 0.0];
        let mut xj: [f64; 3] = [-5e11 + 1.1, 0.25, 0.0];
        let mut naive = 0;
        for _ in 0..400 {
            xj[0] = xj[0].next_up();
            // xj − xi + 10¹¹·10, exactly, then its length, rounded up
            let e = Float::with_val(300, xj[0]) - Float::with_val(300, xi[0]) + Float::with_val(300, 1e12);
            let d = (e.square() + Float::with_val(300, xj[1]).square()).sqrt();
            let reach = d.to_f64_round(Round::Up);
            assert!(reach < 2.0);
            assert_eq!(within(&[xi, xj], &cell, Some(reach)), [Near { i: 0, j: 1 }], "{xj:?}");
            naive += usize::from(double_loop(&[xi, xj], &cell, reach).is_empty());
        }
        assert!(naive >= 50, "the naive test dropped {naive} of 400: the case does not bite");
    }

    proptest! {
        /// A list made ahead, from bodies that then moved by up to 0.4 of the skin, holds: it
        /// is used, and gives the grid's pairs, in any split into parts — bodies crossing the
        /// box's faces (wrapped back in) included; asked for pairs in order, the grid is built.
        /// A body moved by 0.6 of the skin makes it unused.
        #[test]
        fn a_list_made_ahead_gives_the_pairs_of_the_grid(
            pts in prop::collection::vec(prop::array::uniform3(0.0f64..12.0), 64..400),
            moves in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 400),
            reach in 1.2f64..2.0, wrap in any::<bool>(), far in 0usize..64, threads in 1usize..4,
        ) {
            let side = 12.0;
            let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
            let most = 0.4 * SKIN * reach / 3f64.sqrt();
            let moved = |scale: f64| -> Vec<[f64; 3]> {
                pts.iter().zip(&moves).map(|(p, d)| {
                    let q: [f64; 3] = std::array::from_fn(|a| p[a] + d[a] * scale);
                    if wrap { q.map(|c| c.rem_euclid(side)) } else { q }
                }).collect()
            };
            let ahead = [Foreseen::new(&pts, &cell, reach, threads).expect("a grid")];
            let later = moved(most);
            let near = Neighbourhood::new(&later, &cell, Some(reach), &ahead);
            prop_assert!(near.listed.is_some());
            prop_assert_eq!(unordered(&near, far * 5), within(&later, &cell, Some(reach)));
            let run = far..(far + 30).min(later.len());
            prop_assert_eq!(near.of(run.clone()), Neighbourhood::new(&later, &cell, Some(reach), &[]).of(run));
            // sorted pairs come from a grid built for the first run asked for, and kept
            let grid = near.gridded.get().map(|g| &**g as *const Neighbourhood);
            prop_assert!(grid.is_some());
            prop_assert_eq!(near.of(0..later.len()), within(&later, &cell, Some(reach)));
            prop_assert_eq!(near.gridded.get().map(|g| &**g as *const Neighbourhood), grid);
            // one body moved too far: the list is not used, the grid is
            let mut strayed = later.clone();
            strayed[far][0] = pts[far][0] + 0.6 * SKIN * reach;
            let near = Neighbourhood::new(&strayed, &cell, Some(reach), &ahead);
            prop_assert!(near.listed.is_none());
            prop_assert_eq!(unordered(&near, far), within(&strayed, &cell, Some(reach)));
            // nor for another reach
            prop_assert!(Neighbourhood::new(&later, &cell, Some(reach * 1.01), &ahead).listed.is_none());
        }

        /// The bits of a run's tests pick out the candidates that passed, in order.
        #[test]
        fn kept_candidates_are_read_off_their_bits(passed in prop::collection::vec(any::<bool>(), 0..=32)) {
            let run: Vec<usize> = (0..passed.len()).map(|k| 1000 + 7 * k).collect();
            let kept = passed.iter().enumerate().fold(0, |bits, (k, &p)| bits | u32::from(p) << k);
            let mut js = vec![5];
            each_kept(kept, |k| js.push(run[k]));
            let want: Vec<usize> = std::iter::once(5).chain(run.iter().zip(&passed).filter(|(_, &p)| p).map(|(&j, _)| j)).collect();
            prop_assert_eq!(js, want);
        }
    }

    #[test]
    fn unbounded_reach_is_every_pair() {
        let x: Vec<[f64; 3]> = (0..100).map(|i| [i as f64, 0.0, 0.0]).collect();
        assert_eq!(within(&x, &None, None).len(), 4950);
        assert_eq!(within(&x, &None, Some(1.0)).len(), 99);
    }
}
