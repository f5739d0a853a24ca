//! `lagra run FILE`.

use crate::progress::{Progress, When};
use crate::view::PageFrames;
use crate::{fluid, noether, report};
use lagra_checker::certificate::{self, Certificate, Trail};
use lagra_checker::checksum::label;
use lagra_checker::decision::Verdict;
use lagra_checker::model::Snapshot;
use lagra_checker::states::StateWriter;
use lagra_kernel::forces::Pool;
use lagra_kernel::graph::threads_of;
use lagra_lang::integrator::Integrator;
use lagra_lang::scene::Scene;
use lagra_noether::Analysis;
use lagra_run::compile_on;
use lagra_run::marks::{self, OnDisk, Spill};
use lagra_run::restart::Restart;
use lagra_run::run::{run, Options, Report, Restarts, Stop};
use lagra_run::trace::{Behind, Format, Frames, Writer};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

#[derive(clap::Args)]
pub struct Args {
    /// The scene file.
    file: PathBuf,
    /// Print the report as one JSON document instead of text.
    #[arg(long)]
    json: bool,
    /// Write every frame (steps_per_frame): by the extension, `.jsonl` (step, t, energy
    /// witness, positions, velocities a line; what `lagra view` reads), `.xyz` (extended XYZ,
    /// for ASE and OVITO) or `.lammpstrj` (LAMMPS text dump, for OVITO, VMD, MDAnalysis).
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Write the certificate: scene digest, canonical graph, claims, per-checkpoint
    /// enclosures, verdicts (re-check it with `lagra check` or `lagra-check`).
    #[arg(long, value_name = "FILE")]
    certificate: Option<PathBuf>,
    /// Write a page that plays the run in a browser: the trace (written by --trace or kept in
    /// memory), the scene and the certificate in one self-contained HTML file (`lagra view`).
    #[arg(long, value_name = "FILE.html")]
    view: Option<PathBuf>,
    /// Write every state the checker saw, exactly, so a re-check can evaluate every claim again.
    #[arg(long, value_name = "FILE")]
    states: Option<PathBuf>,
    /// Run this many steps instead of the scene's own run length.
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
    /// Use this time step instead of the scene's own (in the scene's units).
    #[arg(long, value_name = "DT")]
    dt: Option<f64>,
    /// Set a parameter before the run: NAME=VALUE with the spellings of `lagra grad` (trap.k,
    /// body[0].mass, ...); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Threads for the forces and the checker's sums (at most 1024). Any count gives the same
    /// bits. Without it: the physical cores for scenes of 16,384 bodies or more, else one
    /// (the report says which)
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Print how each term group visits its bodies (every pair, cell list, Verlet list, pieces).
    #[arg(long)]
    explain: bool,
    /// A progress bar on stderr (steps, steps per second, time left, claims): `auto` shows it
    /// when stderr is a terminal and the run takes over two seconds; `always` prints a line per
    /// report instead, anywhere.
    #[arg(long, value_name = "WHEN", default_value = "auto")]
    progress: When,
    /// No progress bar (the same as --progress never).
    #[arg(long)]
    quiet: bool,
    /// Write a restart file at the end of the run, and where a signal or --until stops it: the
    /// exact state and everything the run carries to its next step, so that --resume continues
    /// it to the bit (written to a temporary file, synced, renamed).
    #[arg(long, value_name = "FILE")]
    restart: Option<PathBuf>,
    /// Also write the restart file every N steps, each replacing the one before (the checker
    /// then judges on the kernel's thread).
    #[arg(long, value_name = "N", requires = "restart")]
    restart_every: Option<u64>,
    /// Continue the run a restart file holds, to the scene's last step (or --steps): the same
    /// states, marks and verdicts as the run never stopped. Its certificate names the one
    /// before; `lagra-check` re-checks the segments as one run.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Stop at this step of the run (counted from its start, not from a --resume), as a signal
    /// would: the claims judged up to there, the files written, a restart file to go on from.
    #[arg(long, value_name = "STEP")]
    until: Option<u64>,
    /// Under mpirun: the bricks the periodic box is cut into, one a rank, as NXxNYxNZ (2x2x1);
    /// without it, the grid whose bricks have the smallest halo.
    #[arg(long, value_name = "NXxNYxNZ")]
    grid: Option<String>,
    /// Refuse (exit 2) a scene that gives a warning: a claim its symmetries cannot support
    /// (momentum along a floor's normal), or a fluid whose kernel's support holds too few
    /// particles; without it those are warnings.
    #[arg(long)]
    strict: bool,
}

