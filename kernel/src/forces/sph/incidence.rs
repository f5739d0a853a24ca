//! Each body's pairs in the pairs' order, and the two passes they make parallel with the bits
//! of one thread: every pair's share on its own (`chunked`), then every body's sum of its pairs'
//! shares in the pairs' order (`gathered`) — the additions a loop over the pairs makes.

use super::super::density_derivative::Near;
use crate::spread;
use rayon::prelude::*;
use rayon::ThreadPool;

/// Bodies a thread takes at once in a pass over the bodies (tens of pairs each).
pub(super) const BODIES: usize = 32;

/// Each body's pairs in the pairs' order: `entries[start[b]..start[b + 1]]`, each a pair's
/// index times two, plus one where the body is the pair's second.
#[derive(Default)]
pub(super) struct Incidence {
    start: Vec<usize>,
    entries: Vec<usize>,
    next: Vec<usize>,
}

impl Incidence {
    /// The bodies' pairs of `near` among `n` bodies (a counting sort, in the pairs' order).
    pub(super) fn of(&mut self, near: &[Near], n: usize) {
        let Incidence { start, entries, next } = self;
        start.clear();
        start.resize(n + 1, 0);
        for &(i, j, ..) in near {
            start[i as usize + 1] += 1;
            start[j as usize + 1] += 1;
        }
        for b in 0..n {
            start[b + 1] += start[b];
        }
        next.clear();
        next.extend_from_slice(&start[..n]);
        entries.clear();
        entries.resize(2 * near.len(), 0);
        for (p, &(i, j, ..)) in near.iter().enumerate() {
            for (side, b) in [i, j].into_iter().enumerate() {
                entries[next[b as usize]] = 2 * p + side;
                next[b as usize] += 1;
            }
        }
    }

    /// Body `b`'s pairs: (pair, whether b is its second body).
    fn pairs_of(&self, b: usize) -> impl Iterator<Item = (usize, bool)> + '_ {
        self.entries[self.start[b]..self.start[b + 1]].iter().map(|&e| (e / 2, e % 2 == 1))
    }
}

/// `each(first, items)` over `items` in chunks of `chunk` on the pool's threads, `first` the
/// index of a chunk's first item; on this thread without a pool. Each item is its own, so the
/// bits are the same.
pub(super) fn chunked<T: Send>(
    pool: Option<&ThreadPool>,
    chunk: usize,
    items: &mut [T],
    each: impl Fn(usize, &mut [T]) + Sync + Send,
) {
    match pool {
        Some(pool) => spread::pass(|| {
            pool.install(|| items.par_chunks_mut(chunk).enumerate().for_each(|(k, c)| each(k * chunk, c)))
        }),
        None => each(0, items),
    }
}

/// `add(item, pair, second)` for each body's item and each of its pairs in the pairs' order
/// (`Incidence`), on the pool's threads.
pub(super) fn gathered<T: Send>(
    pool: &ThreadPool,
    incidence: &Incidence,
    items: &mut [T],
    add: impl Fn(&mut T, usize, bool) + Sync + Send,
) {
    chunked(Some(pool), BODIES, items, |first, items| {
        for (b, item) in (first..).zip(items) {
            for (p, second) in incidence.pairs_of(b) {
                add(item, p, second);
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::Incidence;
    use proptest::prelude::*;

    proptest! {
        /// Every pair is listed twice, once under each of its bodies with its side, and each
        /// body's pairs come in the pairs' order.
        #[test]
        fn each_body_holds_its_pairs_in_order(n in 1usize..40, ends in prop::collection::vec((0u32..40, 0u32..40), 0..200)) {
            let near: Vec<_> = ends.iter().map(|&(i, j)| (i % n as u32, j % n as u32, [0.0; 3], 0.0)).collect();
            let mut incidence = Incidence::default();
            incidence.of(&near, n);
            let mut seen = vec![[0u32; 2]; near.len()];
            for b in 0..n {
                let listed: Vec<(usize, bool)> = incidence.pairs_of(b).collect();
                prop_assert!(listed.windows(2).all(|w| w[0] <= w[1]));
                for (p, second) in listed {
                    let (i, j, ..) = near[p];
                    prop_assert_eq!(if second { j } else { i } as usize, b);
                    seen[p][second as usize] += 1;
                }
            }
            prop_assert!(seen.iter().all(|s| *s == [1, 1]));
        }
    }
}
