//! The pair work cut into pieces that many threads can share with the same bits, after GROMACS's
//! nbnxm per-thread output blocks: a half list's i-clusters (numbered so that near clusters have
//! near numbers) are cut into runs of about equal pair counts, as many as the system's size
//! asks for and never as many as there are threads. Each piece writes only into a buffer of its
//! own that covers its i-clusters and its halo — the j-clusters its pairs reach that another
//! piece owns — and each cluster's forces are the sum of its parts in piece order. Any number
//! of threads, in any order, computes the same pieces and adds them in the same order: the same
//! bits.
//!
//! The same cut serves a domain decomposition across processes: a piece is a domain's home
//! clusters, its halo the ghosts it needs and sends back.

use crate::spread::{self, each};
use rayon::prelude::*;
use rayon::ThreadPool;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering::Relaxed};

/// Clusters a piece holds, about: enough work per piece that its halo (1.6 times its own
/// clusters on the LJ liquid; 2.6 at 256 clusters a piece, which ran 7% slower on one thread)
/// costs little against its pairs, and pieces enough that 64 threads all have work from
/// 131,072 bodies up.
pub const PIECE_CLUSTERS: usize = 512;

/// Most pieces: past this their count would only add halos.
const MOST: usize = 1024;

/// How a half list's work is cut, and where each piece's output goes back.
#[derive(Clone, Debug, Default)]
pub struct Pieces {
    /// Piece k holds the i-clusters `bounds[k]..bounds[k + 1]`.
    bounds: Vec<usize>,
    /// Each piece's buffer length: its own clusters, then its halo.
    sizes: Vec<usize>,
    /// For each listed pair (in list order), its j-cluster's place in its piece's buffer.
    pub place: Vec<u32>,
    /// Cluster c's parts are `parts[first[c]..first[c + 1]]`: (piece, place), in piece order.
    first: Vec<usize>,
    parts: Vec<(u32, u32)>,
}

impl Pieces {
    /// These pieces made a copy of `from` in the memory they hold (`Neighbours::copy_from`).
    pub fn copy_from(&mut self, from: &Pieces, pool: Option<&ThreadPool>) {
        let Pieces { bounds, sizes, place, first, parts } = self;
        bounds.clone_from(&from.bounds);
        sizes.clone_from(&from.sizes);
        spread::copy(pool, place, &from.place);
        spread::copy(pool, first, &from.first);
        spread::copy(pool, parts, &from.parts);
    }

    /// The number of pieces for a list of `clusters` clusters: the size alone decides.
    pub fn count_for(clusters: usize) -> usize {
        (clusters / PIECE_CLUSTERS).clamp(1, MOST)
    }