/// What `lagra run --help` says after the options: the integrators a scene's `solver` block
/// may name, and the exit status.
pub fn after_help() -> String {
    let mut s = String::from("Integrators (solver { integrator: \"NAME\", ... } in the scene):\n");
    for i in Integrator::ALL {
        let settings = match i.settings() {
            [] => String::new(),
            names => format!(" [settings: {}]", names.join(", ")),
        };
        s += &format!("  {:<17} {}{settings}\n", i.name(), i.about());
    }
    s + "Without one, a scene gets velocity_verlet, or rattle if it declares constraints.\n\n\
Exit status: 0 every claim PASSed and every prediction agreed; 1 a claim FAILed or was UNDECIDED, a prediction \
disagreed or could not be measured, or the run halted (a singular force, an iteration that did not converge, a \
non-finite state); 2 bad input (the scene, a file, an argument); 130 or 143 stopped by SIGINT or SIGTERM \
(128 + the signal, as a shell reports it): the run stops at its next look at the flag (about every 10^6 \
atom-steps), the claims are judged up to the state reached, and the certificate (its `run.stopped` says \
why) and the other files are written as at the end of a run, a restart file too with --restart; a second \
SIGINT ends the process at once. A run stopped by --until exits as its verdicts so far say (a claim not yet \
due is UNDECIDED: 1).\n\n\
Restart files: --restart FILE is written at the end, at a signal or --until, and every --restart-every N \
steps; --resume FILE continues from it to the same bits as the run never stopped. A run cut into segments \
is certified in segments whose certificates chain (`lagra-check C1 C2 C3`)."
}

/// Bad input: the message on stderr, exit code 2.
fn bad(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("lagra: {msg}");
    ExitCode::from(2)
}

/// A scene as `lagra run` runs it: compiled from its source, its `--set` and `--dt` applied,
/// `@expect noether` expanded; with the Noether analysis and the warnings (its own, and a fluid's
/// too few neighbours).
#[derive(Clone)]
pub struct Prepared {
    pub scene: Scene,
    pub analysis: Analysis,
    pub warnings: Vec<String>,
    pub generated: usize,
}

/// Compiles a scene's source (`path` names it in messages), applies the settings and a time
/// step, and expands `@expect noether`. The error is the message to show, a located diagnostic
/// for a scene error.
pub fn prepare(source: &str, path: &str, set: &[String], dt: Option<f64>) -> Result<Prepared, String> {
    prepare_on(source, path, set, dt, &|_| None)
}

/// [`prepare`], a large lattice laid out on the threads `threads` gives (`lagra_lang::compile_on`).
pub fn prepare_on<'a>(
    source: &'a str,
    path: &str,
    set: &[String],
    dt: Option<f64>,
    threads: lagra_lang::Threads<'a>,
) -> Result<Prepared, String> {
    let mut scene = compile_on(source, threads).map_err(|d| d.render(path, source).to_string())?;
    lagra_lang::params::apply_settings(&mut scene, set)?;
    if let Some(dt) = dt {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(format!("the time step must be positive and finite, got {dt}"));
        }
        scene.solver.dt = dt;
    }
    let (analysis, mut warnings, generated) = noether::apply(&mut scene, path, source);
    warnings.extend(fluid::warnings(&scene, path, source));
    Ok(Prepared { scene, analysis, warnings, generated })
}

/// The threads each of `ranks` ranks (`here` of them on this machine) takes for its share of
/// `bodies` bodies: `asked`, or by default its share of this machine's cores.
fn threads_here(bodies: usize, ranks: usize, here: usize, asked: Option<usize>) -> Result<usize, String> {
    match lagra_run::run::threads_for(bodies / ranks, asked)? {
        // ranks on one machine share its cores
        t if asked.is_none() => Ok((t / here).max(1)),
        t => Ok(t),
    }
}

