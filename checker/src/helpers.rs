//! The checker's helper threads: one pool for the process, started by the first piece of work
//! that spreads (a checkpoint starts no thread of its own), and `in_order`, which maps pieces of
//! work over them and gives the results back in the pieces' order, whoever computed them.

use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// `f(k)` for k in 0..n, in order of k, computed on up to `threads` of the helpers, each taking
/// the next k until none is left. Which helper computes which k changes nothing: each result is
/// put back at its k. (Dealt out in turn, k ≡ w mod threads to helper w, the pieces waited for
/// the slowest helper: one that shares its CPU with the kernel's threads or another process.)
pub(crate) fn in_order<T: Send>(n: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = threads.clamp(1, n.max(1));
    let Some(pool) = (threads > 1).then(helpers).flatten() else {
        return (0..n).map(f).collect();
    };
    let next = AtomicUsize::new(0);
    let take = |_| {
        let mut taken = vec![];
        loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            if k >= n {
                break taken;
            }
            taken.push((k, f(k)));
        }
    };
    let taken: Vec<Vec<(usize, T)>> = pool.install(|| (0..threads).into_par_iter().map(take).collect());
    let mut results: Vec<Option<T>> = std::iter::repeat_with(|| None).take(n).collect();
    for (k, r) in taken.into_iter().flatten() {
        results[k] = Some(r);
    }
    results.into_iter().map(|r| r.expect("every k was taken")).collect()
}

/// The pool: as many helpers as CPUs, started the first time work spreads; `None` if the system
/// refuses threads (then the caller does all).
static HELPERS: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();

fn helpers() -> Option<&'static rayon::ThreadPool> {
    HELPERS
        .get_or_init(|| {
            let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
            rayon::ThreadPoolBuilder::new().num_threads(cpus).thread_name(|i| format!("lagra-checker-{i}")).build().ok()
        })
        .as_ref()
}

/// How many helpers this process has started: 0 until work first spreads, then the pool's size
/// for the rest of the run.
pub fn started() -> usize {
    HELPERS.get().and_then(Option::as_ref).map_or(0, |p| p.current_num_threads())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// `in_order` gives f(0), …, f(n − 1) in order, whatever the thread count, even where
        /// the pieces take very different times (a slow piece leaves the rest to the others).
        #[test]
        fn in_order_is_the_sequential_map(n in 0usize..40, threads in 0usize..6, slow in 0usize..40) {
            let f = |k: usize| {
                if k == slow {
                    std::thread::sleep(std::time::Duration::from_millis(2));
                }
                k * k + 1
            };
            prop_assert_eq!(in_order(n, threads, f), (0..n).map(|k| k * k + 1).collect::<Vec<_>>());
        }
    }

    /// Sums spread over the same helpers time after time: a hundred spread maps run on no more
    /// threads than the pool holds (a thread started per map would be a new thread each time).
    #[test]
    fn spread_work_starts_no_threads_of_its_own() {
        let seen = std::sync::Mutex::new(std::collections::HashSet::new());
        for _ in 0..100 {
            in_order(8, 4, |_| seen.lock().unwrap().insert(std::thread::current().id()));
        }
        let seen = seen.into_inner().unwrap().len();
        assert!(seen <= started().max(1), "{seen} threads for a pool of {}", started());
    }
}
