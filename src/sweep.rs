//! `lagra sweep FILE --set NAME=V1,V2,...`: independent variants of one scene (a parameter scan,
//! an ensemble of seeds or starting velocities), each a `lagra run` in a process of its own with
//! its own certificate, a few at a time; then one table. A variant that crashes or is killed
//! takes nothing else with it, and its row says so: it never counts as a PASS. Under `mpirun`
//! (built with `--features mpi`) the variants are dealt to the ranks in turn, each rank runs its
//! own the same way, and rank 0 gathers the rows: the folder must be one every rank can write.

use crate::ranks::{World, LAUNCHER_VARIABLES};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitCode, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct Args {
    /// The scene file.
    file: PathBuf,
    /// An axis of the sweep: NAME=V1,V2,... with the spellings of `lagra grad` (trap.k,
    /// body[0].mass, body[3].velocity.x, lj#1.epsilon). Repeatable: the variants are every
    /// combination, the first --set varying slowest.
    #[arg(long = "set", value_name = "NAME=V1,V2,...")]
    set: Vec<String>,
    /// Time steps to sweep too, comma-separated (in the scene's units): one more axis, last.
    #[arg(long, value_name = "DT1,DT2,...")]
    dt: Option<String>,
    /// Run each variant this many steps instead of the scene's own run length.
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
    /// How many variants run at once (on each MPI rank). Without it: the CPUs
    /// (available_parallelism) over the ranks on this machine over --threads.
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Threads for each variant's run (`lagra run --threads`).
    #[arg(long, value_name = "N", default_value_t = 1)]
    threads: usize,
    /// The folder for the variants' certificates (vN.cert.json), reports (vN.json), messages
    /// (vN.log) and the sweep's own summary (sweep.json). Without it: sweep-<scene file's stem>.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the summary as one JSON document instead of the table.
    #[arg(long)]
    json: bool,
    /// No line on stderr as each variant ends.
    #[arg(long)]
    quiet: bool,
}

/// One axis: a parameter's spelling and its values, each as written (so the variant's run gets
/// the very text the user gave).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Axis {
    pub name: String,
    pub values: Vec<String>,
}

/// More variants than this is a typing slip more often than a plan.
const MOST_VARIANTS: usize = 100_000;

/// Reads `NAME=V1,V2,...`: the values must be numbers (what they may be is the scene's to say).
pub fn axis(spelling: &str) -> Result<Axis, String> {
    let (name, list) = spelling
        .split_once('=')
        .ok_or_else(|| format!("`{spelling}`: write --set NAME=V1,V2,... (e.g. trap.k=1,2,4)"))?;
    let values: Vec<String> = list.split(',').map(|v| v.trim().to_string()).collect();
    if let Some(v) = values.iter().find(|v| v.parse::<f64>().map_or(true, |x| !x.is_finite())) {
        return Err(format!("`{spelling}`: `{v}` is not a finite number"));
    }
    Ok(Axis { name: name.trim().to_string(), values })
}

/// Every combination of the axes' values, as an index into each axis; the first axis varies
/// slowest (the order a nested loop over the axes as written would give).
pub fn combinations(axes: &[Axis]) -> Vec<Vec<usize>> {
    let mut out = vec![vec![]];
    for a in axes {
        out = out.into_iter().flat_map(|head| (0..a.values.len()).map(move |i| [&head[..], &[i]].concat())).collect();
    }
    out
}

/// One variant: what is set, and (once run) how it went.
#[derive(Serialize, Deserialize)]
pub struct Variant {
    pub index: usize,
    /// The MPI rank that ran it (0 without MPI).
    pub rank: usize,
    /// `NAME=VALUE` for each axis (`dt=VALUE` for the time step).
    pub settings: Vec<String>,
    pub certificate: PathBuf,
    /// `lagra run`'s exit status; `None` where it was ended by a signal or never started.
    pub exit: Option<i32>,
    /// Why the variant has no report: a signal, bad input, a sweep stopped before it.
    pub failure: Option<String>,
    pub wall_s: f64,
    /// `lagra run --json`'s report, whole.
    pub report: Option<Value>,
}