/// The report of a finished run, with what Noether says of each failed claim.
pub fn summarize(path: &str, p: &Prepared, rep: &Report, threads: usize, explain: bool) -> report::Summary {
    let mut summary = report::Summary::new(path, &p.scene, rep, threads, explain);
    summary.generated = p.generated;
    summary.notes = p
        .scene
        .claims
        .iter()
        .zip(&summary.claims)
        .filter(|(_, line)| matches!(line.verdict, Verdict::Fail(_)))
        .filter_map(|(c, _)| noether::note(&p.analysis, c))
        .collect();
    summary
}

pub fn main(a: Args) -> ExitCode {
    // under mpirun every rank reads and prepares the scene; rank 0 alone speaks
    let world = match crate::ranks::World::join() {
        Ok(w) => w,
        Err(e) => return bad(e),
    };
    let root = world.is_root();
    let fail = |msg: String| if root { bad(msg) } else { ExitCode::from(2) };
    let path = a.file.display().to_string();
    let source = match crate::reading::text(&a.file, crate::reading::Limits::from_env().scene) {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    // the run's threads, started where a large lattice asks for them at the compile (its bodies
    // laid out on them) and handed on to the run; else the run starts its own
    let (ranks, here) = (world.size, world.here());
    let started: OnceLock<Pool> = OnceLock::new();
    let lattice_threads = |bodies: usize| {
        let start = || threads_here(bodies, ranks, here, a.threads).ok().and_then(|t| threads_of(t).ok()).flatten();
        started.get_or_init(start).as_deref()
    };
    let prepared = match prepare_on(&source, &path, &a.set, a.dt, &lattice_threads) {
        Ok(p) => p,
        Err(e) if e.contains('\n') => {
            if root {
                eprintln!("{e}");
            }
            return ExitCode::from(2);
        }
        Err(e) => return fail(e),
    };
    let scene = &prepared.scene;
    let threads = match threads_here(scene.model.bodies.len(), ranks, here, a.threads) {
        Ok(t) => t,
        Err(e) => return fail(e),
    };
    let mut sharing = match Sharing::of(&world, &a, scene, threads) {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    if !root {
        sharing.follow();
        return ExitCode::SUCCESS;
    }
    if let Some(note) = sharing.note() {
        eprintln!("lagra: {note}");
    }
    prepared.warnings.iter().for_each(|w| eprintln!("{w}"));
    if a.strict && !prepared.warnings.is_empty() {
        return bad("--strict: the warnings above are errors");
    }
    if a.steps == Some(0) {
        return bad("--steps must be at least 1");
    }
    if a.restart_every == Some(0) {
        return bad("--restart-every must be at least 1");
    }
    let digest = crate::reading::source_digest(&source);
    let resume = match a.resume.as_deref().map(|p| Restart::read(p).and_then(|r| r.belongs_to(&digest).map(|_| r))) {
        None => None,
        Some(Ok(r)) => Some(r),
        Some(Err(e)) => return bad(format!("--resume: {e}")),
    };
    let previous = resume.as_ref().and_then(|r| r.certificate.clone());
    // the trace goes to its file, and, for a page, to memory as well
    let format = match a.trace.as_deref().map(Format::of).transpose() {
        Ok(f) => f,
        Err(e) => return bad(e),
    };
    let mut file = match a.trace.as_ref().zip(format) {
        Some((p, format)) => match File::create(p) {
            Ok(f) => Some(Behind::new(Writer::new(BufWriter::new(f), format, &scene.model))),
            Err(e) => return bad(format!("cannot create the trace file: {e}")),
        },
        None => None,
    };
    let mut kept = a.view.as_ref().map(|_| PageFrames::new(&scene.model));
    let mut both = Tee(file.as_mut(), kept.as_mut());
    let tracing = both.0.is_some() || both.1.is_some();
    let mut states = match a
        .states
        .as_ref()
        .map(|p| {
            File::create(p).and_then(|f| {
                StateWriter::new(BufWriter::new(f), scene.x0.len(), scene.model.links(), scene.spin0.len())
            })
        })
        .transpose()
    {
        Ok(w) => w,
        Err(e) => return bad(format!("cannot create the state file: {e}")),
    };
    let mut record = recorder(|s| states.as_mut().map_or(Ok(()), |w| w.push(s)));
    // the marks: on disk beside the certificate (and thinned for a page), or dropped
    let spill = match (a.certificate.is_some() || a.view.is_some()).then(|| {
        let dir = a.certificate.as_deref().map_or_else(std::env::temp_dir, |c| folder_of(c).to_path_buf());
        Spill::new(scene.claims.len(), Some(&dir), a.view.is_some())
            .map_err(|e| format!("cannot make a file for the marks in {}: {e}", dir.display()))
    }) {
        None => None,
        Some(Ok(s)) => Some(s),
        Some(Err(e)) => return bad(e),
    };
    let signalled = match Signalled::listen() {
        Ok(s) => s,
        Err(e) => return bad(format!("cannot listen for SIGINT and SIGTERM: {e}")),
    };
    let mut progress = Progress::new(a.progress.unless(a.quiet), a.steps.unwrap_or(scene.solver.steps));
    let shown = progress.is_some();
    let mut tick = |step: u64| progress.as_mut().into_iter().for_each(|p| p.at(step));
    let mut write_restart = |mut r: Restart| {
        r.scene.clone_from(&digest);
        a.restart.as_deref().map_or(Ok(()), |p| r.write(p))
    };
    let restarts =
        a.restart.is_some().then(|| Restarts { every: a.restart_every.unwrap_or(u64::MAX), write: &mut write_restart });
    let result = run(
        scene,
        Options {
            steps: a.steps,
            trace: tracing.then_some(&mut both as &mut dyn Frames),
            record: a.states.is_some().then_some(&mut record),
            threads,
            pool: started.get().cloned().flatten(),
            progress: shown.then_some(&mut tick),
            stop: Some(&*signalled.stop),
            watch: None,
            marks: Some(spill.as_ref().map_or_else(marks::dropped, Spill::sink)),
            resume,
            until: a.until,
            restarts,
            shared: sharing.shared(),
        },
    );
    progress.iter().for_each(Progress::done);
    drop(both);
    let flushed = file.map(|w| w.finish().and_then(|mut w| w.out.flush())).transpose();
    let rep = match (result, flushed) {
        (Ok(r), Ok(_)) => r,
        (Err(e), _) => return bad(e),
        (_, Err(e)) => return bad(format!("writing the trace: {e}")),
    };
    let states_checksum = match states.map(StateWriter::finish).transpose() {
        Ok(sum) => sum.map(label),
        Err(e) => return bad(format!("writing the state file: {e}")),
    };
    let mut summary = summarize(&path, &prepared, &rep, threads, a.explain);
    // a signal counts if it stopped the run (one after its last step changes nothing)
    let signal = match rep.stop {
        Some(Stop::Cancelled { step }) => signalled.which().inspect(|(_, name)| {
            summary.halted =
                Some(format!("stopped at step {step} by a signal ({name}): the claims were judged up to there"))
        }),
        _ => None,
    };
    // the checksum of the certificate written, for the restart file to name
    let mut written = None;
    if let Some(spill) = spill {
        let (disk, plots) = match spill.finish(&scene.claims) {
            Ok(t) => t,
            Err(e) => return bad(format!("writing the marks: {e}")),
        };
        let cert = Certificate {
            format: certificate::FORMAT.into(),
            arithmetic: certificate::ARITHMETIC.into(),
            scene: scene.name.clone(),
            source_digest: digest.clone(),
            model: (*scene.model).clone(),
            claims: scene.claims.clone(),
            run: certificate::Run {
                integrator: scene.solver.integrator.name().into(),
                dt: scene.solver.dt,
                planned_steps: rep.planned_steps,
                steps: rep.steps,
                stopped: summary.halted.clone(),
                first_step: rep.first_step,
            },
            trails: vec![],
            verdicts: summary.claims.iter().map(|c| c.line.clone()).collect(),
            states_checksum,
            previous,
            checksum: String::new(),
        };
        if let Some(c) = &a.certificate {
            match write_certificate(with_trails(cert.clone(), disk), c) {
                Ok(sum) => written = Some(sum),
                Err(e) => return bad(e),
            }
        }
        if let (Some(out), Some(kept)) = (&a.view, kept) {
            let (text, stride) = kept.text();
            if stride > 1 {
                let budget = crate::view::PAGE_TRACE_BYTES >> 20;
                eprintln!("lagra: the page shows one frame in {stride} (and the last), to stay within {budget} MiB; a --trace file has them all");
            }
            let plotted = Certificate { trails: plots, ..cert };
            let page = crate::view::page(&text, "the trace", Some(scene), Some(&plotted));
            if let Err(e) =
                page.and_then(|p| std::fs::write(out, p).map_err(|e| format!("cannot write {}: {e}", out.display())))
            {
                return bad(e);
            }
        }
    }
    match (&a.restart, rep.restart) {
        (Some(p), Some(Ok(mut r))) => {
            (r.scene, r.certificate) = (digest.clone(), written);
            if let Err(e) = r.write(p) {
                return bad(e);
            }
        }
        (Some(p), Some(Err(why))) => eprintln!("lagra: no restart file written to {}: {why}", p.display()),
        _ => {}
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&summary).expect("the summary is plain data"));
    } else {
        print!("{}", summary.text());
    }
    match signal {
        Some((number, _)) => ExitCode::from(128 + number as u8),
        None if summary.passed => ExitCode::SUCCESS,
        None => ExitCode::from(1),
    }
}

