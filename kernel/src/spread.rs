//! The run's thread's clock of the passes that spread over threads, so that a run can state its
//! serial fraction (Amdahl's f): the share of its wall time spent outside every such pass.
//!
//! A pass that has a parallel form is run through [`pass`], whether a pool is there to share it
//! or not: at one thread the same pass runs alone, and is still work that more threads would
//! share. A pass too small to spread at any thread count is serial ([`pass_if`]); so is one on
//! so few bodies that the kernel never spreads it (the kick-drift below `SPREAD_FROM`). Passes nested in one count once. Whatever the thread does outside them (a prefix sum,
//! a table filled in order, the loop between passes) is serial, so the figure errs towards more
//! serial, never less: work left unwrapped counts against it.

use rayon::prelude::*;
use rayon::ThreadPool;
use std::cell::Cell;
use std::time::{Duration, Instant};

thread_local! {
    static SPREAD: Cell<Duration> = const { Cell::new(Duration::ZERO) };
    static DEPTH: Cell<u32> = const { Cell::new(0) };
}

/// Bodies a thread takes at once in a spread pass over them.
pub const BLOCK: usize = 4096;

/// Items a thread takes at once in [`each`]: a block's worth of clusters of four bodies.
const EACH: usize = BLOCK / 4;

/// Bodies from which a pass over them spreads over the run's threads, a thread taking `BLOCK`
/// at once (below, waking them costs more than the pass).
pub const SPREAD_FROM: usize = 4 * BLOCK;

/// `work()`, its wall time on this thread counted as spread (unless a pass around it counts it).
pub fn pass<R>(work: impl FnOnce() -> R) -> R {
    let outermost = DEPTH.with(|d| d.replace(d.get() + 1)) == 0;
    let started = outermost.then(Instant::now);
    let done = work();
    DEPTH.with(|d| d.set(d.get() - 1));
    if let Some(t) = started {
        SPREAD.with(|s| s.set(s.get() + t.elapsed()));
    }
    done
}

/// [`pass`] for work that spreads at more threads only if `spreads` (over `SPREAD_FROM` bodies
/// or more; into more than one piece). Work that does not runs on the calling thread at any
/// thread count, so it is serial, and it is not clocked: a clock costs more than a small pass.
pub fn pass_if<R>(spreads: bool, work: impl FnOnce() -> R) -> R {
    match spreads {
        true => pass(work),
        false => work(),
    }
}

/// `f(i)` for i in `0..n`, in order, on the pool's threads if there is one (each value its
/// own: the same values either way), as a pass.
pub fn each<U: Send>(pool: Option<&ThreadPool>, n: usize, f: impl Fn(usize) -> U + Sync + Send) -> Vec<U> {
    pass(|| match pool {
        Some(pool) => pool.install(|| (0..n).into_par_iter().with_min_len(EACH).map(f).collect()),
        None => (0..n).map(f).collect(),
    })
}

/// A pool's threads' start: every pass on the thread counts as nested, so it reads no clock.
/// The run's thread, which alone reads its clock, waits meanwhile in a pass of its own around
/// the pool's work (or counts that wait as serial). The 1,000-block stack sweeps a hundred
/// islands on the pool, each through hundreds of passes a step: clocked, they cost a seventh of
/// its passes' time at two threads. (Asking rayon in every pass whether its thread is a pool's
/// instead cost the one-body step 4.6 ns of 29.)
pub fn never_clocked(_thread: usize) {
    DEPTH.with(|d| d.set(1));
}

/// `work()` on one of `pool`'s threads, clocked there as it would be on the calling thread (the
/// pool starts its threads unclocked), the time its passes took added to the calling thread's
/// clock on return. A run's steps go to the pool in one piece this way: each pass inside is then
/// on the pool already, where a pass sent from outside wakes a worker and puts the run's thread
/// to sleep until it is done, twice a pass. On a two-vCPU machine that cost 20–90 µs a pass, and
/// the 1,000-block stack makes several passes a step.
pub fn within<R: Send>(pool: &ThreadPool, work: impl FnOnce() -> R + Send) -> R {
    let outer = DEPTH.with(Cell::get);
    let (done, spread) = pool.install(|| {
        let inner = DEPTH.with(|d| d.replace(outer));
        let before = spent();
        let done = work();
        DEPTH.with(|d| d.set(inner));
        (done, spent() - before)
    });
    SPREAD.with(|s| s.set(s.get() + spread));
    done
}

/// This thread's time in passes so far (a run reads it before and after).
pub fn spent() -> Duration {
    SPREAD.with(Cell::get)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::thread::sleep;

    fn nap() {
        sleep(Duration::from_millis(20));
    }

    #[test]
    fn a_pass_counts_its_time_and_a_nested_one_counts_once() {
        let (before, around) = (spent(), Instant::now());
        pass(|| {
            nap();
            pass(nap)
        });
        let (around, counted) = (around.elapsed(), spent() - before);
        assert!(counted >= Duration::from_millis(40), "{counted:?}");
        // counted twice, it would exceed the wall time around it by the inner nap
        assert!(counted <= around, "{counted:?} counted in {around:?}");
    }

    #[test]
    fn time_outside_a_pass_is_not_counted() {
        let before = spent();
        nap();
        pass_if(false, nap);
        assert_eq!(spent(), before);
        pass_if(true, nap);
        assert!(spent() - before >= Duration::from_millis(20));
    }

    #[test]
    fn a_pass_on_a_pools_thread_is_not_clocked_there() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).start_handler(never_clocked).build().unwrap();
        let (before, counted) = pool.install(|| {
            (spent(), {
                pass(nap);
                spent()
            })
        });
        assert_eq!(counted, before);
    }

    /// Work sent whole to a pool is clocked there as on the sender, and counted on the sender's
    /// clock; the pool's thread is unclocked again afterwards; sent from inside a pass, it counts
    /// once.
    #[test]
    fn work_sent_to_the_pool_is_clocked_as_if_at_home() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).start_handler(never_clocked).build().unwrap();
        let (before, around) = (spent(), Instant::now());
        within(&pool, || {
            nap();
            pass(nap)
        });
        let (around, counted) = (around.elapsed(), spent() - before);
        // the pass's nap counted, the nap outside it (20 ms or more) not
        assert!(counted >= Duration::from_millis(20), "{counted:?}");
        assert!(counted + Duration::from_millis(20) <= around, "{counted:?} counted in {around:?}");
        let after = pool.install(|| {
            let before = spent();
            pass(nap);
            spent() - before
        });
        assert_eq!(after, Duration::ZERO, "a pass on the pool's thread is unclocked again");
        let (before, around) = (spent(), Instant::now());
        pass(|| within(&pool, || pass(nap)));
        assert!(spent() - before <= around.elapsed());
    }

    #[test]
    fn each_thread_keeps_its_own_clock() {
        let before = spent();
        std::thread::scope(|s| _ = s.spawn(|| pass(nap)).join());
        assert_eq!(spent(), before);
    }
}
