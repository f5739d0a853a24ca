//! Which pairs of bodies a pair term must look at: every pair whose nearest-image distance could
//! be within its reach. A superset is sound (a pair beyond reach then contributes exactly zero
//! through the exact test that follows); a missed pair is not, so the argument is kept simple:
//! bodies are binned into cells wider than the reach by 1% — far more than any rounding in the
//! binning — and two bodies whose cells are not adjacent (cyclically, on a periodic axis) are
//! farther apart than the reach. Where no such grid fits (few bodies, a periodic axis shorter
//! than three cells, bodies scattered so far that cells would outnumber them) every pair is a
//! candidate. The candidates come out sorted, in the order of the double loop over every pair,
//! so the sums built from them do not depend on the grid.

use crate::model::Cell;

/// Below this many bodies the double loop is as cheap as the grid.
const GRID_FROM: usize = 64;

/// The pairs (i < j), sorted, that can be within `reach` of each other (`None`: unbounded) and
/// that `keep` keeps (filtered before they are sorted, which is most of the cost).
pub fn candidates(
    x: &[[f64; 3]],
    cell: &Option<Cell>,
    reach: Option<f64>,
    keep: impl Fn(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    let n = x.len();
    let every = || (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).filter(|&(i, j)| keep(i, j)).collect();
    let Some(reach) = reach.filter(|r| *r > 0.0 && r.is_finite() && n >= GRID_FROM) else { return every() };
    let Some(grid) = Grid::new(x, cell, reach * 1.01) else { return every() };
    let cells: Vec<[usize; 3]> = x.iter().map(|p| grid.cell_of(p)).collect();
    let mut members: Vec<Vec<usize>> = vec![vec![]; grid.n.iter().product()];
    for (i, c) in cells.iter().enumerate() {
        members[grid.index(*c)].push(i);
    }
    let mut pairs = vec![];
    for (i, c) in cells.iter().enumerate() {
        let from = pairs.len();
        for m in grid.around(*c) {
            pairs.extend(members[m].iter().filter(|&&j| j > i && keep(i, j)).map(|&j| (i, j)));
        }
        pairs[from..].sort_unstable();
    }
    pairs
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

    /// The cell and its neighbours, each once (n ≥ 3 on periodic axes keeps them distinct).
    fn around(&self, c: [usize; 3]) -> Vec<usize> {
        let mut out = Vec::with_capacity(27);
        let axis = |a: usize| -> Vec<usize> {
            let (k, n) = (c[a] as i64, self.n[a] as i64);
            (k - 1..=k + 1)
                .filter_map(|v| if self.periodic[a] { Some(v.rem_euclid(n)) } else { (0..n).contains(&v).then_some(v) })
                .map(|v| v as usize)
                .collect()
        };
        for i in axis(0) {
            for j in axis(1) {
                for k in axis(2) {
                    out.push(self.index([i, j, k]));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The pairs the double loop keeps within `reach` by the exact nearest-image test.
    fn within(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64, pairs: &[(usize, usize)]) -> Vec<(usize, usize)> {
        pairs
            .iter()
            .copied()
            .filter(|&(i, j)| {
                let d = Cell::image(cell, std::array::from_fn(|a| x[j][a] - x[i][a]));
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= reach * reach
            })
            .collect()
    }

    proptest! {
        /// The grid's candidates hold every pair within reach that the double loop finds, in
        /// order — bodies drifted out of the box, on box edges, open or periodic axes.
        #[test]
        fn no_pair_within_reach_is_missed(
            pts in prop::collection::vec(prop::array::uniform3(-30.0f64..60.0), 64..400),
            side in 6.0f64..20.0, periodic in prop::array::uniform3(any::<bool>()), boxed in any::<bool>(), reach in 0.5f64..3.0,
            on_edge in 0usize..64,
        ) {
            let mut x = pts;
            x[on_edge] = [side, 0.0, -side]; // exactly on cell and box boundaries
            let cell = boxed.then_some(Cell { size: [side; 3], periodic });
            let n = x.len();
            let all: Vec<(usize, usize)> = (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).collect();
            let got = candidates(&x, &cell, Some(reach), |_, _| true);
            prop_assert!(got.windows(2).all(|w| w[0] < w[1]), "sorted, no repeats");
            prop_assert_eq!(within(&x, &cell, reach, &got), within(&x, &cell, reach, &all));
        }
    }

    #[test]
    fn a_dense_periodic_box_prunes_most_pairs() {
        let x: Vec<[f64; 3]> = (0..1000).map(|i| [(i % 10) as f64, ((i / 10) % 10) as f64, (i / 100) as f64]).collect();
        let cell = Some(Cell { size: [10.0; 3], periodic: [true; 3] });
        // 6 cells of 1.67 per axis, 4.6 bodies a cell: 1000 · 27 · 4.6 / 2 ≈ 62,500 candidates
        let got = candidates(&x, &cell, Some(1.5), |_, _| true);
        assert!(got.len() <= 62_500, "{} of 499,500", got.len());
        assert_eq!(candidates(&x, &cell, None, |_, _| true).len(), 499_500);
        assert_eq!(candidates(&x, &cell, None, |i, j| i + 1 == j).len(), 999, "kept before sorting");
    }
}