/// How the ranks of a job share a run: this process alone (no job; or rank 0 of a job whose
/// scene is not cut, the others idle, with a note saying why), or the scene cut into domains.
enum Sharing {
    Alone(Option<String>),
    #[cfg(feature = "mpi")]
    Domains(Box<lagra_run::domains::Domain<crate::ranks::Collectives>>),
}

impl Sharing {
    /// A collective: every rank decides alike (from the same scene and arguments) and, to cut the
    /// scene, makes its domain.
    fn of(world: &crate::ranks::World, a: &Args, scene: &Scene, threads: usize) -> Result<Sharing, String> {
        if world.size == 1 {
            return match &a.grid {
                Some(_) => Err("--grid cuts a scene across the ranks of an MPI job: run it under mpirun".into()),
                None => Ok(Sharing::Alone(None)),
            };
        }
        let whole = |why: String| {
            Sharing::Alone(Some(format!("rank 0 of {} runs the scene whole, the other ranks idle: {why}", world.size)))
        };
        if let Err(why) = lagra_run::domains::fits(scene) {
            return Ok(whole(format!("the scene is not cut into domains: {why}")));
        }
        #[cfg(feature = "mpi")]
        if let Some(c) = world.collectives() {
            // every rank reads a restart's state (a file every rank can read, as a sweep's --out)
            let start = match &a.resume {
                Some(p) => Restart::read(p).map_err(|e| format!("--resume: {e}"))?.state,
                None => lagra_kernel::setup::start(scene),
            };
            return lagra_run::domains::Domain::new(c, scene, &start, a.grid.as_deref(), threads)
                .map(|d| Sharing::Domains(Box::new(d)));
        }
        let _ = threads;
        Ok(whole("this lagra was built without MPI".into()))
    }