    /// Cuts a half list: i-cluster c's pairs are `start[c]..start[c + 1]`, pair p's j-cluster is
    /// `j(p)`. Each piece is cut on its own (on the pool's threads, if any) and the results
    /// joined in order: the same cut on any number of threads.
    pub fn cut(start: &[usize], j: impl Fn(usize) -> usize + Sync, pool: Option<&ThreadPool>) -> Pieces {
        let clusters = start.len() - 1;
        let (count, total) = (Self::count_for(clusters), start[clusters]);
        let bounds: Vec<usize> = (0..=count)
            .map(
                |k| if k == count { clusters } else { start.partition_point(|&s| s < total * k / count).min(clusters) },
            )
            .collect();
        // a piece's halo in the order its pairs first reach each cluster; `seen[c]` holds the
        // last piece (plus one) that reached cluster c and where c went in it, so that no sort
        // and no map is needed (one such table per worker, reused across its pieces). Each
        // piece writes its pairs' places straight into its own run of `place`.
        // (zeroed as a pass: every entry is written below, but a vector of 1.75 million zeros
        // made on this thread was a quarter of the serial part at 256,000 atoms)
        let spread = pool.filter(|p| p.current_num_threads() > 1);
        let mut place: Vec<u32> = each(spread, total, |_| 0);
        let places = runs(&mut place, (0..count).map(|k| start[bounds[k + 1]] - start[bounds[k]]));
        let one = |seen: &mut Vec<(u32, u32)>, (k, run): (usize, &mut [u32])| {
            let own = bounds[k]..bounds[k + 1];
            let mut halo = vec![];
            for (p, at) in (start[own.start]..start[own.end]).zip(run.iter_mut()) {
                *at = match j(p) {
                    c if own.contains(&c) => (c - own.start) as u32,
                    c => {
                        if seen[c].0 != k as u32 + 1 {
                            seen[c] = (k as u32 + 1, (own.len() + halo.len()) as u32);
                            halo.push(c as u32);
                        }
                        seen[c].1
                    }
                };
            }
            halo
        };
        let table = || vec![(0u32, 0u32); clusters];
        let halos: Vec<Vec<u32>> = spread::pass(|| match spread {
            Some(p) => p.install(|| (0..count).into_par_iter().zip(places).map_init(table, one).collect()),
            None => {
                let mut seen = table();
                (0..count).zip(places).map(|kr| one(&mut seen, kr)).collect()
            }
        });
        let each_piece = |f: &(dyn Fn(usize) + Sync)| {
            spread::pass(|| match spread {
                Some(p) => p.install(|| (0..count).into_par_iter().for_each(f)),
                None => (0..count).for_each(f),
            })
        };
        // each cluster's parts: its own piece's place and one for each halo that holds it,
        // counted and placed through atomic cursors (whose order varies with the threads), then
        // each cluster's few parts sorted by piece (which does not)
        let held: Vec<AtomicUsize> = each(spread, clusters, |_| AtomicUsize::new(1));
        each_piece(&|k| halos[k].iter().for_each(|&c| _ = held[c as usize].fetch_add(1, Relaxed)));
        let mut first = Vec::with_capacity(clusters + 1);
        first.push(0);
        for h in &held {
            first.push(first.last().copied().unwrap_or(0) + h.load(Relaxed));
        }
        let cursor: Vec<AtomicUsize> = each(spread, clusters, |c| AtomicUsize::new(first[c]));
        let slots: Vec<AtomicU64> = each(spread, first[clusters], |_| AtomicU64::new(0));
        let put = |c: usize, k: usize, at: usize| {
            slots[cursor[c].fetch_add(1, Relaxed)].store((k as u64) << 32 | at as u64, Relaxed)
        };
        each_piece(&|k| {
            let own = bounds[k]..bounds[k + 1];
            own.clone().for_each(|c| put(c, k, c - own.start));
            halos[k].iter().enumerate().for_each(|(h, &c)| put(c as usize, k, own.len() + h));
        });
        let mut parts: Vec<(u32, u32)> = each(spread, slots.len(), |k| {
            let s = slots[k].load(Relaxed);
            ((s >> 32) as u32, s as u32)
        });
        let mut by_cluster = runs(&mut parts, first.windows(2).map(|w| w[1] - w[0]));
        spread::pass(|| match spread {
            Some(p) => p.install(|| by_cluster.par_iter_mut().for_each(|r| r.sort_unstable())),
            None => by_cluster.iter_mut().for_each(|r| r.sort_unstable()),
        });
        let sizes = halos.iter().enumerate().map(|(k, halo)| bounds[k + 1] - bounds[k] + halo.len()).collect();
        Pieces { bounds, sizes, place, first, parts }
    }

    pub fn count(&self) -> usize {
        self.sizes.len()
    }

    /// Piece k's own i-clusters.
    pub fn own(&self, k: usize) -> Range<usize> {
        self.bounds[k]..self.bounds[k + 1]
    }

    /// Piece k's buffer length.
    pub fn size(&self, k: usize) -> usize {
        self.sizes[k]
    }

