//! How the run hands states to the checker: inline, or on a second thread that judges checkpoint
//! k while the kernel steps towards k + 1. Both give the same report, bit for bit: the kernel
//! never passes checkpoint k + 1 before checkpoint k is judged, and a breach at k reports the
//! state at k, however far the kernel got. Overlapped, the checker is also handed a state a few
//! steps before the last checkpoint, to list that checkpoint's pairs ahead (`Monitor::foresee`):
//! the last checkpoint is the one nothing overlaps, and the list changes no bit of its verdict.

use lagra_checker::claims::Claim;
use lagra_checker::model::Model;
use lagra_checker::monitor::{is_balance, next_checkpoint, Halt, Monitor};
use lagra_checker::quantities::Parts;
use lagra_kernel::spread;
use lagra_kernel::state::State;
use rayon::ThreadPool;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::{Scope, ScopedJoinHandle};

/// From this many bodies a checkpoint costs enough to be worth a thread: judging takes 4–6 µs a
/// body (lj_liquid's 256 atoms 1.3 ms, lj_nvt's 500 2.0 ms, stack_1000's solids 5.5 ms), so
/// about 2.5 ms here, where the hand-over (a copy of the state, a wake) was not seen on one CPU
/// against the run's noise. From 1,024 before: the stack's 1,000 blocks then waited for every
/// checkpoint, 2.5% of its two-thread run.
const OVERLAP_FROM: usize = 512;

/// Whether a run may check on a second thread: a big scene whose checker looks only at its
/// checkpoints (an energy balance integrates over every step), and nothing else that sees the
/// states past a breach before it is known (a trace, a state file, the predictions' meters).
pub fn can_overlap(model: &Model, claims: &[Claim], watched: bool) -> bool {
    !watched && model.bodies.len() >= OVERLAP_FROM && !is_balance(model, claims)
}

/// A breach, with the state it was found at.
pub type Breach = (Halt, State);

pub enum Checking<'s> {
    Inline(Monitor),
    Overlapped(Overlap<'s>),
}

/// What the checker thread is handed.
enum Handed {
    /// A checkpoint, to judge, and in domains the ranks' parts of it.
    Checkpoint(State, Option<Parts>),
    /// A state before the last checkpoint, to list its pairs from.
    Ahead(State),
}

pub struct Overlap<'s> {
    states: SyncSender<Handed>,
    verdicts: Receiver<Result<(), Breach>>,
    /// A checkpoint handed over whose verdict has not been read.
    pending: bool,
    /// The cadences of the dynamic claims: the checker looks at their multiples, step 0 and the
    /// last step, and returns at once from any other state.
    every: Vec<u64>,
    last: u64,
    /// The step of the state handed ahead of the last checkpoint, if any.
    ahead: Option<u64>,
    /// The kernel's threads, which copy a large state handed over.
    pool: Option<&'s ThreadPool>,
    /// The monitor, and the CPU seconds the thread spent judging and listing ahead.
    thread: ScopedJoinHandle<'s, (Monitor, f64)>,
}

/// A copy of `s` for the checker thread, a large state's positions and velocities copied on
/// the kernel's threads (at 1,000,000 bodies, 48 MB of fresh memory at every checkpoint).
fn copied(s: &State, pool: Option<&ThreadPool>) -> State {
    let (x, v) = (spread::copied(pool, &s.x), spread::copied(pool, &s.v));
    State { step: s.step, t: s.t, x, v, chain: s.chain.clone(), spin: s.spin.clone() }
}

