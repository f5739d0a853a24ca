//! The run loop: step the solver, hand every checkpoint's exact state to the checker, measure
//! the predictions, write the trace. A certified failure, a singular force or a non-finite
//! state halts the run at that step.

use crate::checking::{can_overlap, Checking};
use crate::domains::{Asks, EnergyAndVirial, Reached, Shared};
use crate::observables::{Observables, Observer};
use crate::predict::Meter;
use crate::restart::{setup_of, Restart};
use crate::trace::Frames;
use lagra_checker::claims::ClaimKind;
use lagra_checker::model::Snapshot;
use lagra_checker::monitor::{Halt, MarkSink, Monitor, Outcome};
use lagra_checker::terms::Kind;
use lagra_kernel::forces::Pool;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::{Carried, Evaluated, Iterations, Stepper};
use lagra_kernel::state::{kinetic, State};
use lagra_lang::prediction::Prediction;
use lagra_lang::scene::Scene;
use serde::Serialize;
use std::time::Instant;

/// Why a run stopped before its last step.
#[derive(Debug, Clone, PartialEq)]
pub enum Stop {
    /// The checker certified that a claim is violated (or could not evaluate the state).
    Checker(Halt),
    /// The solver could not take this step: a force is undefined there, or an iteration inside
    /// the step (constraints, an action window) did not reach its tolerance.
    Solver { step: u64, message: String },
    /// The caller asked the run to stop (`Options::stop`), here.
    Cancelled { step: u64 },
    /// The run reached the step it was asked to stop at (`Options::until`), before its end.
    Until { step: u64 },
}

#[derive(Debug, Clone, Serialize)]
pub struct Measured {
    pub name: &'static str,
    pub predicted: Option<f64>,
    pub measured: Option<f64>,
    pub rel_diff: Option<f64>,
    pub tol: Option<f64>,
    /// Within `tol` (true when no tol was given and a period was measured).
    pub agrees: bool,
    /// What a statistical test saw.
    pub detail: Option<String>,
}

pub struct Report {
    /// The run length asked for, and the steps taken (fewer if the run halted).
    pub planned_steps: u64,
    pub steps: u64,
    pub wall_s: f64,
    /// The time the checker spent judging the states (and listing pairs ahead), on the kernel's
    /// thread (inline) or on its own (its CPU time there, but the wall time of a checkpoint
    /// spread over every CPU): on one CPU, what it adds to the run.
    pub checker_s: f64,
    /// Of `wall_s`, the time the kernel's thread spent on the checker: judging inline, or waiting
    /// for a verdict the second thread had not reached: on two CPUs, what it adds to the run
    /// (with what sharing the machine's caches costs the kernel's steps).
    pub checker_wait_s: f64,
    /// Of `wall_s`, the time the kernel's thread spent outside every pass that spreads over
    /// threads (`lagra_kernel::spread`) and outside the checker: Amdahl's serial part, measured.
    pub serial_s: f64,
    pub stop: Option<Stop>,
    pub outcome: Outcome,
    pub predictions: Vec<Measured>,
    pub state: State,
    /// How each term group visited its bodies (with the neighbour-list builds, after the run).
    pub plan: Vec<(Kind, String)>,
    /// Where the checker ran: inline, or on a second thread overlapping the kernel.
    pub checker: &'static str,
    /// How the iterations inside the solver's steps went (RATTLE, action descent).
    pub iterations: Option<Iterations>,
    /// How the solver spread its steps over the threads, where it chose (AVBD's islands).
    pub solver_plan: Option<String>,
    /// The averages after `equilibrate` (a thermostatted scene, or one that asked).
    pub observables: Option<Observables>,
    /// The step the run started from: 0, or a restart's.
    pub first_step: u64,
    /// Where it was asked for (`Options::restarts`), what goes on from the state reached, or
    /// why the run cannot go on from there (it halted; its solver cannot be cut).
    pub restart: Option<Result<Restart, String>>,
}

/// Keeps the states a run produces (the state file's writer).
pub type Recorder<'a> = &'a mut dyn FnMut(&Snapshot) -> std::io::Result<()>;