    /// Why rank 0 runs the scene whole, if it does.
    fn note(&self) -> Option<&str> {
        match self {
            Sharing::Alone(note) => note.as_deref(),
            #[cfg(feature = "mpi")]
            Sharing::Domains(_) => None,
        }
    }

    /// On a rank other than 0: its domain's share of the steps rank 0 asks for, or nothing.
    fn follow(self) {
        #[cfg(feature = "mpi")]
        if let Sharing::Domains(d) = self {
            d.follow();
        }
    }

    /// What rank 0's run loop steps the domains through.
    fn shared(&mut self) -> Option<&mut dyn lagra_run::domains::Shared> {
        match self {
            Sharing::Alone(_) => None,
            #[cfg(feature = "mpi")]
            Sharing::Domains(d) => Some(d.as_mut()),
        }
    }
}

/// SIGINT and SIGTERM (Ctrl-C, a batch system's time limit) ask the run to stop: it stops at
/// its next look at the flag and writes everything as at its end. A second SIGINT ends the
/// process at once (`register_conditional_shutdown` runs before the flag is set).
struct Signalled {
    stop: Arc<AtomicBool>,
    by: Arc<AtomicUsize>,
}

impl Signalled {
    fn listen() -> std::io::Result<Signalled> {
        use signal_hook::consts::{SIGINT, SIGTERM};
        use signal_hook::flag;
        let (stop, by) = (Arc::<AtomicBool>::default(), Arc::<AtomicUsize>::default());
        flag::register_conditional_shutdown(SIGINT, 130, Arc::clone(&stop))?;
        for sig in [SIGINT, SIGTERM] {
            flag::register_usize(sig, Arc::clone(&by), sig as usize)?;
            flag::register(sig, Arc::clone(&stop))?;
        }
        Ok(Signalled { stop, by })
    }

