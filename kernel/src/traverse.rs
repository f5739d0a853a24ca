//! Which pairs a pair term visits: every pair, or, for a term of finite reach on enough bodies,
//! the pairs in the same or neighbouring cells of a cell list (cells at least the reach wide,
//! rebuilt every step, each pair once: Newton's third law). Bodies are binned by counting sort, so
//! the order of visits depends on the positions alone, never on threads.

use lagra_checker::model::Cell;

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
    let grid = reach.filter(|_| x.len() >= CELL_LIST_FROM).and_then(|r| Grid::new(x, cell, r));
    let Some(grid) = grid else {
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                visit(i, j, Cell::image(cell, sub(&x[j], &x[i])))?;
            }
        }
        return Ok(());
    };
    grid.each_pair(x, |i, j, _| visit(i, j, Cell::image(cell, sub(&x[j], &x[i]))))
}

/// For bodies already wrapped into the box (`[0, L]` along periodic axes): calls
/// `visit(i, j, image)` for every pair in the same or adjacent cells of a grid at least `reach`
/// wide, where `image` (0..27, axis x least significant, digit 0/1/2 for −L/0/+L) is the box
/// shift to add to xⱼ − xᵢ. No division or rounding per pair: the shift is the neighbour cell's
/// wrap. `false` if no grid fits (too few bodies or cells).
pub fn binned(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64, mut visit: impl FnMut(usize, usize, u8)) -> bool {
    let Some(grid) = Grid::new(x, cell, reach).filter(|_| x.len() >= CELL_LIST_FROM) else { return false };
    grid.each_pair::<std::convert::Infallible>(x, |i, j, image| {
        visit(i, j, image);
        Ok(())
    })
    .is_ok()
}

/// A grid of cells at least `reach` wide over the bodies (over the box along periodic axes).
struct Grid {
    lo: [f64; 3],
    size: [f64; 3],
    n: [usize; 3],
    periodic: [bool; 3],
    length: [f64; 3],
}

impl Grid {
    /// `None` where a cell list would not help or would repeat a pair: fewer than three cells
    /// along a periodic axis, or far more cells than bodies (bodies scattered very far apart).
    fn new(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Option<Grid> {
        let (periodic, length) = cell.map_or(([false; 3], [0.0; 3]), |c| (c.periodic, c.size));
        let mut g = Grid { lo: [0.0; 3], size: [0.0; 3], n: [1; 3], periodic, length };
        for a in 0..3 {
            let (lo, extent) = if periodic[a] {
                (0.0, length[a])
            } else {
                let (lo, hi) =
                    x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                (lo, hi - lo)
            };
            let cells = (extent / reach).floor();
            if !(cells.is_finite() && reach > 0.0) || (periodic[a] && cells < 3.0) || cells > 4.0 * x.len() as f64 {
                return None;
            }
            g.n[a] = (cells as usize).max(1);
            (g.lo[a], g.size[a]) = (lo, if cells >= 1.0 { extent / cells } else { extent.max(reach) });
        }
        (g.n.iter().product::<usize>() <= 4 * x.len()).then_some(g)
    }

    /// Each pair in the same or adjacent cells once, with the image index of its cell's wrap.
    fn each_pair<E>(&self, x: &[[f64; 3]], mut visit: impl FnMut(usize, usize, u8) -> Result<(), E>) -> Result<(), E> {
        let (order, start) = self.bin(x);
        let members = |c: usize| &order[start[c]..start[c + 1]];
        for c in 0..self.cells() {
            for (k, n) in self.half_shell(c).into_iter().enumerate() {
                let Some((n, image)) = n else { continue };
                for (a, &i) in members(c).iter().enumerate() {
                    // in its own cell a body pairs with the ones after it; elsewhere with all
                    let others = if k == 0 { &members(c)[a + 1..] } else { members(n) };
                    for &j in others {
                        visit(i, j, image)?;
                    }
                }
            }
        }
        Ok(())
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

    /// The cell itself, then its 13 neighbours ahead of it (None beyond a closed edge), each
    /// with the image index of the box shift its wrap implies.
    fn half_shell(&self, c: usize) -> [Option<(usize, u8)>; 14] {
        let at = [c / (self.n[1] * self.n[2]), (c / self.n[2]) % self.n[1], c % self.n[2]];
        let mut out = [None; 14];
        out[0] = Some((c, 13));
        let mut k = 1;
        for d in [-1i64, 0, 1]
            .iter()
            .flat_map(|&x| [-1i64, 0, 1].map(move |y| (x, y)))
            .flat_map(|(x, y)| [-1i64, 0, 1].map(move |z| [x, y, z]))
        {
            if d <= [0, 0, 0] {
                continue;
            }
            let mut m = [0usize; 3];
            let mut inside = true;
            let mut image = 0u8;
            for a in (0..3).rev() {
                let v = at[a] as i64 + d[a];
                let n = self.n[a] as i64;
                // past the last cell the neighbour is the first one, one box length on
                image = 3 * image + (1 + v.div_euclid(n)) as u8;
                if self.periodic[a] {
                    m[a] = v.rem_euclid(n) as usize;
                } else if (0..n).contains(&v) {
                    m[a] = v as usize;
                } else {
                    inside = false;
                }
            }
            out[k] = inside.then(|| (self.index(m), image));
            k += 1;
        }
        out
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
        assert!(Grid::new(&x, &None, 1.0).is_none());
    }
}
