//! A build's passes over the bodies (`Neighbours::build`): the columns they are binned into and
//! cut into clusters along z, and the search for the cluster pairs within reach + skin, column
//! by column. Like the list itself, everything here depends on the positions alone.

use super::{Cluster, Pair, CENTRE, EMPTY, LANES};
use crate::lanes::{norm2, F64x4, Lane};
use crate::pieces::runs;
use crate::spread::{self, each, share};
use crate::step::BLOCK;
use lagra_checker::model::Cell;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::ops::Range;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The parts one after another, `map(part, value)` applied to each value, each part copied on
/// the pool's threads if there is one: the same values either way.
pub(super) fn joined<U: Copy + Send + Sync>(
    spread: Option<&ThreadPool>,
    parts: &[&[U]],
    map: impl Fn(usize, U) -> U + Sync,
) -> Vec<U> {
    let Some(&[fill, ..]) = parts.iter().find(|p| !p.is_empty()).copied() else { return vec![] };
    let n = parts.iter().map(|p| p.len()).sum();
    // (filled on the threads too: a fill on one would be half the work)
    let mut all = spread::pass(|| match spread {
        Some(pool) => pool.install(|| {
            let mut all = Vec::with_capacity(n);
            all.par_extend(rayon::iter::repeat_n(fill, n));
            all
        }),
        None => vec![fill; n],
    });
    let runs = runs(&mut all, parts.iter().map(|p| p.len()));
    let copy = |(k, run): (usize, &mut [U])| run.iter_mut().zip(parts[k]).for_each(|(to, &from)| *to = map(k, from));
    spread::pass(|| match spread {
        Some(pool) => pool.install(|| runs.into_par_iter().enumerate().for_each(copy)),
        None => runs.into_iter().enumerate().for_each(copy),
    });
    all
}

/// Where empty slots sit: beyond the farthest coordinate of any body by r and the longest
/// period `p` (so that no periodic image of a body comes within r of one), along y and z too,
/// and 4 r + p apart from each other along x (so that no image of one comes within r of
/// another): a pair with an empty slot is beyond the cutoff whatever image the list gives it.
/// (Without the periods, 4 r apart, an empty slot's image one box over could land within the
/// cutoff of its neighbour's in a small sparse box, and the kernel counted the phantom pair's
/// energy: `the_list_is_every_cluster_pair_that_touches`.) And no distance to one squares into
/// a subnormal's range.
pub(super) fn far(w: &[[f64; 3]], r: f64, p: f64, spread: Option<&ThreadPool>) -> impl Fn(usize) -> [f64; 3] {
    let largest = |p: &[f64; 3]| p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    // (the largest of a set is the same however it is split)
    let base = spread::pass(|| match spread {
        Some(pool) => pool.install(|| w.par_iter().with_min_len(BLOCK).map(largest).reduce(|| 0.0, f64::max)),
        None => w.iter().map(largest).fold(0.0, f64::max),
    }) + p
        + 10.0 * r
        + 1.0;
    move |slot| [base + (4.0 * r + p) * slot as f64, base, base]
}

/// Bodies a block deals into the columns (`Columns::clusters`): 16 blocks at 256,000 bodies.
const DEAL: usize = 4 * BLOCK;

/// An axis-aligned box around a cluster's bodies.
#[derive(Clone, Copy)]
pub(super) struct Bounds {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Bounds {
    pub(super) fn of<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> Bounds {
        points.fold(Bounds { lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] }, |b, p| Bounds {
            lo: std::array::from_fn(|a| b.lo[a].min(p[a])),
            hi: std::array::from_fn(|a| b.hi[a].max(p[a])),
        })
    }

    /// The box around `boxes` (empty, lo above hi, if there are none).
    pub(super) fn around(boxes: &[Bounds]) -> Bounds {
        Bounds::of(boxes.iter().flat_map(|b| [&b.lo, &b.hi]))
    }
}

