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
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

thread_local! {
    static SPREAD: Cell<Duration> = const { Cell::new(Duration::ZERO) };
    static DEPTH: Cell<u32> = const { Cell::new(0) };
    /// Whether this thread is polling the pool for work ([`awake`]).
    static POLLING: Cell<bool> = const { Cell::new(false) };
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

/// A pass over `n` bodies (or items): `work(true)` on `pool`'s threads where they are enough to
/// spread (`SPREAD_FROM` or more, and a pool given), else `work(false)` on this thread; clocked
/// wherever that many would spread at more threads, serial and not clocked below. `work` gives
/// the same bits either way (each body's arithmetic its own, or a reduction that does not
/// depend on the split), so the thread count changes none. (The few bodies' way is tested
/// first and calls `work` with nothing around it: through `pass_if`'s closure, the one-body
/// step took 40 ns against 24.)
#[inline(always)]
pub fn over<R: Send>(pool: Option<&ThreadPool>, n: usize, work: impl FnOnce(bool) -> R + Send) -> R {
    match (n >= SPREAD_FROM, pool) {
        (false, _) => work(false),
        (true, Some(pool)) => pass(|| pool.install(|| work(true))),
        (true, None) => pass(|| work(false)),
    }
}

/// `into` made a copy of `from` (in the memory it holds, where that is enough), as a pass in
/// `BLOCK`s on the pool's threads where `from` is long enough to spread. A large copy is bound
/// by memory, and more cores draw more of its bandwidth; fresh memory's page faults are taken
/// where it is written, on those threads. A gradient copies states and lists at every step of
/// its replays: on one thread they were most of its serial part.
pub fn copy<T: Copy + Send + Sync>(pool: Option<&ThreadPool>, into: &mut Vec<T>, from: &[T]) {
    into.clear();
    over(pool, from.len(), |on_pool| match on_pool {
        true => into.par_extend(from.par_iter().copied().with_min_len(BLOCK)),
        false => into.extend_from_slice(from),
    })
}

/// A copy of `from`, made as [`copy`] makes it.
pub fn copied<T: Copy + Send + Sync>(pool: Option<&ThreadPool>, from: &[T]) -> Vec<T> {
    let mut into = vec![];
    copy(pool, &mut into, from);
    into
}

/// `f(i)` for i in `0..n`, in order, on the pool's threads if there is one (each value its
/// own: the same values either way), as a pass.
pub fn each<U: Send>(pool: Option<&ThreadPool>, n: usize, f: impl Fn(usize) -> U + Sync + Send) -> Vec<U> {
    pass(|| match pool {
        Some(pool) => pool.install(|| (0..n).into_par_iter().with_min_len(EACH).map(f).collect()),
        None => (0..n).map(f).collect(),
    })
}

/// `f(i)` for i in `0..n`, in order, on the pool's threads if there is one, as a pass: each
/// thread takes the next `chunk` indices as it comes free, and the calling thread, its own
/// share done, spins until the last chunk in another's hands is in. A join in its place put
/// the caller to sleep when the other thread's last piece outlasted rayon's few dozen yields,
/// and waking it took ~100 µs on a 2-vCPU virtual machine, once a pass: the stack's islands
/// (70 µs each) lost that every step; a parallel iterator's halves, split only when stolen,
/// also left one thread idle for up to a quarter of the pass. The values are each their own,
/// so they are the same whoever computed them.
pub fn share<U: Send>(pool: Option<&ThreadPool>, n: usize, chunk: usize, f: impl Fn(usize) -> U + Sync) -> Vec<U> {
    pass(|| match pool {
        Some(pool) => pool.install(|| shared(n, chunk.max(1), &f)),
        None => (0..n).map(f).collect(),
    })
}

/// [`share`] on the current pool.
fn shared<U: Send>(n: usize, chunk: usize, f: &(impl Fn(usize) -> U + Sync)) -> Vec<U> {
    let helpers = others().min(n.div_ceil(chunk).saturating_sub(1));
    let (next, done, broken) = (AtomicUsize::new(0), AtomicUsize::new(0), AtomicBool::new(false));
    let found: Mutex<Vec<(usize, Vec<U>)>> = Mutex::new(vec![]);
    let take = || {
        let mine = catch_unwind(AssertUnwindSafe(|| {
            let mut mine = vec![];
            loop {
                let from = next.fetch_add(chunk, Ordering::Relaxed);
                if from >= n {
                    break mine;
                }
                mine.push((from, (from..(from + chunk).min(n)).map(f).collect::<Vec<U>>()));
            }
        }));
        match mine {
            Ok(mine) => {
                let count = mine.iter().map(|c| c.1.len()).sum();
                found.lock().unwrap_or_else(|e| e.into_inner()).extend(mine);
                done.fetch_add(count, Ordering::Release);
            }
            // the caller stops waiting for chunks that will never come; the scope passes it on
            Err(panic) => {
                broken.store(true, Ordering::Release);
                resume_unwind(panic)
            }
        }
    };
    rayon::scope(|s| {
        for _ in 0..helpers {
            s.spawn(|_| take());
        }
        take();
        let mut spins = 0u32;
        while done.load(Ordering::Acquire) < n && !broken.load(Ordering::Acquire) {
            // spin a while (the last chunk is one item's time away), then give the CPU up
            // between looks, in case the thread holding it has been put off the CPU
            spins += 1;
            match spins < 1 << 12 {
                true => std::hint::spin_loop(),
                false => std::thread::yield_now(),
            }
        }
    });
    let mut chunks = found.into_inner().unwrap_or_else(|e| e.into_inner());
    chunks.sort_unstable_by_key(|c| c.0);
    chunks.into_iter().flat_map(|c| c.1).collect()
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
    // (on the pool already, whose passes are clocked where they run: counted again, here, the
    // passes of a gradient's steps, on the pool whole, made its serial part −40%)
    if pool.current_thread_index().is_some() {
        return work();
    }
    let outer = DEPTH.with(Cell::get);
    let (done, spread) = pool.install(|| {
        let inner = DEPTH.with(|d| d.replace(outer));
        let before = spent();
        let done = awake(work);
        DEPTH.with(|d| d.set(inner));
        (done, spent() - before)
    });
    SPREAD.with(|s| s.set(s.get() + spread));
    done
}

/// How long a pool's thread kept awake by [`awake`] polls without finding work before it goes
/// back to the pool's own idling (and, soon after, to sleep). The stack's serial gaps between
/// passes are a few hundred microseconds; a checkpoint's ends every `within`.
const POLL_IDLE: Duration = Duration::from_millis(2);

/// `work()` on this pool thread, the pool's other threads kept awake meanwhile, each polling
/// the pool for work (`rayon::yield_now`) until `work` returns. A pool's idle thread yields a
/// few dozen times and then sleeps; waking it for the next pass took 100–300 µs on a 2-vCPU
/// virtual machine (the hypervisor deschedules a halted vCPU), half of the stack's 0.6 ms
/// broad-phase pass. OpenMP runtimes spin between parallel regions for the same reason
/// (`OMP_WAIT_POLICY=active`). Only as many threads poll as there are CPUs besides this one
/// (an oversubscribed pool's pollers would take the CPU from the work), and a poller that finds
/// nothing for `POLL_IDLE` stops, so a panic in `work` or a long serial part costs no more.
fn awake<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    awake_with(others(), work)
}