pub struct Options<'a> {
    /// Overrides the scene's run length.
    pub steps: Option<u64>,
    /// Every frame (`steps_per_frame`), in a format (`trace::Writer`) or in memory.
    pub trace: Option<&'a mut dyn Frames>,
    /// Called with every state the checker is shown (step 0 included), to keep them.
    pub record: Option<Recorder<'a>>,
    /// Threads for the forces (the results are the same bits for any count).
    pub threads: usize,
    /// A pool of `threads` threads already started (the compile's, for a large lattice), to run
    /// on in place of one of the run's own.
    pub pool: Pool,
    /// Called with the step reached about every million atom-steps (every `FEWEST_STEPS_A_STOP`
    /// steps or more: `stride`), for a progress line (the run's results are the same with or
    /// without it).
    pub progress: Option<&'a mut dyn FnMut(u64)>,
    /// Read as often as `progress` is called: once set, the run stops there (`Stop::Cancelled`),
    /// with the claims judged up to the state reached.
    pub stop: Option<&'a std::sync::atomic::AtomicBool>,
    /// Shown the state every so many steps (a notebook's live plot); the run is the same bits.
    pub watch: Option<Watch<'a>>,
    /// Where the checker's marks go (`crate::marks`); without it the outcome's trails hold
    /// them all, in memory, which grows with the run.
    pub marks: Option<MarkSink>,
    /// Where the run starts from: a restart file's, in place of the scene's initial state.
    pub resume: Option<Restart>,
    /// Stops the run at this step (`Stop::Until`) if it comes before the end.
    pub until: Option<u64>,
    /// What goes on from the state reached is made at the end of the run (`Report::restart`),
    /// and every so many steps on the way, handed to the writer.
    pub restarts: Option<Restarts<'a>>,
    /// The ranks of a job that step the scene in domains (`crate::domains`), rank 0's run loop
    /// driving them; `None`: this process steps it alone.
    pub shared: Option<&'a mut dyn Shared>,
}

/// Restart files made along a run, besides the one at its end.
pub struct Restarts<'a> {
    /// Every this many steps (never: `u64::MAX`); the checker then judges on the kernel's thread.
    pub every: u64,
    pub write: &'a mut dyn FnMut(Restart) -> Result<(), String>,
}

impl Options<'_> {
    /// A run of `steps` (the scene's if `None`) on one thread, with nothing attached.
    pub fn plain(steps: Option<u64>) -> Self {
        Options {
            steps,
            trace: None,
            record: None,
            threads: 1,
            pool: None,
            progress: None,
            stop: None,
            watch: None,
            marks: None,
            resume: None,
            until: None,
            restarts: None,
            shared: None,
        }
    }
}
/// A look at the state every `every` steps.
pub struct Watch<'a> {
    pub every: u64,
    pub see: &'a mut dyn FnMut(&State),
}

/// The most threads a run may ask for: past this a pool is only oversubscribed.
pub const MOST_THREADS: usize = 1024;

/// Bodies from which a run without `--threads` uses every core: below, one thread is as fast
/// (the pieces of `lagra_kernel::pieces` pay from tens of thousands of bodies).
pub const AUTO_FROM: usize = 16_384;

/// The threads a run uses: `asked`, checked, or by default the physical cores this process may
/// use for a scene of `AUTO_FROM` bodies or more, one below. Any count gives the same bits.
pub fn threads_for(bodies: usize, asked: Option<usize>) -> Result<usize, String> {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    match asked {
        Some(0) => Err("--threads must be at least 1".into()),
        Some(n) if n > MOST_THREADS => {
            Err(format!("--threads {n} is more than the {MOST_THREADS} a run may use (this machine has {cpus} CPUs)"))
        }
        Some(n) => Ok(n),
        None if bodies >= AUTO_FROM => Ok(num_cpus::get_physical().clamp(1, cpus)),
        None => Ok(1),
    }
}

