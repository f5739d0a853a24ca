//! Which pairs a pair term visits: every pair, or, for a term of finite reach on enough bodies,
//! the pairs in the same or nearby cells of a cell list (cells half the reach wide where the box
//! allows, each pair once: Newton's third law). Bodies are binned by counting sort, so
//! the order of visits depends on the positions alone, never on threads.

use lagra_checker::model::{Cell, Images};
use std::ops::Range;

/// Below this many bodies the plain double loop is as fast.
const CELL_LIST_FROM: usize = 64;

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Calls `visit(i, j, d)` with d the minimum-image displacement xⱼ − xᵢ, for every pair that can
/// be within `reach` (all pairs if `reach` is `None`).
pub fn pairs<E>(
    x: &[[f64; 3]],
    cell: &Option<Cell>,
    reach: Option<f64>,
    mut visit: impl FnMut(usize, usize, [f64; 3]) -> Result<(), E>,
) -> Result<(), E> {
    let Some(binned) = reach.and_then(|r| Binned::new(x, cell, r)) else {
        let images = Images::of(cell);
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                visit(i, j, images.image(sub(&x[j], &x[i])))?;
            }
        }
        return Ok(());
    };
    pairs_in(x, cell, &binned, 0..binned.cells(), visit)
}

/// `pairs` for the bodies of `binned`'s cells `cells` (`Binned::each_in`): over consecutive
/// ranges of cells that cover them all, each pair once, in the order `pairs` visits them.
pub fn pairs_in<E>(
    x: &[[f64; 3]],
    cell: &Option<Cell>,
    binned: &Binned,
    cells: Range<usize>,
    mut visit: impl FnMut(usize, usize, [f64; 3]) -> Result<(), E>,
) -> Result<(), E> {
    let (images, order) = (Images::of(cell), &binned.order);
    let mut result = Ok(());
    binned.each_in(cells, |b, runs| {
        let i = order[b];
        for (run, _) in runs {
            for &j in &order[run.clone()] {
                if result.is_ok() {
                    result = visit(i, j, images.image(sub(&x[j], &x[i])));
                }
            }
        }
    });
    result
}

/// Bodies binned into a grid of cells (`Grid::fine`) by counting sort: `order[b]` is the body at
/// position b of the cell order.
pub struct Binned {
    pub order: Vec<usize>,
    /// Where each cell's run of positions starts.
    start: Vec<usize>,
    grid: Grid,
}

impl Binned {
    /// `None` if no grid fits (too few bodies, too few cells along a periodic axis, bodies
    /// scattered far apart): then every pair is the way.
    pub fn new(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Option<Binned> {
        // the count first: for a few bodies the grid (its stencil) would cost more than the pairs
        if x.len() < CELL_LIST_FROM {
            return None;
        }
        let grid = Grid::fine(x, cell, reach)?;
        let (order, start) = grid.bin(x);
        Some(Binned { order, start, grid })
    }

    pub fn cells(&self) -> usize {
        self.grid.cells()
    }

    /// The cells cut into `parts` consecutive ranges holding about as many bodies each.
    pub fn split(&self, parts: usize) -> Vec<Range<usize>> {
        let (cells, n) = (self.grid.cells(), self.order.len());
        let bound =
            |k: usize| if k == parts { cells } else { self.start.partition_point(|&b| b < n * k / parts).min(cells) };
        (0..parts).map(|k| bound(k)..bound(k + 1)).collect()
    }

    /// Calls `visit(b, runs)` for every position b of the cells `cells` in cell order, with the
    /// runs of positions whose bodies it pairs with (each pair once over all the cells): in its
    /// own cell the ones after it, in the stencil's cells ahead of its cell all of them. Each run
    /// carries its `image` (0..27, axis x least significant, digit 0/1/2 for −L/0/+L): for bodies
    /// wrapped into the box, the box shift to add to xⱼ − xᵢ, so that no division or rounding is
    /// needed per pair.
    pub fn each_in(&self, cells: Range<usize>, mut visit: impl FnMut(usize, &[(Range<usize>, u8)])) {
        let mut runs: Vec<(Range<usize>, u8)> = Vec::with_capacity(self.grid.stencil.len() + 1);
        let mut shell = Vec::with_capacity(self.grid.stencil.len());
        for c in cells {
            self.grid.half_shell(c, &mut shell);
            let end = self.start[c + 1];
            for b in self.start[c]..end {
                runs.clear();
                runs.push((b + 1..end, 13));
                runs.extend(shell.iter().map(|&(n, image)| (self.start[n]..self.start[n + 1], image)));
                visit(b, &runs);
            }
        }
    }
}

/// A grid of cells at least reach/`per` wide over the bodies (over the box along periodic axes):
/// a body's partners lie within `per` cells of its own.
struct Grid {
    lo: [f64; 3],
    size: [f64; 3],
    n: [usize; 3],
    periodic: [bool; 3],
    length: [f64; 3],
    /// The half stencil: the neighbour offsets ahead of a cell (d > 0 in lexicographic order)
    /// whose cells can hold a body within reach of one in the cell.
    stencil: Vec<[i64; 3]>,
}

impl Grid {
    /// Cells reach/2 wide where every periodic axis has at least five of them (a body then meets
    /// about 40% fewer candidates than with cells the reach wide), else reach wide.
    fn fine(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Option<Grid> {
        Grid::new(x, cell, reach, 2).or_else(|| Grid::new(x, cell, reach, 1))
    }

    /// `None` where a cell list would not help or would repeat a pair: fewer than 2·per + 1
    /// cells along a periodic axis, or far more cells than bodies (bodies scattered very far
    /// apart).
    fn new(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64, per: usize) -> Option<Grid> {
        let (periodic, length) = cell.map_or(([false; 3], [0.0; 3]), |c| (c.periodic, c.size));
        let mut g = Grid { lo: [0.0; 3], size: [0.0; 3], n: [1; 3], periodic, length, stencil: vec![] };
        let width = reach / per as f64;
        for a in 0..3 {
            let (lo, extent) = if periodic[a] {
                (0.0, length[a])
            } else {
                let (lo, hi) =
                    x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                (lo, hi - lo)
            };
            let cells = (extent / width).floor();
            if !(cells.is_finite() && width > 0.0)
                || (periodic[a] && cells < (2 * per + 1) as f64)
                || cells > 4.0 * x.len() as f64
            {
                return None;
            }
            g.n[a] = (cells as usize).max(1);
            (g.lo[a], g.size[a]) = (lo, if cells >= 1.0 { extent / cells } else { extent.max(width) });
        }
        // Offsets whose cells cannot hold a pair within reach are left out, with a margin far
        // above the rounding of the binning.
        let p = per as i64;
        for d in (-p..=p).flat_map(|x| (-p..=p).flat_map(move |y| (-p..=p).map(move |z| [x, y, z]))) {
            let gap: f64 = (0..3).map(|a| ((d[a].abs() - 1).max(0) as f64 * g.size[a]).powi(2)).sum();
            if d > [0, 0, 0] && gap < reach * reach * (1.0 - 1e-9) {
                g.stencil.push(d);
            }
        }
        (g.n.iter().product::<usize>() <= 4 * x.len()).then_some(g)
    }

    fn cells(&self) -> usize {
        self.n.iter().product()
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.n[1] + c[1]) * self.n[2] + c[2]
    }