/// [`awake`] with `pollers` threads polling.
fn awake_with<R: Send>(pollers: usize, work: impl FnOnce() -> R + Send) -> R {
    if pollers == 0 {
        return work();
    }
    let (owner, done) = (rayon::current_thread_index(), AtomicBool::new(false));
    rayon::scope(|s| {
        for _ in 0..pollers {
            s.spawn(|_| poll(&done, owner));
        }
        let r = work();
        done.store(true, Ordering::Release);
        r
    })
}

/// Runs the pool's pending work on this thread until `done`, or until there has been none for
/// `POLL_IDLE`. A poller that lands on the owner's thread (taken from its own queue while it
/// waits in a pass), or inside another poller's job on this thread, returns at once: one that
/// polled there would hold up the work it is nested in until it found nothing for `POLL_IDLE`
/// (never longer: the bound, not this check, is what rules out a hang).
fn poll(done: &AtomicBool, owner: Option<usize>) {
    if rayon::current_thread_index() == owner || POLLING.with(|p| p.replace(true)) {
        return;
    }
    let mut found = Instant::now();
    while !done.load(Ordering::Acquire) {
        match rayon::yield_now() {
            Some(rayon::Yield::Executed) => found = Instant::now(),
            _ if found.elapsed() > POLL_IDLE => break,
            _ => std::thread::yield_now(),
        }
    }
    POLLING.with(|p| p.set(false));
}

/// The current pool's threads besides this one that have a CPU of their own to run on (more
/// would only take the CPU from the work).
fn others() -> usize {
    rayon::current_num_threads().min(cpus()).saturating_sub(1)
}