/// Steps between the stops a watched run (progress, a stop flag) makes: about a million
/// atom-steps, and never fewer than `FEWEST_STEPS_A_STOP`.
fn stride(bodies: usize) -> u64 {
    ((1u64 << 20) / bodies.max(1) as u64).max(FEWEST_STEPS_A_STOP)
}

/// The fewest steps between a watched run's stops. Each stop ends the solver's stride with a
/// force evaluation that computes the energy too (13% more than the forces alone for the LJ
/// kernel): a million atom-steps was every 4 steps at 256,000 atoms (~1.5% of the run, within
/// its noise) and every step from 1,048,576 (48 steps of that many on two threads took
/// 5.75–5.86 s, 5.52–5.58 s with a stop every 16). Sixteen steps of a million atoms are a few
/// seconds on one thread, a fraction of one on sixteen: a stop flag (Ctrl-C, SIGTERM) is still
/// seen soon.
const FEWEST_STEPS_A_STOP: u64 = 16;

/// Runs a scene. Errors are setup errors (a model the checker rejects, trace I/O).
pub fn run(scene: &Scene, mut opts: Options) -> Result<Report, String> {
    let steps = opts.steps.unwrap_or(scene.solver.steps);
    let dt = scene.solver.dt;
    let graph = match opts.pool.take().filter(|p| p.current_num_threads() == opts.threads) {
        Some(pool) => LagrangianGraph::with_pool(&scene.model, Some(pool)),
        None => LagrangianGraph::with_threads(&scene.model, opts.threads)?,
    };
    let (model, claims) = (scene.model.clone(), scene.claims.clone());
    // a restart's state and everything carried with it, or the scene's start
    let (mut state, mut monitor, mut observer, mut meters, carried) = match opts.resume.take() {
        None => {
            let meters: Vec<(Meter, &Prediction)> =
                scene.predictions.iter().map(|p| (Meter::new(p, &scene.model, &scene.x0, scene.bath()), p)).collect();
            let observer = Observer::new(scene, &graph, steps)?;
            (
                lagra_kernel::setup::start_on(scene, graph.pool()),
                Monitor::new(model, claims, steps)?,
                observer,
                meters,
                None,
            )
        }
        Some(r) => {
            let fits = |e: String| format!("the restart does not fit this scene: {e}");
            scene.model.check_state(&r.state.snapshot()).map_err(fits)?;
            if r.meters.len() != scene.predictions.len() || r.observer.is_some() != scene.sampling.is_some() {
                return Err(fits("it measures other predictions or observables".into()));
            }
            if r.setup != setup_of(scene) {
                return Err(fits(
                    "it was made with another model, claims, integrator or time step (--set, --dt)".into(),
                ));
            }
            if r.state.step > steps {
                return Err(format!("the restart is at step {}, past the run's end at step {steps}", r.state.step));
            }
            graph.build_lists_at(&r.lists).map_err(fits)?;
            let monitor = Monitor::resumed(model, claims, steps, r.monitor).map_err(fits)?;
            (r.state, monitor, r.observer, r.meters.into_iter().zip(&scene.predictions).collect(), Some(r.solver))
        }
    };
    if let Some(sink) = opts.marks.take() {
        monitor.hand_marks_to(sink);
    }
    let first_step = state.step;
    if let Some(u) = opts.until.filter(|&u| u < first_step) {
        return Err(format!("--until {u} is before the step the run resumes from, {first_step}"));
    }
    let end = opts.until.map_or(steps, |u| u.min(steps));
    let mut restarts = opts.restarts.take();
    let mut shared = opts.shared.take();
    if shared.is_some() && !meters.is_empty() {
        return Err("a run in domains measures no prediction".into());
    }
    // What goes on from the state reached. In domains rank 0 has the state, not its forces: they
    // are evaluated whole here, as a run in one process stopped there would have them, so that
    // a restart made on some ranks resumes on any number, or in one process.
    let in_domains = shared.is_some();
    // in domains the ranks enclose their parts of the energy and momentum at their checkpoints
    let additive = |k: ClaimKind| matches!(k, ClaimKind::EnergyConservation | ClaimKind::MomentumConservation);
    let in_parts = in_domains && scene.claims.iter().any(|c| additive(c.kind));
    let solver_carries = |solver: &Stepper, s: &State| match in_domains {
        true => Evaluated::at(&graph, s).map(|at| Carried::forces(&at)).map_err(|e| e.to_string()),
        false => solver.carried(),
    };
    let every_restart = restarts.as_ref().map_or(u64::MAX, |r| r.every.max(1));
    let tracing = opts.trace.is_some();
    // (a restart made on the way takes the monitor from the kernel's thread)
    let watched = tracing || opts.record.is_some() || !meters.is_empty() || every_restart != u64::MAX;
    let overlap = can_overlap(&scene.model, &scene.claims, watched);

    let (start, spread_before) = (Instant::now(), lagra_kernel::spread::spent());
    let mut stop: Option<Stop> = None;
    let mut trace = |s: &State, potential: f64| -> Result<(), String> {
        if let Some(w) = opts.trace.as_mut() {
            // H, or with a thermostat chain the H′ the checker certifies
            let chain = scene.model.thermostat.as_ref().map_or(0.0, |c| c.energy(&s.chain, &0.0));
            let energy = kinetic(s, &graph.masses) + potential + chain;
            w.frame(s, energy).map_err(|e| format!("writing the trace: {e}"))?;
        }
        Ok(())
    };
    // Every state the run produces is recorded and shown to the checker, in order; a breach
    // (found at this state, or, overlapped, at the checkpoint before) replaces the run's state.
    let mut record = opts.record.take();
    // the states a meter or the state file sees are every state; a trace sees the frames, the
    // checker its checkpoints: the solver steps straight to the next of them
    let every_step = record.is_some() || !meters.is_empty();
    let mut progress = opts.progress.take();
    let mut watch = opts.watch.take();
    let cancel = opts.stop;
    let watched_often = progress.is_some() || cancel.is_some();
    let stride = if watched_often { stride(scene.x0.len()) } else { u64::MAX };
    // the kernel's thread's time on the checker, added up by `check` and the last settle
    let waited = std::cell::Cell::new(0.0);
    let judged = |since: Instant| waited.set(waited.get() + since.elapsed().as_secs_f64());
    // (a resumed run's first state was judged by the run that wrote the restart: recorded only)
    let mut check = |checking: &mut Checking, s: &mut State, judge: bool, parts| -> Result<Option<Stop>, String> {
        if let Some(r) = record.as_mut() {
            r(&s.snapshot()).map_err(|e| format!("writing the states: {e}"))?;
        }
        if !judge {
            return Ok(None);
        }
        let judging = Instant::now();
        let shown = checking.show(s, parts);
        judged(judging);
        Ok(shown.err().map(|(halt, at)| {
            *s = at;
            Stop::Checker(halt)
        }))
    };
    // The checker's own test of a state (sizes, finiteness), for when no claim looks at it.
    let non_finite =
        |s: &State| scene.model.check_state(&s.snapshot()).err().map(|e| Stop::Checker(Halt::InvalidState(e)));
    let mut iterations = None;
    let mut solver_plan = None;
    let mut solver_carried = Err("the solver could not start".to_string());
    let (monitor, busy) = std::thread::scope(|scope| -> Result<(Monitor, Option<f64>), String> {
        let mut checking = if overlap {
            Checking::overlapped(scope, monitor, &scene.claims, steps, graph.pool())
        } else {
            Checking::Inline(monitor)
        };
        // in domains the ranks evaluated the first state's forces; rank 0's solver steps nothing
        let stepper = match shared {
            Some(_) => Ok(Stepper::resume_verlet(Evaluated { f: vec![], potential: f64::NAN })),
            None => Stepper::for_scene(scene, &graph, &state),
        };
        match stepper {
            Err(e) => stop = Some(Stop::Solver { step: 0, message: e.to_string() }),
            Ok(mut solver) => {
                // in domains rank 0 gathers a state, not its sums: the ranks measure the potential
                // energy and virial where a frame or a sample needs them (`EnergyAndVirial`)
                let frame = scene.solver.steps_per_frame.max(1);
                let framed = |step: u64| tracing && (step.is_multiple_of(frame) || step == steps);
                let potential = |m: Option<EnergyAndVirial>, solver: &Stepper| {
                    m.map_or_else(|| solver.potential(), |m| m.potential)
                };
                let sample = |o: &mut Option<Observer>, s: &State, potential: f64, m: Option<EnergyAndVirial>| match o
                    .as_mut()
                    .filter(|o| o.due(s.step))
                {
                    Some(o) => o.observe(&graph, s, potential, m.map(|m| m.virial)),
                    None => Ok(()),
                };
                let sampled_at_start = carried.is_none() && observer.as_ref().is_some_and(|o| o.due(state.step));
                let here = state.step;
                // (the first state's parts are the reference of energy and momentum)
                let asks = Asks { measure: tracing || sampled_at_start, enclose: in_parts && carried.is_none() };
                let (at_start, start_parts) = match shared.as_mut() {
                    Some(d) if asks != Asks::default() => {
                        let r = d.advance_to(&mut state, here, asks)?;
                        (r.measured, r.parts)
                    }
                    _ => (None, None),
                };
                match &carried {
                    Some(c) => {
                        // (in domains the ranks evaluated the restart's state afresh)
                        if shared.is_none() {
                            solver.take_up(c, &graph).map_err(|e| format!("the restart: {e}"))?;
                        }
                        check(&mut checking, &mut state, false, None)?;
                    }
                    None => {
                        stop = check(&mut checking, &mut state, true, start_parts)?;
                        meters.iter_mut().for_each(|(m, _)| m.observe(state.t, &state.x, &state.v, solver.forces()));
                        sample(&mut observer, &state, potential(at_start, &solver), at_start)?;
                    }
                }
                if tracing {
                    trace(&state, potential(at_start, &solver))?;
                }
                let next = |every: u64, step: u64| (step / every).saturating_add(1).saturating_mul(every);
                while stop.is_none() && state.step < end {
                    let next_frame = if tracing { next(frame, state.step) } else { u64::MAX };
                    let next_look = watch.as_ref().map_or(u64::MAX, |w| next(w.every.max(1), state.step));
                    let until = if every_step {
                        state.step + 1
                    } else {
                        let sampled = observer.as_ref().map_or(u64::MAX, |o| o.next_due(state.step));
                        let due = checking.next_due(state.step).min(next_frame).min(next_look);
                        due.min(next(stride, state.step)).min(sampled).min(next(every_restart, state.step))
                    };
                    let to = until.min(end);
                    let advanced = match shared.as_mut() {
                        Some(d) => {
                            let measure = observer.as_ref().is_some_and(|o| o.due(to)) || framed(to);
                            let enclose = in_parts && checking.next_due(state.step) == to;
                            d.advance_to(&mut state, to, Asks { measure, enclose })
                        }
                        None => solver
                            .advance_to(&graph, &mut state, dt, to)
                            .map(|_| Reached::default())
                            .map_err(|e| e.to_string()),
                    };
                    let (measured, parts) = match advanced {
                        Ok(r) => (r.measured, r.parts),
                        Err(message) => {
                            stop = Some(Stop::Solver { step: state.step + 1, message });
                            break;
                        }
                    };
                    stop = check(&mut checking, &mut state, true, parts)?;
                    // (the domains' forces were tested finite on their ranks)
                    if stop.is_none() && shared.is_none() && !solver.potential().is_finite() {
                        stop = non_finite(&state);
                    }
                    meters.iter_mut().for_each(|(m, _)| m.observe(state.t, &state.x, &state.v, solver.forces()));
                    if stop.is_none() {
                        sample(&mut observer, &state, potential(measured, &solver), measured)?;
                    }
                    if framed(state.step) {
                        trace(&state, potential(measured, &solver))?;
                    }
                    if let Some(w) = watch.as_mut().filter(|w| state.step.is_multiple_of(w.every.max(1))) {
                        (w.see)(&state);
                    }
                    if let Some(p) = progress.as_mut() {
                        p(state.step);
                    }
                    if stop.is_none() && cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                        stop = Some(Stop::Cancelled { step: state.step });
                    }
                    let on_the_way = state.step.is_multiple_of(every_restart) && state.step < end;
                    if let Some(r) = restarts.as_mut().filter(|_| stop.is_none() && on_the_way) {
                        let made = carry(
                            &state,
                            (scene, steps),
                            solver_carries(&solver, &state),
                            &graph,
                            checking.carried(),
                            &observer,
                            &meters,
                        );
                        (r.write)(made?)?;
                    }
                }
                if stop.is_none() {
                    stop = non_finite(&state);
                }
                if stop.is_none() && state.step < steps {
                    stop = Some(Stop::Until { step: state.step });
                }
                iterations = solver.iterations().cloned();
                solver_plan = shared.as_ref().map_or_else(|| solver.plan(), |d| Some(d.plan()));
                if restarts.is_some() {
                    solver_carried = solver_carries(&solver, &state);
                }
            }
        }
        // a breach at the checkpoint still being judged came first
        let judging = Instant::now();
        let settled = checking.settle();
        judged(judging);
        if let Err((halt, at)) = settled {
            (stop, state) = (Some(Stop::Checker(halt)), at);
        }
        Ok(checking.into_monitor())
    })?;
    let wall_s = start.elapsed().as_secs_f64();
    let spread_s = (lagra_kernel::spread::spent() - spread_before).as_secs_f64();
    let predictions = meters
        .iter()
        .map(|(m, p)| {
            let (measured, detail) = m.measured().unzip();
            let detail = detail.flatten();
            let (rel_diff, agrees) = match (p.predicted, measured) {
                (Some(want), Some(got)) => {
                    let d = (got - want).abs() / want;
                    (Some(d), p.tol.is_none_or(|tol| d <= tol))
                }
                // a statistical test: the measured value is its p-value
                (None, Some(pv)) => (None, pv >= p.tol.unwrap_or(0.01)),
                (_, None) => (None, false),
            };
            Measured { name: p.kind.name(), predicted: p.predicted, measured, rel_diff, tol: p.tol, agrees, detail }
        })
        .collect();
    let restart = restarts.map(|_| match &stop {
        Some(Stop::Checker(h)) => Err(format!("the run {h}, and cannot go on")),
        Some(Stop::Solver { step, message }) => Err(format!("the solver failed at step {step} ({message})")),
        _ => carry(&state, (scene, steps), solver_carried, &graph, monitor.carried(), &observer, &meters),
    });
    // (in domains rank 0's whole graph only evaluated the first state: the solver's plan says
    // how its share was visited)
    let plan = if shared.is_some() { vec![] } else { graph.plan() };
    Ok(Report {
        planned_steps: steps,
        steps: state.step,
        wall_s,
        checker_s: busy.unwrap_or(waited.get()),
        checker_wait_s: waited.get(),
        serial_s: (wall_s - spread_s - waited.get()).max(0.0),
        stop,
        outcome: monitor.finish(),
        predictions,
        state,
        plan,
        checker: if overlap {
            "on a second thread, judging checkpoint k while the kernel steps to k + 1"
        } else {
            "inline, at every checkpoint"
        },
        iterations,
        solver_plan,
        observables: observer.and_then(Observer::finish),
        first_step,
        restart,
    })
}

/// What goes on from state `s` (the front names its scene and certificate).
fn carry(
    s: &State,
    (scene, planned_steps): (&Scene, u64),
    solver: Result<lagra_kernel::solvers::Carried, String>,
    graph: &LagrangianGraph,
    monitor: Result<lagra_checker::monitor::Carried, String>,
    observer: &Option<Observer>,
    meters: &[(Meter, &Prediction)],
) -> Result<Restart, String> {
    Ok(Restart {
        scene: String::new(),
        setup: setup_of(scene),
        planned_steps,
        state: s.clone(),
        solver: solver?,
        lists: graph.lists_built_at(),
        monitor: monitor?,
        observer: observer.clone(),
        meters: meters.iter().map(|m| m.0.clone()).collect(),
        certificate: None,
    })
}