impl<'s> Checking<'s> {
    /// The monitor on a second thread of `scope`, judging the states due for `claims`.
    pub fn overlapped<'e>(
        scope: &'s Scope<'s, 'e>,
        mut monitor: Monitor,
        claims: &[Claim],
        last: u64,
        pool: Option<&'s ThreadPool>,
    ) -> Self {
        let every = claims.iter().filter(|c| c.kind.is_dynamic()).map(|c| c.every).collect();
        let cpus = monitor.threads();
        // the list made ahead saves the last checkpoint its grid only if another CPU builds it
        // while the kernel steps; on one CPU it would cost the kernel what it saves and more
        let ahead = monitor.foresight().filter(|_| cpus > 1).and_then(|k| last.checked_sub(k));
        let (states, inbox) = sync_channel::<Handed>(1);
        let (outbox, verdicts) = sync_channel(1);
        let thread = scope.spawn(move || {
            let mut busy = 0.0;
            for handed in inbox {
                // CPU time (on one CPU the thread shares it with the kernel's), but wall time
                // where the work spreads over every CPU: this thread's CPU time would miss its
                // helpers'
                let started = (cpu_time::ThreadTime::now(), std::time::Instant::now());
                let took = |threads: usize| match threads {
                    1 => started.0.elapsed().as_secs_f64(),
                    _ => started.1.elapsed().as_secs_f64(),
                };
                let verdict = match handed {
                    Handed::Ahead(s) => {
                        // every CPU: at many threads the kernel's FORESIGHT steps are over
                        // before one thread would have listed 256,000 bodies (~0.2 s)
                        monitor.set_threads(cpus);
                        monitor.foresee(&s.snapshot());
                        busy += took(cpus);
                        continue;
                    }
                    Handed::Checkpoint(s, parts) => {
                        // one thread while the kernel steps on; every CPU for the last
                        // checkpoint, which nothing else overlaps
                        let threads = if s.step == last { cpus } else { 1 };
                        monitor.set_threads(threads);
                        let verdict = monitor.observe_with(&s.snapshot(), parts.as_ref()).map_err(|h| (h, s));
                        busy += took(threads);
                        verdict
                    }
                };
                if outbox.send(verdict).is_err() {
                    break;
                }
            }
            (monitor, busy)
        });
        Checking::Overlapped(Overlap { states, verdicts, pending: false, every, last, ahead, pool, thread })
    }

    /// Shows the checker a state, and in domains the ranks' parts of it (`Monitor::observe_with`).
    /// Inline, the answer is about this state; overlapped, it is about the checkpoint before,
    /// and a breach comes with that checkpoint's state.
    pub fn show(&mut self, s: &State, parts: Option<Parts>) -> Result<(), Breach> {
        match self {
            Checking::Inline(m) => m.observe_with(&s.snapshot(), parts.as_ref()).map_err(|h| (h, s.clone())),
            Checking::Overlapped(o) if s.step == 0 || o.next_checkpoint(s.step - 1) == s.step => {
                o.settle()?;
                o.hand(Handed::Checkpoint(copied(s, o.pool), parts));
                o.pending = true;
                Ok(())
            }
            Checking::Overlapped(o) if o.ahead == Some(s.step) => {
                o.hand(Handed::Ahead(copied(s, o.pool)));
                Ok(())
            }
            Checking::Overlapped(_) => Ok(()),
        }
    }

    /// The first step after `after` the checker needs to see (`u64::MAX`: none); the kernel may
    /// step through the ones in between without showing them.
    pub fn next_due(&self, after: u64) -> u64 {
        match self {
            Checking::Inline(m) => m.next_due(after),
            Checking::Overlapped(o) => {
                let due = o.next_checkpoint(after);
                match o.ahead {
                    Some(h) if due == o.last && after < h && h < due => h,
                    _ => due,
                }
            }
        }
    }

    /// Waits for the verdict of the checkpoint handed over last, if any.
    pub fn settle(&mut self) -> Result<(), Breach> {
        match self {
            Checking::Inline(_) => Ok(()),
            Checking::Overlapped(o) => o.settle(),
        }
    }

    /// What the monitor carries to the next checkpoint (a restart's), from a monitor on the
    /// kernel's thread: a run that writes restarts on its way judges inline.
    pub fn carried(&self) -> Result<lagra_checker::monitor::Carried, String> {
        match self {
            Checking::Inline(m) => m.carried(),
            Checking::Overlapped(_) => Err("the checker is on another thread".into()),
        }
    }

    /// The monitor, every verdict read, and overlapped, the CPU seconds the second thread spent
    /// judging (inline, that is the time `show` took).
    pub fn into_monitor(self) -> (Monitor, Option<f64>) {
        match self {
            Checking::Inline(m) => (m, None),
            Checking::Overlapped(o) => {
                drop(o.states);
                drop(o.verdicts);
                let (m, busy) = o.thread.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                (m, Some(busy))
            }
        }
    }
}