/// The CPUs this process may run on (read once).
fn cpus() -> usize {
    static CPUS: OnceLock<usize> = OnceLock::new();
    *CPUS.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
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

    /// `over` sends work to the pool only from `SPREAD_FROM` items, clocks it from there with or
    /// without a pool, and leaves fewer items on this thread, unclocked.
    #[test]
    fn a_pass_over_bodies_spreads_and_is_clocked_from_its_threshold() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let on_pool = |on: bool| {
            nap();
            (on, rayon::current_thread_index().is_some())
        };
        for (pool, n, spreads, clocked) in [
            (Some(&pool), SPREAD_FROM, true, true),
            (Some(&pool), SPREAD_FROM - 1, false, false),
            (None, SPREAD_FROM, false, true),
            (None, 1, false, false),
        ] {
            let before = spent();
            assert_eq!(over(pool, n, on_pool), (spreads, spreads), "{n} items");
            assert_eq!(spent() - before >= Duration::from_millis(20), clocked, "{n} items");
        }
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
        // sent again from the pool's own thread (a gradient on the pool whole, its steps sent
        // each): once
        let (before, around) = (spent(), Instant::now());
        within(&pool, || within(&pool, || pass(nap)));
        let (around, counted) = (around.elapsed(), spent() - before);
        assert!(counted >= Duration::from_millis(20) && counted <= around, "{counted:?} counted in {around:?}");
    }

    /// Every thread but one polling, nested passes on an oversubscribed pool (so pollers land
    /// on the owner's thread and inside one another's jobs): the same sums, and no hang.
    #[test]
    fn work_kept_awake_gets_its_answer_and_ends() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(8).build().unwrap();
        let nested = |i: u64| (0..i % 50).into_par_iter().map(|k| k * k).sum::<u64>();
        let want: u64 = (0..2000).map(nested).sum();
        for _ in 0..20 {
            let got = pool.install(|| awake_with(7, || (0..2000u64).into_par_iter().map(nested).sum::<u64>()));
            assert_eq!(got, want);
        }
    }

    #[test]
    fn a_panic_in_work_kept_awake_is_passed_on() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| awake_with(1, || panic!("in the work")))
        }));
        assert!(caught.is_err());
        assert_eq!(pool.install(|| awake_with(1, || 7)), 7, "the pool still works");
    }

    /// Every index once, in order, at any pool size and chunk (chunks that do not divide n,
    /// more helpers than chunks, an oversubscribed pool), and the same with no pool.
    #[test]
    fn shared_work_comes_back_whole_and_in_order() {
        let want: Vec<u64> = (0..1000u64).map(|i| i * i + 1).collect();
        for threads in [1, 2, 3, 16] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for (n, chunk) in [(1000, 1), (1000, 7), (1000, 16), (1000, 5000), (3, 1), (0, 4)] {
                let got = share(Some(&pool), n, chunk, |i| want[i]);
                assert_eq!(got, want[..n], "{threads} threads, n {n}, chunk {chunk}");
            }
        }
        assert_eq!(share(None, 1000, 16, |i| want[i]), want);
    }

    /// Shared out over the pool's threads: with a pass's work slow enough, both take part.
    #[test]
    fn shared_work_is_taken_by_more_than_one_thread() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let on = share(Some(&pool), 64, 1, |_| {
            std::thread::sleep(Duration::from_millis(1));
            rayon::current_thread_index()
        });
        if cpus() > 1 {
            assert!(on.contains(&Some(0)) && on.contains(&Some(1)), "{on:?}");
        }
    }

    /// A panic in a helper's chunk or the caller's reaches the caller, not a hang; the pool
    /// still works.
    #[test]
    fn a_panic_in_shared_work_is_passed_on() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for bad in [0, 63] {
            let caught = std::panic::catch_unwind(AssertUnwindSafe(|| {
                share(Some(&pool), 64, 1, |i| {
                    std::thread::sleep(Duration::from_micros(200));
                    assert_ne!(i, bad, "item {i}");
                })
            }));
            assert!(caught.is_err(), "item {bad}'s panic");
        }
        assert_eq!(share(Some(&pool), 3, 1, |i| i), [0, 1, 2]);
    }

    #[test]
    fn each_thread_keeps_its_own_clock() {
        let before = spent();
        std::thread::scope(|s| _ = s.spawn(|| pass(nap)).join());
        assert_eq!(spent(), before);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(16))]
        /// A copy is its source, on a pool or not, into memory of any length before: the same
        /// memory where it held enough.
        #[test]
        fn a_copy_is_its_source_into_any_memory(len in 0usize..3 * SPREAD_FROM, before in 0usize..3 * SPREAD_FROM, seed: u32) {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
            let from: Vec<u32> = (0..len as u32).map(|i| i.wrapping_mul(2_654_435_761) ^ seed).collect();
            for pool in [None, Some(&pool)] {
                let mut into = vec![7u32; before];
                let (at, room) = (into.as_ptr(), into.capacity());
                copy(pool, &mut into, &from);
                proptest::prop_assert_eq!(&into, &from);
                if room >= len {
                    proptest::prop_assert_eq!(into.as_ptr(), at);
                }
                proptest::prop_assert_eq!(copied(pool, &from), from.clone());
            }
        }
    }
}