impl Variant {
    pub fn passed(&self) -> bool {
        self.exit == Some(0) && self.report.as_ref().is_some_and(|r| r["passed"] == Value::Bool(true))
    }
}

#[derive(Serialize)]
pub struct Sweep {
    pub file: String,
    pub axes: Vec<Axis>,
    /// MPI ranks (1 without MPI); `jobs` variants at a time on each.
    pub ranks: usize,
    pub jobs: usize,
    pub threads: usize,
    pub out: PathBuf,
    pub variants: Vec<Variant>,
    pub wall_s: f64,
    /// Every variant ran and PASSed every claim and prediction.
    pub passed: bool,
    /// Why the sweep stopped before its end (a signal), if it did.
    pub stopped: Option<String>,
}

/// What one rank sends rank 0: the signal that stopped it (0 if none) and its variants.
#[derive(Serialize, Deserialize)]
struct Share {
    signal: i32,
    variants: Vec<Variant>,
}

pub fn main(a: Args) -> ExitCode {
    let world = match World::join() {
        Ok(w) => w,
        Err(e) => {
            eprintln!("lagra: {e}");
            return ExitCode::from(2);
        }
    };
    match sweep(&a, &world) {
        Ok(code) => code,
        // every rank found the same bad input: one says so
        Err(e) => {
            if world.is_root() {
                eprintln!("lagra: {e}");
            }
            ExitCode::from(2)
        }
    }
}

fn sweep(a: &Args, world: &World) -> Result<ExitCode, String> {
    let path = a.file.display().to_string();
    let source = crate::reading::text(&a.file, crate::reading::Limits::from_env().scene)?;
    let mut axes = a.set.iter().map(|s| axis(s)).collect::<Result<Vec<_>, _>>()?;
    if let Some(dt) = &a.dt {
        axes.push(axis(&format!("dt={dt}")).map_err(|e| format!("--dt: {e}"))?);
    }
    if axes.is_empty() {
        return Err("a sweep needs an axis: --set NAME=V1,V2,... or --dt DT1,DT2,...".into());
    }
    let count: usize = axes.iter().map(|ax| ax.values.len()).product();
    if count > MOST_VARIANTS {
        return Err(format!("the sweep has {count} variants, more than {MOST_VARIANTS}: split it"));
    }
    if a.threads == 0 || a.jobs == Some(0) || a.steps == Some(0) {
        return Err("--threads, --jobs and --steps must be at least 1".into());
    }
    let stem = a.file.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let out = a.out.clone().unwrap_or_else(|| PathBuf::from(format!("sweep-{stem}")));
    // every variant compiled here first: a value the scene refuses stops the sweep before it runs
    let mut variants = vec![];
    for (index, pick) in combinations(&axes).into_iter().enumerate() {
        let settings: Vec<String> =
            axes.iter().zip(&pick).map(|(ax, &i)| format!("{}={}", ax.name, ax.values[i])).collect();
        let (dt, set): (Vec<&String>, Vec<&String>) = settings.iter().partition(|s| s.starts_with("dt="));
        let set: Vec<String> = set.into_iter().cloned().collect();
        let dt = dt.first().map(|s| s["dt=".len()..].parse::<f64>().expect("checked by axis"));
        crate::run::prepare(&source, &path, &set, dt)
            .map_err(|e| format!("variant {index} ({}): {e}", settings.join(" ")))?;
        variants.push(Variant {
            index,
            rank: index % world.size,
            settings,
            certificate: out.join(format!("v{index}.cert.json")),
            exit: None,
            failure: None,
            wall_s: 0.0,
            report: None,
        });
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot make the folder {}: {e}", out.display()))?;
    // this rank's share: every size-th variant
    let mine: Vec<Variant> = variants.into_iter().filter(|v| v.rank == world.rank).collect();
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = a.jobs.unwrap_or((cpus / world.here() / a.threads).max(1)).min(mine.len().max(1));
    let stop = Arc::new(AtomicBool::new(false));
    let by = Arc::new(AtomicUsize::new(0));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .and_then(|_| signal_hook::flag::register_usize(sig, Arc::clone(&by), sig as usize))
            .map_err(|e| format!("cannot listen for SIGINT and SIGTERM: {e}"))?;
    }
    let started = Instant::now();
    let done = run_all(a, world, &out, mine, jobs, &stop);
    let share = Share { signal: by.load(Ordering::SeqCst) as i32, variants: done };
    let bytes = serde_json::to_vec(&share).expect("the variants are plain data");
    let Some(shares) = world.gather(bytes) else { return Ok(ExitCode::SUCCESS) };
    let shares: Vec<Share> = shares
        .iter()
        .map(|b| serde_json::from_slice(b))
        .collect::<Result<_, _>>()
        .expect("every rank sends what this code wrote");
    let signal = shares.iter().map(|s| s.signal).find(|&s| s != 0).unwrap_or(0);
    let mut all: Vec<Variant> = shares.into_iter().flat_map(|s| s.variants).collect();
    all.sort_by_key(|v| v.index);
    let sweep = Sweep {
        file: path,
        axes,
        ranks: world.size,
        jobs,
        threads: a.threads,
        out: out.clone(),
        passed: signal == 0 && all.iter().all(Variant::passed),
        variants: all,
        wall_s: started.elapsed().as_secs_f64(),
        stopped: (signal != 0).then(|| format!("stopped by signal {signal}: the variants not yet started did not run")),
    };
    let json = serde_json::to_string_pretty(&sweep).expect("the sweep is plain data");
    if let Err(e) = std::fs::write(out.join("sweep.json"), format!("{json}\n")) {
        eprintln!("lagra: cannot write {}: {e}", out.join("sweep.json").display());
    }
    if a.json {
        println!("{json}");
    } else {
        print!("{}", table(&sweep));
    }
    Ok(match signal {
        0 if sweep.passed => ExitCode::SUCCESS,
        0 => ExitCode::from(1),
        s => ExitCode::from(128 + s as u8),
    })
}