    /// Cluster c's parts from the pieces' buffers, in piece order: `add` folds them.
    pub fn gather<V: Copy>(&self, c: usize, buffers: &[Vec<V>], add: impl Fn(V, V) -> V) -> V {
        let mut parts =
            self.parts[self.first[c]..self.first[c + 1]].iter().map(|&(k, at)| buffers[k as usize][at as usize]);
        let first = parts.next().expect("every cluster belongs to a piece");
        parts.fold(first, add)
    }

    /// All the work a halo adds: buffer places over clusters (1 would be no halo at all).
    pub fn spread(&self) -> f64 {
        self.parts.len() as f64 / (self.first.len() - 1).max(1) as f64
    }
}

/// `all` cut into consecutive runs of the given lengths, each to be written on its own (by
/// another thread, say).
pub fn runs<T>(all: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = all;
    lengths
        .map(|n| {
            let (run, tail) = std::mem::take(&mut rest).split_at_mut(n);
            rest = tail;
            run
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A made-up half list: each i-cluster's j-clusters, from a seed, some near and some wrapping
    /// far (as periodic images do).
    fn list(clusters: usize, seed: u64) -> (Vec<usize>, Vec<usize>) {
        let (mut start, mut js) = (vec![0], vec![]);
        let mut s = seed | 1;
        for c in 0..clusters {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            for k in 0..(s % 9) as usize {
                js.push(match k % 3 {
                    0 => c,
                    1 => (c + 1 + (s as usize >> 8) % 40).min(clusters - 1),
                    _ => (s as usize >> 16) % clusters,
                });
            }
            start.push(js.len());
        }
        (start, js)
    }

    proptest! {
        /// Every pair lands in exactly one piece, at a place that is its j-cluster's; every
        /// cluster's parts are its own piece's place and its halos', in piece order.
        #[test]
        fn every_pair_is_written_once_and_every_part_gathered(clusters in 1usize..3000, seed in any::<u64>()) {
            let (start, js) = list(clusters, seed);
            let p = Pieces::cut(&start, |q| js[q], None);
            prop_assert_eq!(p.count(), Pieces::count_for(clusters));
            prop_assert_eq!(p.own(0).start, 0);
            prop_assert_eq!(p.own(p.count() - 1).end, clusters);
            // which cluster each piece's places stand for, from the parts
            let mut stands: Vec<Vec<Option<usize>>> = (0..p.count()).map(|k| vec![None; p.size(k)]).collect();
            for c in 0..clusters {
                let parts = &p.parts[p.first[c]..p.first[c + 1]];
                prop_assert!(parts.windows(2).all(|w| w[0].0 < w[1].0), "piece order");
                for &(k, at) in parts {
                    prop_assert!(stands[k as usize][at as usize].replace(c).is_none(), "a place stands for one cluster");
                }
            }
            let mut seen = 0;
            for k in 0..p.count() {
                prop_assert!(stands[k].iter().all(Option::is_some), "no place unused");
                for ic in p.own(k) {
                    prop_assert_eq!(stands[k][ic - p.own(k).start], Some(ic));
                    for q in start[ic]..start[ic + 1] {
                        prop_assert_eq!(stands[k][p.place[q] as usize], Some(js[q]));
                        seen += 1;
                    }
                }
            }
            prop_assert_eq!(seen, js.len());
        }
    }

    #[test]
    fn the_cut_is_the_same_on_any_number_of_threads() {
        let (start, js) = list(40_000, 7);
        let one = Pieces::cut(&start, |q| js[q], None);
        for threads in [2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let many = Pieces::cut(&start, |q| js[q], Some(&pool));
            assert_eq!((&one.bounds, &one.place, &one.parts), (&many.bounds, &many.place, &many.parts));
        }
    }

    #[test]
    fn the_count_follows_the_size_not_the_threads() {
        assert_eq!(Pieces::count_for(10), 1);
        assert_eq!(Pieces::count_for(64_000), 125);
        assert_eq!(Pieces::count_for(10_000_000), MOST);
    }
}