    /// The signal that stopped the run, if one did: its number and name.
    fn which(&self) -> Option<(i32, &'static str)> {
        use signal_hook::consts::{SIGINT, SIGTERM};
        match self.by.load(Ordering::SeqCst) as i32 {
            SIGINT => Some((SIGINT, "SIGINT")),
            SIGTERM => Some((SIGTERM, "SIGTERM")),
            _ => None,
        }
    }
}

/// A certificate with other trails (the marks on disk for its file, thinned for a page).
fn with_trails<M, N>(c: Certificate<M>, trails: Vec<Trail<N>>) -> Certificate<N> {
    Certificate {
        format: c.format,
        arithmetic: c.arithmetic,
        scene: c.scene,
        source_digest: c.source_digest,
        model: c.model,
        claims: c.claims,
        run: c.run,
        trails,
        verdicts: c.verdicts,
        states_checksum: c.states_checksum,
        previous: c.previous,
        checksum: c.checksum,
    }
}

/// Seals the certificate and writes it, its marks streamed from disk, to a temporary file
/// beside `to` that is then renamed over it: a reader never sees half a certificate.
fn write_certificate(cert: Certificate<OnDisk>, to: &Path) -> Result<String, String> {
    let failed = |e: &dyn std::fmt::Display| format!("cannot write the certificate {}: {e}", to.display());
    let cert = cert.seal().map_err(|e| failed(&e))?;
    let dir = folder_of(to);
    // the mode a plain create gives (0666 less the umask), not a temporary file's 0600
    let mode = std::os::unix::fs::PermissionsExt::from_mode(0o666);
    let file = tempfile::Builder::new().permissions(mode).tempfile_in(dir).map_err(|e| failed(&e))?;
    let mut out = BufWriter::new(file);
    serde_json::to_writer(&mut out, &cert).map_err(|e| failed(&e))?;
    out.write_all(b"\n").map_err(|e| failed(&e))?;
    let file = out.into_inner().map_err(|e| failed(&e.into_error()))?;
    file.as_file().sync_all().map_err(|e| failed(&e))?;
    file.persist(to).map_err(|e| failed(&e.error))?;
    Ok(cert.checksum)
}

/// The folder a file named by `path` is in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// A trace written to a file and kept in memory for a page, either or both.
struct Tee<'a, A: Frames, B: Frames>(Option<&'a mut A>, Option<&'a mut B>);

impl<A: Frames, B: Frames> Frames for Tee<'_, A, B> {
    fn frame(&mut self, s: &lagra_kernel::state::State, energy: f64) -> std::io::Result<()> {
        if let Some(a) = self.0.as_mut() {
            a.frame(s, energy)?;
        }
        if let Some(b) = self.1.as_mut() {
            b.frame(s, energy)?;
        }
        Ok(())
    }
}

/// Pins a closure to the signature `Options::record` takes (for every lifetime of the snapshot).
fn recorder<F: FnMut(&Snapshot) -> std::io::Result<()>>(f: F) -> F {
    f
}
