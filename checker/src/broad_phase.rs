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

use crate::model::{Cell, Images};
use std::ops::Range;

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
    Neighbourhood::new(x, cell, reach).of(0..x.len())
}

/// The bodies binned once, to list the pairs within reach of any run of bodies.
pub struct Neighbourhood<'a> {
    x: &'a [[f64; 3]],
    images: Images,
    /// The reach squared (∞: unbounded).
    limit: f64,
    bins: Option<Bins>,
}

/// The grid, each body's cell, and the bodies by cell (cell m's are `members[start[m]..start[m
/// + 1]]`, in increasing order, at `placed[start[m]..start[m + 1]]`: a cell's positions sit
/// together).
struct Bins {
    grid: Grid,
    cells: Vec<[usize; 3]>,
    start: Vec<usize>,
    members: Vec<usize>,
    placed: Vec<[f64; 3]>,
}

impl<'a> Neighbourhood<'a> {
    pub fn new(x: &'a [[f64; 3]], cell: &'a Option<Cell>, reach: Option<f64>) -> Self {
        // the rounding slack and the grid's bound on it (`scale`)
        let size = scale(x, cell);
        let limit =
            reach.map_or(f64::INFINITY, |r| ((r + (size + r) * 2f64.powi(-49)) * (1.0 + 2f64.powi(-48))).powi(2));
        let grid = reach
            .filter(|r| *r > 0.0 && r.is_finite() && x.len() >= GRID_FROM && size * 2f64.powi(-40) < 1e-3 * r)
            .and_then(|r| Grid::new(x, cell, r * 1.01));
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
            let placed = members.iter().map(|&i| x[i]).collect();
            Bins { grid, cells, start, members, placed }
        });
        Neighbourhood { x, images: Images::of(cell), limit, bins }
    }

    /// Whether `xj`, body j's position, has its nearest image within reach of body i.
    #[inline]
    fn near(&self, i: usize, xj: &[f64; 3]) -> bool {
        let e = self.images.image(std::array::from_fn(|a| xj[a] - self.x[i][a]));
        e[0] * e[0] + e[1] * e[1] + e[2] * e[2] <= self.limit
    }

    /// The pairs (i, j > i) within reach for i in `bodies`, sorted.
    pub fn of(&self, bodies: Range<usize>) -> Vec<Near> {
        let n = self.x.len();
        let Some(b) = &self.bins else {
            let near = |&(i, j): &(usize, usize)| self.near(i, &self.x[j]);
            return bodies
                .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
                .filter(near)
                .map(|(i, j)| Near { i, j })
                .collect();
        };
        // every candidate is written and kept by advancing the end: no branch to mispredict
        let (mut pairs, mut end) = (vec![], 0);
        for i in bodies {
            let from = end;
            b.grid.around(b.cells[i], |m| {
                let (lo, hi) = (b.start[m], b.start[m + 1]);
                // the cell's bodies after i (in increasing order): mostly all or none of them
                let cell = &b.members[lo..hi];
                let after = match (cell.first(), cell.last()) {
                    (Some(&first), _) if first > i => lo,
                    (_, Some(&last)) if last > i => lo + cell.partition_point(|&j| j <= i),
                    _ => return,
                };
                if pairs.len() < end + (hi - after) {
                    pairs.resize(2 * pairs.len() + hi - after, Near { i: 0, j: 0 });
                }
                // the tests first, then the compaction: were each write's place to wait for the
                // test before, every candidate would wait for the last one's whole distance
                for (js, xs) in b.members[after..hi].chunks(32).zip(b.placed[after..hi].chunks(32)) {
                    let mut keep = [false; 32];
                    for (k, xj) in keep.iter_mut().zip(xs) {
                        *k = self.near(i, xj);
                    }
                    for (&j, &k) in js.iter().zip(&keep) {
                        pairs[end] = Near { i, j };
                        end += usize::from(k);
                    }
                }
            });
            pairs[from..end].sort_unstable_by_key(|p: &Near| p.j);
        }
        pairs.truncate(end);
        pairs
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
            let near = Neighbourhood::new(&x, &cell, Some(reach));
            let (a, b) = (cut.min(x.len()), (cut + 17).min(x.len()));
            let run: Vec<Near> = found.iter().copied().filter(|p| (a..b).contains(&p.i)).collect();
            prop_assert_eq!(near.of(a..b), run);
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

    #[test]
    fn unbounded_reach_is_every_pair() {
        let x: Vec<[f64; 3]> = (0..100).map(|i| [i as f64, 0.0, 0.0]).collect();
        assert_eq!(within(&x, &None, None).len(), 4950);
        assert_eq!(within(&x, &None, Some(1.0)).len(), 99);
    }
}