impl Overlap<'_> {
    fn next_checkpoint(&self, after: u64) -> u64 {
        self.every.iter().map(|&e| next_checkpoint(e, self.last, after)).min().unwrap_or(u64::MAX)
    }

    fn hand(&self, h: Handed) {
        self.states.send(h).expect("the checker thread takes states until the run ends");
    }

    fn settle(&mut self) -> Result<(), Breach> {
        if !std::mem::take(&mut self.pending) {
            return Ok(());
        }
        self.verdicts.recv().expect("the checker thread answers every state it is handed")
    }
}

#[cfg(test)]
mod tests {
    use crate::compile;
    use crate::run::{run, Options, Report, Stop};

    /// 1,372 LJ atoms, energy and momentum checked every 10 steps; `tol` decides whether the
    /// energy claim breaks part-way.
    fn melt(tol: f64) -> lagra_lang::scene::Scene {
        melt_every(tol, 10)
    }

    fn melt_every(tol: f64, every: u64) -> lagra_lang::scene::Scene {
        compile(&format!(
            "scene m {{ entity atom {{ mass: 1 }}
               lattice {{ type: atom, density: 0.8442, cells: [7, 7, 7], temperature: 1.44, seed: 3 }}
               interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
               @expect energy_conservation {{ tol: {tol}, every: {every} }}
               @expect momentum_conservation {{ every: {every} }}
               solver {{ dt: 0.005, steps: 60 }} }}"
        ))
        .unwrap()
    }

    /// A run with a trace cannot overlap (the trace would show states past a breach): the
    /// reference, inline.
    fn both(scene: &lagra_lang::scene::Scene) -> (Report, Report) {
        let overlapped = run(scene, Options::plain(None)).unwrap();
        let mut sink = crate::trace::Recorded::default();
        let inline = run(scene, Options { trace: Some(&mut sink), ..Options::plain(None) }).unwrap();
        assert!(overlapped.checker.starts_with("on a second thread") && inline.checker.starts_with("inline"));
        (overlapped, inline)
    }

    fn same(a: &Report, b: &Report) {
        assert_eq!((a.steps, &a.stop), (b.steps, &b.stop));
        assert_eq!(a.state.step, b.state.step);
        let bits = |r: &Report| {
            let (x, v, spin) = (&r.state.x, &r.state.v, &r.state.spin);
            x.iter().chain(v).flatten().chain(spin.iter().flatten()).map(|c| c.to_bits()).collect::<Vec<_>>()
        };
        assert!(bits(a) == bits(b));
        assert_eq!(format!("{:?}", a.outcome.verdicts), format!("{:?}", b.outcome.verdicts));
        let trails = |r: &Report| serde_json::to_string(&r.outcome.trails).unwrap();
        assert_eq!(trails(a), trails(b));
    }

    /// `n` unit blocks in towers of eight, a hair apart, on a floor; no overlap checked every 5 of
    /// 20 steps.
    fn towers(n: usize) -> lagra_lang::scene::Scene {
        let blocks: String = (0..n)
            .map(|i| {
                let (t, level) = (i / 8, i % 8);
                let (x, y, z) = ((t % 8) as f64 * 1.5, 0.5 + level as f64 * 1.001, (t / 8) as f64 * 1.5);
                format!("entity {{ shape: box, size: [1, 1, 1], mass: 1, position: [{x}, {y}, {z}] }}\n")
            })
            .collect();
        compile(&format!(
            "scene towers {{ uses newtonian.rigid_bodies
               {blocks} gravity {{ g: [0, -9.81, 0] }} floor {{ y: 0, friction: 0.6 }}
               @expect no_penetration {{ tol: 1e-3, every: 5 }}
               solver {{ dt: 0.005, steps: 20 }} }}"
        ))
        .unwrap()
    }

    /// Solids count as atoms do: from 512 blocks a run checks alongside the kernel and ends as
    /// the inline run does, orientations included, bit for bit; 511 check inline.
    #[test]
    fn from_512_blocks_a_stack_is_checked_alongside() {
        let (a, b) = both(&towers(512));
        assert!(a.stop.is_none() && a.steps == 20, "{:?}", a.stop);
        same(&a, &b);
        let r = run(&towers(511), Options::plain(None)).unwrap();
        assert!(r.checker.starts_with("inline"), "{}", r.checker);
    }

    #[test]
    fn overlapped_checking_reports_what_inline_checking_does() {
        let (a, b) = both(&melt(1e-3));
        assert!(a.stop.is_none() && a.steps == 60);
        same(&a, &b);
    }

    /// Overlapped on two CPUs, the kernel also stops `FORESIGHT` steps before the last
    /// checkpoint (not before the others) to hand the checker a state to list that checkpoint's
    /// pairs from; on one it does not. The run ends as the inline one does, bit for bit.
    #[test]
    fn the_last_checkpoint_is_listed_ahead_and_changes_nothing() {
        use super::Checking;
        use lagra_checker::broad_phase::FORESIGHT;
        use lagra_checker::monitor::Monitor;
        let scene = melt_every(1e-3, 20);
        let ahead = 60 - FORESIGHT;
        assert!(ahead > 40);
        for (cpus, stops) in [(2, vec![20, 40, ahead, 60]), (1, vec![20, 40, 60])] {
            std::thread::scope(|scope| {
                let mut monitor = Monitor::new(scene.model.clone(), scene.claims.clone(), 60).unwrap();
                monitor.set_threads(cpus);
                let c = Checking::overlapped(scope, monitor, &scene.claims, 60, None);
                let due: Vec<u64> =
                    std::iter::successors(Some(0), |&s| Some(c.next_due(s)).filter(|_| s < 60)).collect();
                assert_eq!(due[1..], stops, "{cpus} CPUs");
                c.into_monitor().0;
            });
        }
        let (a, b) = both(&scene);
        assert!(a.stop.is_none() && a.steps == 60);
        same(&a, &b);
    }

    /// A breach at checkpoint k halts at k with k's state, though the kernel went on to k + 10.
    #[test]
    fn a_breach_found_on_the_second_thread_halts_at_its_own_step() {
        let (a, b) = both(&melt(1e-9));
        assert!(matches!(a.stop, Some(Stop::Checker(_))) && a.steps < 60 && a.steps % 10 == 0, "{:?}", a.stop);
        same(&a, &b);
    }

    /// A run with a progress report, and the steps it was called at.
    fn with_progress(scene: &lagra_lang::scene::Scene) -> (Report, Vec<u64>) {
        let mut reached = vec![];
        let mut tick = |step: u64| reached.push(step);
        let r = run(scene, Options { progress: Some(&mut tick), ..Options::plain(None) });
        (r.unwrap(), reached)
    }

    /// Shown every state (as when they are recorded) or only its checkpoints (the solver then
    /// steps straight from one to the next), a run ends the same: a pass, a certified breach,
    /// and an instability past the stability limit, found at the same step.
    #[test]
    fn stepping_straight_to_the_checkpoints_changes_nothing() {
        // ωdt = 0.11, and 3.2: past Verlet's limit of 2, where the force overflows long before
        // the claims' only checkpoint at the end
        for (tol, dt, every, ends) in [
            (1e-2, 0.05, 7, "None"),
            (1e-5, 0.05, 7, "Some(Checker(Breach"),
            (1.0, 1.5, 1000, "Some(Solver { step: 172"),
        ] {
            let scene = compile(&format!(
                "scene s {{ entity {{ position: [0, 0, 0], mass: 1 }} entity {{ position: [1.3, 0.1, 0], mass: 2 }}
                   bond harmonic [0, 1] {{ k: 3, r0: 1 }}
                   @expect energy_conservation {{ tol: {tol}, every: {every} }}
                   @expect momentum_conservation {{ every: {every} }}
                   solver {{ dt: {dt}, steps: 400 }} }}"
            ))
            .unwrap();
            let straight = run(&scene, Options::plain(None)).unwrap();
            let mut shown = 0;
            let mut each = |_: &lagra_checker::model::Snapshot| -> std::io::Result<()> {
                shown += 1;
                Ok(())
            };
            let every = run(&scene, Options { record: Some(&mut each), ..Options::plain(None) }).unwrap();
            same(&straight, &every);
            assert_eq!(shown, every.steps + 1);
            assert!(format!("{:?}", every.stop).starts_with(ends), "{:?}", every.stop);
            // a progress report stops the solver too (for two bodies, every 2¹⁹ steps: here
            // only at the checkpoints and the end), and changes nothing either
            let (watched, reached) = with_progress(&scene);
            same(&straight, &watched);
            assert!(
                reached.windows(2).all(|w| w[0] < w[1]) && reached.last() == Some(&watched.steps)
                    || matches!(watched.stop, Some(Stop::Solver { .. })),
                "{reached:?}"
            );
        }
    }

    /// A watch sees the state every N steps, and the run ends with the bits it has without it.
    #[test]
    fn a_watch_sees_every_nth_state_and_changes_nothing() {
        let scene = melt(1e-2);
        let plain = run(&scene, Options::plain(None)).unwrap();
        let mut seen = vec![];
        let mut see = |s: &lagra_kernel::state::State| seen.push((s.step, s.x[7]));
        let watch = Some(crate::run::Watch { every: 7, see: &mut see });
        let watched = run(&scene, Options { watch, ..Options::plain(None) }).unwrap();
        same(&plain, &watched);
        let steps: Vec<u64> = seen.iter().map(|s| s.0).collect();
        assert_eq!(steps, (1..=plain.steps / 7).map(|k| 7 * k).collect::<Vec<_>>());
    }

    /// A pool handed to the run (the compile's) is the one it runs on where it has the threads
    /// asked for, and is left alone where it has not; the bits are the same either way.
    #[test]
    fn a_run_takes_a_pool_of_its_thread_count_and_no_other() {
        let scene = melt(1e-2);
        let plain = run(&scene, Options::plain(None)).unwrap();
        let pool = lagra_kernel::graph::threads_of(3).unwrap().unwrap();
        // (the graph and its groups each hold it while they run on it)
        for (threads, used) in [(3, true), (2, false)] {
            let mut holders = vec![];
            let mut see = |_: &lagra_kernel::state::State| holders.push(std::sync::Arc::strong_count(&pool));
            let watch = Some(crate::run::Watch { every: 50, see: &mut see });
            let on = run(&scene, Options { threads, pool: Some(pool.clone()), watch, ..Options::plain(None) }).unwrap();
            same(&plain, &on);
            assert!(!holders.is_empty() && holders.iter().all(|&h| (h > 1) == used), "{threads} threads: {holders:?}");
        }
        assert_eq!(std::sync::Arc::strong_count(&pool), 1, "the run let go of it");
    }

    /// Progress stops a two-body run every 2¹⁹ steps (a million atom-steps), and the run ends
    /// with the bits it has without it.
    #[test]
    fn progress_reports_every_million_atom_steps() {
        let scene = compile(
            "scene s { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.3, 0.1, 0], mass: 2 }
               bond harmonic [0, 1] { k: 3, r0: 1 } solver { dt: 0.01, steps: 1200000 } }",
        )
        .unwrap();
        let plain = run(&scene, Options::plain(None)).unwrap();
        let (watched, reached) = with_progress(&scene);
        same(&plain, &watched);
        assert_eq!(reached, [1 << 19, 1 << 20, 1_200_000]);
    }

    /// Past 65,536 bodies a million atom-steps is fewer than 16 steps: progress stops every 16
    /// (`FEWEST_STEPS_A_STOP`), and the run ends with the bits it has without it.
    #[test]
    fn progress_stops_no_more_often_than_every_sixteen_steps() {
        let scene = compile(
            "scene s { entity atom { mass: 1 } lattice { type: atom, kind: sc, density: 1, cells: [51, 51, 51], temperature: 1, seed: 3 }
               solver { dt: 0.01, steps: 40 } }",
        )
        .unwrap();
        assert!(scene.x0.len() > 1 << 17, "{} bodies: a million atom-steps is under 8 steps", scene.x0.len());
        let plain = run(&scene, Options::plain(None)).unwrap();
        let (watched, reached) = with_progress(&scene);
        same(&plain, &watched);
        assert_eq!(reached, [16, 32, 40]);
    }
}