/// Runs the variants, `jobs` at a time, each its own `lagra run` process; returns them in order.
fn run_all(
    a: &Args,
    world: &World,
    out: &Path,
    variants: Vec<Variant>,
    jobs: usize,
    stop: &AtomicBool,
) -> Vec<Variant> {
    let total = variants.len();
    let queue = Mutex::new(variants.into_iter());
    let finished = Mutex::new(vec![]);
    let exe = std::env::current_exe();
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| loop {
                let Some(mut v) = queue.lock().unwrap().next() else { break };
                if stop.load(Ordering::SeqCst) {
                    v.failure = Some("not run: the sweep was stopped".into());
                } else {
                    match &exe {
                        Ok(exe) => run_one(exe, a, out, &mut v, stop),
                        Err(e) => v.failure = Some(format!("cannot find the lagra executable: {e}")),
                    }
                }
                let mut f = finished.lock().unwrap();
                if !a.quiet && v.failure.as_deref() != Some("not run: the sweep was stopped") {
                    let rank = if world.size > 1 { format!(" rank {}", world.rank) } else { String::new() };
                    eprintln!("lagra sweep{rank}: [{}/{total}] {} {}", f.len() + 1, v.settings.join(" "), outcome(&v));
                }
                f.push(v);
            });
        }
    });
    let mut done = finished.into_inner().unwrap();
    done.sort_by_key(|v| v.index);
    done
}