    fn cell_of(&self, p: &[f64; 3]) -> usize {
        let c: [usize; 3] = std::array::from_fn(|a| {
            let u = if self.periodic[a] { p[a] - self.length[a] * (p[a] / self.length[a]).floor() } else { p[a] };
            (((u - self.lo[a]) / self.size[a]).floor().max(0.0) as usize).min(self.n[a] - 1)
        });
        self.index(c)
    }

    /// Bodies sorted by cell (counting sort), and where each cell's run starts.
    fn bin(&self, x: &[[f64; 3]]) -> (Vec<usize>, Vec<usize>) {
        let of: Vec<usize> = x.iter().map(|p| self.cell_of(p)).collect();
        let mut start = vec![0; self.cells() + 1];
        for &c in &of {
            start[c + 1] += 1;
        }
        for c in 0..self.cells() {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut order = vec![0; x.len()];
        for (i, &c) in of.iter().enumerate() {
            order[next[c]] = i;
            next[c] += 1;
        }
        (order, start)
    }

    /// The stencil's cells around cell `c` that exist (none beyond a closed edge), each with the
    /// image index of the box shift its wrap implies (at most one box length: the grid has at
    /// least 2·per + 1 cells along a periodic axis).
    fn half_shell(&self, c: usize, out: &mut Vec<(usize, u8)>) {
        let at = [c / (self.n[1] * self.n[2]), (c / self.n[2]) % self.n[1], c % self.n[2]];
        out.clear();
        'offsets: for d in &self.stencil {
            let mut m = [0usize; 3];
            let mut image = 0u8;
            for a in (0..3).rev() {
                let v = at[a] as i64 + d[a];
                let n = self.n[a] as i64;
                // past the last cell the neighbour is the first one, one box length on (|d| ≤ per
                // and n ≥ 2·per + 1 on a periodic axis: one wrap at most, no division needed)
                let (wrapped, digit) = if v < 0 {
                    (v + n, 0)
                } else if v >= n {
                    (v - n, 2)
                } else {
                    (v, 1)
                };
                if digit != 1 && !self.periodic[a] {
                    continue 'offsets;
                }
                image = 3 * image + digit;
                m[a] = wrapped as usize;
            }
            out.push((self.index(m), image));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::dual::Rng;
    use proptest::prelude::*;

    /// The pairs within `reach`, each as (min, max, d·d), found by a traversal.
    fn near(x: &[[f64; 3]], cell: &Option<Cell>, reach: Option<f64>, r: f64) -> Vec<(usize, usize, u64)> {
        let mut found = vec![];
        pairs::<()>(x, cell, reach, |i, j, d| {
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            if d2 < r * r {
                found.push((i.min(j), i.max(j), d2.to_bits()));
            }
            Ok(())
        })
        .unwrap();
        found.sort();
        found
    }

    proptest! {
        /// The cell list finds exactly the pairs within reach that the double loop finds, with
        /// the same minimum-image displacement, in periodic and in open space.
        #[test]
        fn the_cell_list_misses_no_pair(seed in any::<u64>(), n in 64usize..400, side in 6.0f64..20.0, periodic in any::<bool>(), reach in 1.0f64..2.0) {
            let mut rng = Rng::new(seed);
            let x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-side, 2.0 * side))).collect();
            let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, true, rng.uniform(0.0, 1.0) < 0.5] });
            prop_assert_eq!(near(&x, &cell, Some(reach), reach), near(&x, &cell, None, reach));
        }
    }

    #[test]
    fn scattered_bodies_fall_back_to_every_pair() {
        let x: Vec<[f64; 3]> = (0..100).map(|i| [i as f64 * 1e300, 0.0, f64::from(i % 3)]).collect();
        assert!(Grid::fine(&x, &None, 1.0).is_none());
    }
}
