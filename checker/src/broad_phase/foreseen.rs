//! A checkpoint's pairs listed ahead, from a state a few steps before it, while the kernel
//! steps on: the pairs within a wider reach there hold every pair within reach at the
//! checkpoint while no body has moved far, which the checkpoint tests (`Foreseen::holds`); it
//! then keeps the same pairs by the grid's distance test, without a grid.

use super::Neighbourhood;
use crate::helpers::in_order;
use crate::model::{Cell, Images};
use std::ops::Range;

/// How much farther than the reach a `Foreseen` list looks, as a share of the reach.
pub(super) const SKIN: f64 = 0.3;

/// How many steps before a checkpoint its pairs are worth listing ahead: long enough for the
/// list to be built while the kernel steps on (~20 ms for 32,000 LJ atoms, ~30 ms beside the
/// kernel, against ~60 ms for 12 of the kernel's steps), short enough that bodies stay within
/// the skin (in the LJ benchmark, T = 1.44 and dt = 0.005, the fastest atom moves 0.10σ in 5
/// steps and 0.20σ in 10, against the 0.37σ the skin of a 2.5σ cutoff allows). Farther, the
/// grid is built instead.
pub const FORESIGHT: u64 = 12;

/// The pairs within reach·(1 + SKIN) of a state a few steps before a checkpoint, listed while
/// the kernel steps on to it. At the checkpoint, a pair within reach was within reach + |δi| +
/// |δj| of each other at the earlier state, δ being each body's displacement to its nearest
/// image (the triangle inequality: whichever images the bodies are seen through, their
/// displacements shift the pair's image by whole boxes). So while no body has moved more than
/// half the skin the list holds every pair within reach, and the distance test keeps exactly
/// the pairs the grid would give.
pub struct Foreseen {
    x: Vec<[f64; 3]>,
    reach: f64,
    /// The lists, made in pieces of `CELLS_A_PIECE` of the grid's cells on the helpers: list p
    /// of the whole is list p − first[k] of piece k, where first[k] ≤ p < first[k + 1] (one
    /// more entry: the number of lists).
    pieces: Vec<Lists>,
    first: Vec<usize>,
}

/// The lists of a run of the grid's cells: list p, of body `bodies[p]`, is
/// `after[start[p]..start[p + 1]]`, each pair once, under either of its bodies (in the grid's
/// order, `Neighbourhood::half_shells`: no sort; 32 bits each: this list is built beside the
/// kernel's own, and half the size is half the memory traffic).
#[derive(Default)]
struct Lists {
    bodies: Vec<u32>,
    start: Vec<usize>,
    after: Vec<u32>,
}

/// Cells a piece of a `Foreseen` list: 32,000 LJ atoms bin into ~1,000 cells, 256,000 into
/// ~8,000 (125 pieces, some 1.6 ms of listing each).
const CELLS_A_PIECE: usize = 64;

impl Foreseen {
    /// The list for `reach`, from the state at `x`, made on up to `threads` of the helpers (the
    /// same list on any number); none where the grid would not be used (few bodies, or
    /// coordinates too large for its rounding argument) or for 2³² bodies or more.
    pub fn new(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64, threads: usize) -> Option<Foreseen> {
        let wide = Neighbourhood::new(x, cell, Some(reach * (1.0 + SKIN)), &[]);
        let b = wide.bins.as_ref().filter(|_| u32::try_from(x.len()).is_ok())?;
        let cells = b.start.len() - 1;
        let pieces = in_order(cells.div_ceil(CELLS_A_PIECE), threads, |k| {
            // a list for each body with partners (a body's partners come one after another)
            let mut l = Lists::default();
            wide.half_shells(b, k * CELLS_A_PIECE..((k + 1) * CELLS_A_PIECE).min(cells), |i, j| {
                if l.bodies.last() != Some(&(i as u32)) {
                    l.bodies.push(i as u32);
                    l.start.push(l.after.len());
                }
                l.after.push(j as u32);
            });
            l.start.push(l.after.len());
            l
        });
        let counts = pieces.iter().scan(0, |n, l| {
            *n += l.bodies.len();
            Some(*n)
        });
        let first = std::iter::once(0).chain(counts).collect();
        Some(Foreseen { x: x.to_vec(), reach, pieces, first })
    }

    /// `f(i, js)` for each list p in `lists`, a range of `0..lists()`: its body i and the
    /// bodies listed under it.
    pub(super) fn each(&self, lists: Range<usize>, mut f: impl FnMut(usize, &[u32])) {
        for p in lists {
            let k = self.first.partition_point(|&s| s <= p) - 1;
            let (l, q) = (&self.pieces[k], p - self.first[k]);
            f(l.bodies[q] as usize, &l.after[l.start[q]..l.start[q + 1]]);
        }
    }

    /// How many lists: bodies with a partner.
    pub(super) fn lists(&self) -> usize {
        self.first.last().copied().unwrap_or(0)
    }

    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// Whether the list holds every pair within `reach` of `x`: the same reach and bodies, and
    /// every computed displacement within 0.99 of half the skin. A computed displacement is off
    /// by at most 2η like a pair's distance (`scale`), and a pair the distance test keeps is
    /// within reach·(1 + 2⁻⁴⁷) + 4η; the grid's condition on the size (checked by the caller,
    /// for the later state, and by `new`, for the earlier) keeps η below 10⁻⁶ of the reach, far
    /// under the 1% of the skin left over.
    pub(super) fn holds(&self, x: &[[f64; 3]], images: &Images, reach: f64) -> bool {
        let most = (0.99 * SKIN * reach / 2.0).powi(2);
        self.reach == reach
            && self.x.len() == x.len()
            && x.iter().zip(&self.x).all(|(a, b)| {
                let e = images.image(std::array::from_fn(|k| a[k] - b[k]));
                e[0] * e[0] + e[1] * e[1] + e[2] * e[2] <= most
            })
    }
}