/// Columns along x and y over the box (periodic axes) or over the bodies' extent (open axes).
pub(super) struct Columns {
    n: [usize; 2],
    lo: [f64; 2],
    width: [f64; 2],
    /// Box lengths along periodic axes (x, y, z), 0 along open ones.
    period: [f64; 3],
}

impl Columns {
    pub(super) fn new(w: &[[f64; 3]], cell: &Option<Cell>) -> Columns {
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
    pub(super) fn clusters(&self, w: &[[f64; 3]], spread: Option<&ThreadPool>) -> (Vec<u32>, Vec<usize>) {
        let columns = self.n[0] * self.n[1];
        let column: Vec<usize> = each(spread, w.len(), |i| self.index(0, w[i][0]) + self.n[0] * self.index(1, w[i][1]));
        // counted and dealt into the columns block by block, each block of bodies from cursors
        // of its own (no cursor shared between threads, which on many cores would pass each
        // other its cache lines at every body), the blocks' places in a column in block order:
        // a column's bodies come in increasing order. The blocks follow the bodies, never the
        // threads, and their tallies take at most four counters a body (columns ≤ bodies / 4).
        let blocks = w.len().div_ceil(DEAL).min(4 * w.len() / columns).max(1);
        let block = |b: usize| w.len() * b / blocks..w.len() * (b + 1) / blocks;
        let mut places: Vec<Vec<u32>> = share(spread, blocks, 1, |b| {
            let mut tally = vec![0u32; columns];
            column[block(b)].iter().for_each(|&c| tally[c] += 1);
            tally
        });
        // each block's first place in each column (and `count`, each column's first place)
        let mut count = vec![0usize; columns + 1];
        for c in 0..columns {
            let mut at = count[c] as u32;
            for tally in &mut places {
                (tally[c], at) = (at, at + tally[c]);
            }
            count[c + 1] = at as usize;
        }
        let dealt: Vec<AtomicU32> = each(spread, w.len(), |_| AtomicU32::new(0));
        share(spread, blocks, 1, |b| {
            let mut next = places[b].clone();
            for i in block(b) {
                dealt[next[column[i]] as usize].store(i as u32, Relaxed);
                next[column[i]] += 1;
            }
        });
        let mut order: Vec<u32> = each(spread, w.len(), |k| dealt[k].load(Relaxed));
        // each column's run sorted by z (then by body: a total order, so the same runs however
        // the columns are shared out)
        let mut runs = runs(&mut order, count.windows(2).map(|w| w[1] - w[0]));
        let by_z = |run: &mut &mut [u32]| {
            run.sort_unstable_by(|&a, &b| w[a as usize][2].total_cmp(&w[b as usize][2]).then(a.cmp(&b)))
        };
        spread::pass(|| match spread {
            Some(pool) => pool.install(|| runs.par_iter_mut().for_each(by_z)),
            None => runs.iter_mut().for_each(by_z),
        });
        // each column's clusters, the last padded with empty slots
        let mut first = Vec::with_capacity(columns + 1);
        first.push(0);
        for c in 0..columns {
            first.push(first[c] + (count[c + 1] - count[c]).div_ceil(LANES));
        }
        let slots: Vec<[u32; LANES]> = each(spread, first[columns], |k| {
            let c = first.partition_point(|&f| f <= k) - 1;
            let run = &order[count[c]..count[c + 1]];
            std::array::from_fn(|l| run.get(LANES * (k - first[c]) + l).copied().unwrap_or(EMPTY))
        });
        let slots = slots.into_flattened();
        (slots, first)
    }
}

/// Whether some body of an i-cluster lies within r (r² given) of one of cluster `xj` moved by
/// `s` (empty slots are far from everything), from the i-cluster's `Rows`: boxes within r whose
/// bodies are not (a third of them on a dense liquid) are left out.
pub(super) trait Touch<Rows>: Fn(&Rows, &Cluster, &[f64; 3], f64) -> bool {}
impl<Rows, F: Fn(&Rows, &Cluster, &[f64; 3], f64) -> bool> Touch<Rows> for F {}

/// `Touch` as four rows of four lanes (the i-cluster's positions are its rows): sixteen
/// distances, no branch.
#[inline(always)]
fn touch(xi: &Cluster, xj: &Cluster, s: &[f64; 3], r2: f64) -> bool {
    let xs = [xj[0] + s[0], xj[1] + s[1], xj[2] + s[2]];
    let mut least = F64x4::splat(f64::INFINITY);
    for a in 0..LANES {
        let d = [xs[0] - xi[0].lane(a), xs[1] - xi[1].lane(a), xs[2] - xi[2].lane(a)];
        least = least.min(norm2(&d));
    }
    least.lt(F64x4::splat(r2)).any()
}

/// An i-cluster's rows in AVX-512 registers: bodies 0 and 1 (each four times over), then
/// bodies 2 and 3, by coordinate.
#[cfg(target_arch = "x86_64")]
type Eight = [[std::arch::x86_64::__m512d; 3]; 2];

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[inline]
fn eight(xi: &Cluster) -> Eight {
    use std::arch::x86_64::_mm512_set_pd;
    [0, 2].map(|a| {
        std::array::from_fn(|k| {
            let (p, q) = (xi[k].lane(a), xi[k].lane(a + 1));
            _mm512_set_pd(q, q, q, q, p, p, p, p)
        })
    })
}

/// `touch` on AVX-512 registers, two rows in each (the j-cluster twice over against `eight`'s
/// rows): half the instructions, each distance computed by the same operations in the same
/// order as `touch` (the j-positions moved by s, the differences, |d|² as `norm2`), so the
/// same answer.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[inline]
fn touch_eight(xi: &Eight, xj: &Cluster, s: &[f64; 3], r2: f64) -> bool {
    use std::arch::x86_64::*;
    let xs: [__m512d; 3] = std::array::from_fn(|k| {
        let [a, b, c, d] = xj[k].to_array();
        _mm512_add_pd(_mm512_set_pd(d, c, b, a, d, c, b, a), _mm512_set1_pd(s[k]))
    });
    let r2 = _mm512_set1_pd(r2);
    let mut near = 0;
    for row in xi {
        let d: [__m512d; 3] = std::array::from_fn(|k| _mm512_sub_pd(xs[k], row[k]));
        let d2 = _mm512_fmadd_pd(d[2], d[2], _mm512_fmadd_pd(d[1], d[1], _mm512_mul_pd(d[0], d[0])));
        near |= _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d2, r2);
    }
    near != 0
}