/// One variant's run: `lagra run FILE --json --quiet --certificate ... --set ...`, its report
/// and messages kept beside its certificate. A stop asked of the sweep is passed on as SIGTERM,
/// so the run writes its certificate as far as it got.
fn run_one(exe: &Path, a: &Args, out: &Path, v: &mut Variant, stop: &AtomicBool) {
    let mut cmd = Command::new(exe);
    cmd.arg("run").arg(&a.file).args(["--json", "--quiet", "--threads", &a.threads.to_string()]);
    cmd.arg("--certificate").arg(&v.certificate);
    if let Some(n) = a.steps {
        cmd.args(["--steps", &n.to_string()]);
    }
    for s in &v.settings {
        match s.strip_prefix("dt=") {
            Some(dt) => cmd.args(["--dt", dt]),
            None => cmd.args(["--set", s]),
        };
    }
    let (report, log) = (out.join(format!("v{}.json", v.index)), out.join(format!("v{}.log", v.index)));
    let files = std::fs::File::create(&report).and_then(|r| std::fs::File::create(&log).map(|l| (r, l)));
    let (r, l) = match files {
        Ok(f) => f,
        Err(e) => {
            v.failure = Some(format!("cannot create its files in {}: {e}", out.display()));
            return;
        }
    };
    // the variant is a plain process, not a rank: the launcher's variables are not passed on
    for (name, _) in std::env::vars_os() {
        if LAUNCHER_VARIABLES.iter().any(|p| name.to_string_lossy().starts_with(p)) {
            cmd.env_remove(name);
        }
    }
    let started = Instant::now();
    let child = cmd.stdin(Stdio::null()).stdout(r).stderr(l).spawn();
    let status = match child.and_then(|c| wait(c, stop)) {
        Ok(s) => s,
        Err(e) => {
            v.failure = Some(format!("cannot run it: {e}"));
            return;
        }
    };
    v.wall_s = started.elapsed().as_secs_f64();
    v.exit = status.code();
    let said = std::fs::read_to_string(&log).unwrap_or_default();
    if said.is_empty() {
        let _ = std::fs::remove_file(&log);
    }
    v.report = std::fs::read_to_string(&report).ok().and_then(|t| serde_json::from_str(&t).ok());
    use std::os::unix::process::ExitStatusExt;
    v.failure = match (status.code(), status.signal()) {
        (_, Some(sig)) => Some(format!("ended by signal {sig}")),
        (Some(2), _) => Some(format!("bad input: {}", said.lines().last().unwrap_or("(no message)"))),
        (_, _) if v.report.is_none() => Some(format!("no report (exit {status})")),
        _ => None,
    };
}

