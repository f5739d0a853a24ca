//! The broad phase: which solids' bounding balls (grown by the margin) meet. The solids are
//! binned into cells at least a widest ball's diameter across, so a pair's two cells touch; the
//! cells grow so that there are at most about four a solid (a far outlier makes them large:
//! slower, never wrong). A sweep along one axis, as before, met a hundred candidates a block on
//! the 1,000-block stack (ten towers stand at each x), a quarter of a step at five sweeps.

use super::Pose;
use nalgebra::Vector3;

type V = Vector3<f64>;

/// The solids, each an index and the radius of its ball, binned by centre: the solids of cell
/// c are `held[first[c]..first[c + 1]]` (a counting sort).
pub(super) struct Grid<'a> {
    poses: &'a [Pose],
    lo: V,
    cell: f64,
    dims: Vector3<usize>,
    first: Vec<usize>,
    held: Vec<(usize, f64)>,
}

impl<'a> Grid<'a> {
    pub fn of(solids: &[(usize, f64)], poses: &'a [Pose]) -> Grid<'a> {
        let (mut lo, mut hi) = (V::repeat(f64::INFINITY), V::repeat(f64::NEG_INFINITY));
        for &(i, _) in solids {
            (lo, hi) = (lo.inf(&poses[i].centre), hi.sup(&poses[i].centre));
        }
        let widest = 2.0 * solids.iter().map(|s| s.1).fold(0.0, f64::max);
        let span = (hi - lo).map(|s| s.max(widest));
        let mut cell = widest.max((span.x * span.y * span.z / (4.0 * solids.len().max(1) as f64)).cbrt());
        // a non-finite centre or span lands in cell 0 (float-to-int casts saturate); a box flat
        // along an axis, or solids of no size, widen the cells until they are few enough
        let cells = |cell: f64| span.map(|s| ((s / cell) as usize).min(1 << 20) + 1);
        while cells(cell).iter().fold(1usize, |n, d| n.saturating_mul(*d)) > 8 * solids.len() + 8 {
            cell = if cell > 0.0 { 2.0 * cell } else { f64::MIN_POSITIVE };
        }
        let mut grid = Grid { poses, lo, cell, dims: cells(cell), first: vec![], held: vec![(0, 0.0); solids.len()] };
        grid.first = vec![0; grid.dims.product() + 1];
        for &(i, _) in solids {
            let c = grid.flat(grid.at(i));
            grid.first[c + 1] += 1;
        }
        for c in 1..grid.first.len() {
            grid.first[c] += grid.first[c - 1];
        }
        let mut fill = grid.first.clone();
        for &(i, r) in solids {
            let c = grid.flat(grid.at(i));
            grid.held[fill[c]] = (i, r);
            fill[c] += 1;
        }
        grid
    }

    /// The solids numbered after `i` (of ball radius `r`) whose balls meet its, in order, in
    /// `found` (emptied first: a search reuses one list).
    pub fn after<'f>(&self, i: usize, r: f64, found: &'f mut Vec<usize>) -> &'f [usize] {
        found.clear();
        let k = self.at(i);
        let around = |k: usize, d: usize| k.saturating_sub(1)..(k + 2).min(d);
        for x in around(k[0], self.dims.x) {
            for y in around(k[1], self.dims.y) {
                for z in around(k[2], self.dims.z) {
                    let c = self.flat([x, y, z]);
                    for &(j, rj) in self.held[self.first[c]..self.first[c + 1]].iter().filter(|h| h.0 > i) {
                        let d = self.poses[j].centre - self.poses[i].centre;
                        if d.iter().all(|c| c.abs() <= r + rj) && d.norm() <= r + rj {
                            found.push(j);
                        }
                    }
                }
            }
        }
        found.sort_unstable();
        found
    }

    /// Solid i's cell.
    fn at(&self, i: usize) -> [usize; 3] {
        let k = ((self.poses[i].centre - self.lo) / self.cell).map(|x| x as usize);
        [k.x.min(self.dims.x - 1), k.y.min(self.dims.y - 1), k.z.min(self.dims.z - 1)]
    }

    fn flat(&self, k: [usize; 3]) -> usize {
        (k[0] * self.dims.y + k[1]) * self.dims.z + k[2]
    }
}