/// Where the search of each neighbouring column (offset along x and y, image along z) has got
/// to, for the i-clusters of one column, taken in z order.
struct Cursors {
    at: Vec<(usize, usize)>,
    /// Each neighbouring column's z window (`Search::z_reach`), worked out at the column's
    /// first use (NaN before: a square root for every i-cluster cost more than it saved).
    z_reach: Vec<f64>,
    ny: usize,
    reach: [usize; 2],
}

/// What the pair search reads: the clusters by column, their boxes and positions.
pub(super) struct Search<'a> {
    pub(super) columns: &'a Columns,
    pub(super) first: &'a [usize],
    pub(super) boxes: &'a [Bounds],
    /// Each column's box: around its clusters' boxes.
    pub(super) column_boxes: &'a [Bounds],
    pub(super) x: &'a [Cluster],
    pub(super) shifts: &'a [[f64; 3]; 32],
    pub(super) r: f64,
    /// The clusters whose bodies are all ghosts (`Neighbours::leave_out_pairs_among`), if any
    /// are: no pair of two of them is listed.
    pub(super) ghostly: Option<&'a [bool]>,
}

impl Search<'_> {
    /// The i-clusters `part`: where each one's pairs start (from 0) and the pairs. Where the
    /// CPU has AVX-512 (detected at run time), the same code compiled for it (`wide_part`).
    pub(super) fn part(&self, part: Range<usize>) -> (Vec<usize>, Vec<Pair>) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512vl") {
            // SAFETY: the CPU has the features `wide_part` is compiled for, checked just above.
            return unsafe { self.wide_part(part) };
        }
        self.portable_part(part, |xi| *xi, touch)
    }

    /// `portable_part` compiled for AVX-512 (as the force kernel's `pipelined` is): the
    /// sixteen distances of a candidate in one or two instructions a step instead of SSE2's
    /// pairs; the same arithmetic on the same lanes, so the same list.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
    #[inline(never)]
    fn wide_part(&self, part: Range<usize>) -> (Vec<usize>, Vec<Pair>) {
        self.portable_part(part, |xi| eight(xi), |xi, xj, s, r2| touch_eight(xi, xj, s, r2))
    }

    #[inline(always)]
    fn portable_part<Rows>(
        &self,
        part: Range<usize>,
        rows: impl Fn(&Cluster) -> Rows,
        touch: impl Touch<Rows>,
    ) -> (Vec<usize>, Vec<Pair>) {
        let (mut start, mut pairs) = (vec![], vec![]);
        let mut column = self.first.partition_point(|&f| f <= part.start) - 1;
        let reach = [0, 1].map(|a| self.columns.reach(a, self.r) as usize);
        let mut cursors = Cursors { at: vec![], z_reach: vec![], ny: 2 * reach[1] + 1, reach };
        for ic in part {
            if self.first[column + 1] <= ic || cursors.at.is_empty() {
                while self.first[column + 1] <= ic {
                    column += 1;
                }
                cursors.at = vec![(0, 0); (2 * reach[0] + 1) * cursors.ny * 3];
                cursors.z_reach = vec![f64::NAN; (2 * reach[0] + 1) * cursors.ny];
            }
            start.push(pairs.len());
            self.near(ic, column, &mut cursors, &mut pairs, (&rows(&self.x[ic]), &touch));
        }
        (start, pairs)
    }

    /// How far along z a body of column `col` moved by `shift` (along x and y) can be from one
    /// of column `column` and still lie within r: √(r² − g²), g the gap between the two
    /// columns' boxes across x and y (a column two over from `column` needs a z window of
    /// √(2.8² − 1.68²) = 2.24 instead of 2.8 on the LJ liquid: an eighth fewer candidates to
    /// test). Why the window holds every pair the sixteen distances would list: the gap along
    /// an axis is computed with the same roundings as a pair's difference there (each rounding
    /// monotone), so it is at most that difference's size; what is left for z is widened by
    /// 10⁻⁹ against the square root's rounding. −∞ where the gap is r or more: no pair of the
    /// two columns can be listed. One window for every i-cluster of `column`, so the cursors
    /// still only move up.
    fn z_reach(&self, column: usize, col: usize, shift: [f64; 2]) -> f64 {
        let (i, j) = (&self.column_boxes[column], &self.column_boxes[col]);
        let gap = |a: usize| (j.lo[a] + shift[a] - i.hi[a]).max(i.lo[a] - (j.hi[a] + shift[a])).max(0.0);
        let (gx, gy) = (gap(0), gap(1));
        let left = self.r * self.r - gy.mul_add(gy, gx * gx);
        if left > 0.0 {
            left.sqrt() * (1.0 + 1e-9)
        } else {
            f64::NEG_INFINITY
        }
    }

    /// The clusters whose boxes lie within r of cluster `ic`'s (in column `column`), each
    /// cluster pair once: j after i, or i itself at the zero image or a later one.
    #[inline(always)]
    fn near<Rows>(
        &self,
        ic: usize,
        column: usize,
        cursors: &mut Cursors,
        out: &mut Vec<Pair>,
        (rows, touch): (&Rows, &impl Touch<Rows>),
    ) {
        let g = self.columns;
        let b = &self.boxes[ic];
        let r2 = self.r * self.r;
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
            for (jy, ny, iy) in offsets(1, cy) {
                let sy = ny as f64 * g.period[1];
                let col = jx + g.n[0] * jy;
                // clusters are numbered column by column: an earlier column's come before ic's
                if col < column {
                    continue;
                }
                // (a column too far from ic's is left out by a test that comes out the same for
                // every i-cluster of the column: one by ic's own box, which varies, cost more in
                // mispredicted branches than the candidates it saved)
                let rz = &mut cursors.z_reach[ix * cursors.ny + iy];
                if rz.is_nan() {
                    *rz = self.z_reach(column, col, [sx, sy]);
                }
                let rz = *rz;
                if rz < 0.0 {
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
                    while *from < run.len() && run[*from].hi[2] + sz < b.lo[2] - rz {
                        *from += 1;
                    }
                    *to = (*to).max(*from);
                    while *to < run.len() && run[*to].lo[2] + sz <= b.hi[2] + rz {
                        *to += 1;
                    }
                    // bodies within r imply boxes within r: the sixteen distances alone decide,
                    // each candidate written and kept by advancing the end (no branch to miss)
                    let base = self.first[col];
                    let from = (*from + base).max(if image >= CENTRE { ic } else { ic + 1 });
                    let to = *to + base;
                    let mut end = out.len();
                    out.resize(end + to.saturating_sub(from), Pair(0));
                    match self.ghostly.filter(|g| g[ic]) {
                        None => {
                            for jc in from..to {
                                out[end] = Pair::new(jc, image);
                                end += usize::from(touch(rows, &self.x[jc], s, r2));
                            }
                        }
                        // (a loop of its own: the one above, every list's, stays as it was)
                        Some(ghostly) => {
                            for jc in from..to {
                                out[end] = Pair::new(jc, image);
                                end += usize::from(touch(rows, &self.x[jc], s, r2) && !ghostly[jc]);
                            }
                        }
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
    use std::array::from_fn;

    /// The eight-lane test answers as the four-lane one where it is hardest to: a j-body a few
    /// ulps either side of r from an i-body, where an operation done otherwise would flip the
    /// answer (both answers occur, or the test would not bite).
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn eight_lanes_answer_as_four_at_the_edge() {
        if !std::is_x86_feature_detected!("avx512vl") {
            eprintln!("this CPU has no AVX-512: the eight-lane test is not compiled into any run here");
            return;
        }
        let (mut rng, r) = (Rng::new(7), 2.8f64);
        let mut answers = [0; 2];
        for _ in 0..100_000 {
            let xi: Cluster = from_fn(|_| F64x4::new(from_fn(|_| rng.uniform(0.0, 2.0))));
            let (a, b) = (rng.uniform(0.0, 4.0) as usize, rng.uniform(0.0, 4.0) as usize);
            let u: [f64; 3] = from_fn(|_| rng.uniform(-1.0, 1.0));
            let scale = r * (1.0 + (rng.uniform(-4.0, 4.0)).round() * f64::EPSILON) / norm2(&u).sqrt();
            let s: [f64; 3] = from_fn(|_| [-10.0, 0.0, 10.0][rng.uniform(0.0, 3.0) as usize]);
            // body b of j at about r from body a of i (once moved by s), the others far
            let xj: Cluster = from_fn(|k| {
                F64x4::new(from_fn(|l| if l == b { xi[k].lane(a) + u[k] * scale - s[k] } else { 100.0 + l as f64 }))
            });
            let four = touch(&xi, &xj, &s, r * r);
            // SAFETY: the CPU has AVX-512 (checked above), which `eight` and `touch_eight` are
            // compiled for.
            let wide = unsafe { touch_eight(&eight(&xi), &xj, &s, r * r) };
            assert_eq!(four, wide, "{xi:?} {xj:?} {s:?}");
            answers[usize::from(four)] += 1;
        }
        assert!(answers.iter().all(|&n| n > 1000), "{answers:?}");
    }
}