/// Waits for a child, passing a stop on to it as SIGTERM (once).
fn wait(mut child: Child, stop: &AtomicBool) -> std::io::Result<std::process::ExitStatus> {
    let mut told = false;
    loop {
        if let Some(s) = child.try_wait()? {
            return Ok(s);
        }
        if stop.load(Ordering::SeqCst) && !told {
            // SAFETY: kill(2) on the pid of a child not yet reaped (try_wait said it runs)
            unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
            told = true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A variant's outcome in a few words.
fn outcome(v: &Variant) -> String {
    if let Some(f) = &v.failure {
        return f.clone();
    }
    let Some(r) = &v.report else { return "no report".into() };
    let claims = r["claims"].as_array().map_or(&[][..], Vec::as_slice);
    let passed = claims.iter().filter(|c| c["status"] == "PASS").count();
    let mut s = format!("{passed}/{} claims PASS", claims.len());
    let failed: Vec<&str> =
        claims.iter().filter(|c| c["status"] != "PASS").filter_map(|c| c["claim"].as_str()).collect();
    if !failed.is_empty() {
        s += &format!(" (not: {})", failed.join(", "));
    }
    if let Some(p) = r["predictions"].as_array().filter(|p| !p.is_empty()) {
        let agree = p.iter().filter(|m| m["agrees"] == Value::Bool(true)).count();
        s += &format!(", {agree}/{} predictions agree", p.len());
    }
    if let Some(h) = r["halted"].as_str() {
        s += &format!("; {h}");
    }
    s + &format!(" ({:.2} s)", v.wall_s)
}

/// What the table shows of each variant's measurements: every prediction's measured value and
/// every observable's mean.
fn measured(r: &Value) -> Vec<(String, f64)> {
    let mut m = vec![];
    for p in r["predictions"].as_array().into_iter().flatten() {
        if let (Some(name), Some(x)) = (p["name"].as_str(), p["measured"].as_f64()) {
            m.push((name.to_string(), x));
        }
    }
    for name in ["potential_energy_per_body", "kinetic_temperature", "pressure", "diffusion"] {
        if let Some(x) = r["observables"][name]["mean"].as_f64() {
            m.push((name.to_string(), x));
        }
    }
    m
}

/// The summary as text: a row per variant, a column per axis and per measured quantity.
pub fn table(s: &Sweep) -> String {
    let mut columns: Vec<String> = vec![];
    for v in &s.variants {
        for (name, _) in v.report.as_ref().map(measured).unwrap_or_default() {
            if !columns.contains(&name) {
                columns.push(name);
            }
        }
    }
    let mut head: Vec<String> = vec!["#".into()];
    head.extend(s.axes.iter().map(|a| a.name.clone()));
    head.extend(columns.iter().cloned());
    head.push("outcome".into());
    let mut rows = vec![head];
    for v in &s.variants {
        let mut row = vec![v.index.to_string()];
        row.extend(v.settings.iter().map(|x| x.split_once('=').map_or(x.clone(), |(_, value)| value.to_string())));
        let m = v.report.as_ref().map(measured).unwrap_or_default();
        for c in &columns {
            row.push(m.iter().find(|(n, _)| n == c).map_or("-".into(), |(_, x)| format!("{x:.6e}")));
        }
        row.push(outcome(v));
        rows.push(row);
    }
    let widths: Vec<usize> =
        (0..rows[0].len()).map(|i| rows.iter().map(|r| r[i].chars().count()).max().unwrap_or(0)).collect();
    let mut text = format!(
        "sweep of {}: {} variants, {} at a time{}, {} thread(s) each, {:.2} s; files in {}\n",
        s.file,
        s.variants.len(),
        s.jobs,
        if s.ranks > 1 { format!(" on each of {} ranks", s.ranks) } else { String::new() },
        s.threads,
        s.wall_s,
        s.out.display()
    );
    for r in rows {
        let cells: Vec<String> = r.iter().zip(&widths).map(|(c, w)| format!("{c:<w$}")).collect();
        text += &format!("  {}\n", cells.join("  ").trim_end());
    }
    let passed = s.variants.iter().filter(|v| v.passed()).count();
    text += &format!("{passed}/{} variants PASS", s.variants.len());
    if let Some(why) = &s.stopped {
        text += &format!("; {why}");
    }
    let first = &s.variants[0];
    let set: String = first.settings.iter().filter(|x| !x.starts_with("dt=")).map(|x| format!(" --set {x}")).collect();
    text + &format!(
        "\nre-check a variant with its settings: lagra check {} --scene {}{set}\n",
        first.certificate.display(),
        s.file
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ax(name: &str, n: usize) -> Axis {
        Axis { name: name.into(), values: (0..n).map(|i| i.to_string()).collect() }
    }

    #[test]
    fn an_axis_is_read_with_its_values_as_written() {
        assert_eq!(
            axis("trap.k = 1, 2.50,4e0").unwrap(),
            Axis { name: "trap.k".into(), values: vec!["1".into(), "2.50".into(), "4e0".into()] }
        );
    }

    #[test]
    fn an_axis_without_numbers_is_refused() {
        assert!(axis("trap.k").unwrap_err().contains("NAME=V1,V2"));
        assert!(axis("trap.k=1,,2").unwrap_err().contains("`` is not a finite number"));
        assert!(axis("trap.k=1,nan").unwrap_err().contains("`nan`"));
        assert!(axis("trap.k=inf").is_err());
    }

    #[test]
    fn the_first_axis_varies_slowest() {
        assert_eq!(combinations(&[ax("a", 2), ax("b", 3)]), [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]]);
    }

    proptest! {
        #[test]
        fn every_combination_comes_once(sizes in proptest::collection::vec(1usize..5, 0..4)) {
            let axes: Vec<Axis> = sizes.iter().enumerate().map(|(i, &n)| ax(&i.to_string(), n)).collect();
            let all = combinations(&axes);
            prop_assert_eq!(all.len(), sizes.iter().product::<usize>());
            let mut sorted = all.clone();
            sorted.sort();
            sorted.dedup();
            // sorted lexicographically already: first axis slowest, and no repeats
            prop_assert_eq!(&sorted, &all);
            prop_assert!(all.iter().all(|c| c.iter().zip(&sizes).all(|(i, n)| i < n)));
        }
    }
}
