//! `lagra grad SCENE --objective ... --wrt ...` and `lagra fit SCENE --target TRACE --wrt ...`.

use crate::progress::{Progress, When};
use argmin::core::{CostFunction, Executor, Gradient as ArgminGradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use lagra_lang::params;
use lagra_lang::params::Named;
use lagra_lang::scene::Scene;
use lagra_run::compile;
use lagra_run::grad::{gradient, objective_value, Gradient, Method, Objective, Request};
use serde::ser::{Serialize, SerializeMap, Serializer};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

const SPELLINGS: &str = "Objectives: position[I].x@end (.y, .z), velocity[I].x@end, kinetic@end, potential@end, \
energy@end, distance[I,J]@end; @sum in place of @end sums over the run's frames (step 0, every steps_per_frame \
steps, the last); mse:FILE.jsonl is the mean squared distance of the positions from a trace in Lagra's format, at \
its steps.\n\nParameters: TERM.PARAM (its keyword: trap.k, lj.epsilon; a vector gives .x .y .z, or name one: \
gravity.g.y), TERM#N.PARAM for the N-th declaration of a keyword used more than once (from 0), body[I].mass, \
body[I].charge, body[I].position, body[I].velocity (.x .y .z, or one of them).\n\nThe gradient is exact for the \
floating-point run: reverse mode is the discrete adjoint of velocity Verlet (memory O(√steps)), forward mode one \
tangent sweep per parameter. A pair crossing a cutoff where the force jumps (lj, lj_shifted) has no derivative \
there: the gradient is that of the smooth pieces; lj_force_shifted is smooth through the cutoff.";

#[derive(clap::Args)]
#[command(after_help = SPELLINGS)]
pub struct GradArgs {
    /// The scene file (its solver must be velocity_verlet).
    file: PathBuf,
    /// What to differentiate (see below).
    #[arg(long, value_name = "OBJECTIVE")]
    objective: String,
    /// With respect to what: a comma-separated list of parameters (see below).
    #[arg(long, value_name = "PARAMS")]
    wrt: String,
    /// reverse (the discrete adjoint: one backward pass for all parameters), forward (one
    /// tangent sweep per parameter), or check (both, and their largest relative difference).
    #[arg(long, value_name = "METHOD", default_value = "reverse")]
    method: GradMethod,
    /// Set a parameter before the run: NAME=VALUE, with the spellings of --wrt (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Run this many steps instead of the scene's own run length.
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
    /// Threads for the forces (the same bits for any count).
    #[arg(long, value_name = "N", default_value_t = 1)]
    threads: usize,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// A progress bar on stderr: `auto` on a terminal when the work takes over two seconds.
    #[arg(long, value_name = "WHEN", default_value = "auto")]
    progress: When,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum GradMethod {
    Reverse,
    Forward,
    Check,
}

#[derive(clap::Args)]
#[command(after_help = SPELLINGS)]
pub struct FitArgs {
    /// The scene file, with the starting values of the parameters (or set them with --set).
    file: PathBuf,
    /// The trace to fit: Lagra's JSONL trace format (`lagra run --trace`).
    #[arg(long, value_name = "TRACE.jsonl")]
    target: PathBuf,
    /// The parameters to fit, comma-separated.
    #[arg(long, value_name = "PARAMS")]
    wrt: String,
    /// Set a parameter before fitting: NAME=VALUE (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// The most L-BFGS iterations.
    #[arg(long, value_name = "N", default_value_t = 50)]
    iterations: u64,
    /// Threads for each run of the scene and its gradient (the same bits for any count).
    #[arg(long, value_name = "N", default_value_t = 1)]
    threads: usize,
    /// Print one JSON object (the fitted and starting values, the loss at each, the iterations) instead of text.
    #[arg(long)]
    json: bool,
    /// A progress bar on stderr (the objective's evaluations): `auto` on a terminal when the fit
    /// takes over two seconds.
    #[arg(long, value_name = "WHEN", default_value = "auto")]
    progress: When,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn bad(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("lagra: {msg}");
    ExitCode::from(2)
}

/// The scene of a file, with `--set` and `--steps` applied; or the message to print.
fn load(file: &PathBuf, set: &[String], steps: Option<u64>) -> Result<Scene, String> {
    let path = file.display().to_string();
    let source = crate::reading::text(file, crate::reading::Limits::from_env().scene)?;
    let mut scene = compile(&source).map_err(|d| d.render(&path, &source).to_string())?;
    params::apply_settings(&mut scene, set)?;
    if let Some(n) = steps {
        if n == 0 {
            return Err("--steps must be at least 1".into());
        }
        scene.solver.steps = n;
    }
    Ok(scene)
}

/// A target trace (`mse:FILE`), read within the certificate limit (`reading::Limits`).
pub fn read_trace(file: &str) -> Result<String, String> {
    crate::reading::text(std::path::Path::new(file), crate::reading::Limits::from_env().certificate)
}

/// The peak resident memory of this process so far (Linux's VmHWM), if it says.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kb| kb * 1024)
}

/// A list of (name, value) written as a JSON object in its own order.
struct Ordered<'a>(&'a [(String, f64)]);

impl Serialize for Ordered<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// What `--json` prints.
#[derive(serde::Serialize)]
struct GradReport<'a> {
    objective: &'a str,
    value: f64,
    gradient: Ordered<'a>,
    method: &'a str,
    steps: u64,
    seconds: f64,
    peak_memory_bytes: Option<u64>,
    states_kept: usize,
    growth: lagra_run::grad::Growth,
    /// With --method check: the forward gradient and the largest relative difference.
    #[serde(skip_serializing_if = "Option::is_none")]
    forward: Option<Ordered<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max_relative_difference: Option<f64>,
    warning: Option<String>,
}

fn warning(g: &Gradient) -> Option<String> {
    g.growth.alarming().then(|| {
        format!(
            "the derivatives grew by a factor {:.1e} along the run (an e-folding rate of {:.3} per unit time): the run is chaotic over this span; the gradient is exact for this floating-point trajectory but says little about nearby ones",
            g.growth.factor, g.growth.rate_per_time
        )
    })
}

/// The gradients of `objective` by the chosen method(s), and the JSON report of them, as text
/// (the document `lagra grad --json` prints and the MCP tool returns). `tell` hears the progress.
pub fn compute(
    scene: &Scene,
    spelling: &str,
    wrt: &str,
    method: GradMethod,
    threads: usize,
    read: &dyn Fn(&str) -> Result<String, String>,
    tell: &mut (dyn FnMut(&str, u64, u64) + Send),
) -> Result<(Vec<Gradient>, String), String> {
    let objective = Objective::parse_reading(spelling, scene, read)?;
    let wrt = params::parse_list(wrt, scene)?;
    if threads == 0 {
        return Err("--threads must be at least 1".into());
    }
    let start = Instant::now();
    let methods: &[Method] = match method {
        GradMethod::Reverse => &[Method::Reverse],
        GradMethod::Forward => &[Method::Forward],
        GradMethod::Check => &[Method::Reverse, Method::Forward],
    };
    let mut results: Vec<Gradient> = vec![];
    for &m in methods {
        let request = Request { scene, objective: &objective, wrt: &wrt, threads, progress: Some(&mut *tell) };
        results.push(gradient(request, m)?);
    }
    let seconds = start.elapsed().as_secs_f64();
    let first = &results[0];
    let check = results.get(1).map(|f| {
        let scale = first.gradient.iter().fold(f64::MIN_POSITIVE, |s, g| s.max(g.1.abs()));
        first.gradient.iter().zip(&f.gradient).map(|(r, f)| (r.1 - f.1).abs() / scale).fold(0.0f64, f64::max)
    });
    let report = GradReport {
        objective: spelling,
        value: first.value,
        gradient: Ordered(&first.gradient),
        method: method.name(),
        steps: first.steps,
        seconds,
        peak_memory_bytes: peak_memory(),
        states_kept: first.states_kept,
        growth: first.growth,
        forward: results.get(1).map(|f| Ordered(&f.gradient)),
        max_relative_difference: check,
        warning: warning(first),
    };
    // written from the struct, so the derivatives keep the order they were asked in
    let doc = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    Ok((results, doc))
}

impl GradMethod {
    fn name(self) -> &'static str {
        match self {
            GradMethod::Reverse => "reverse",
            GradMethod::Forward => "forward",
            GradMethod::Check => "reverse+forward",
        }
    }

    /// From the name `--method` takes.
    pub fn from_name(s: &str) -> Option<GradMethod> {
        match s {
            "reverse" => Some(GradMethod::Reverse),
            "forward" => Some(GradMethod::Forward),
            "check" => Some(GradMethod::Check),
            _ => None,
        }
    }
}

pub fn grad(a: GradArgs) -> ExitCode {
    let scene = match load(&a.file, &a.set, a.steps) {
        Ok(s) => s,
        Err(e) if e.contains(": ") && e.contains('\n') => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
        Err(e) => return bad(e),
    };
    // bad spellings are bad input (2); a run that cannot be differentiated is not (1)
    if let Err(e) =
        Objective::parse_reading(&a.objective, &scene, &read_trace).and_then(|_| params::parse_list(&a.wrt, &scene))
    {
        return bad(e);
    }
    let passes =
        3 * scene.solver.steps * if a.method == GradMethod::Reverse { 1 } else { 1 + a.wrt.split(',').count() as u64 };
    let mut progress = Progress::new(a.progress.unless(a.quiet), passes);
    let mut count = 0u64;
    let mut tell = |what: &str, _done: u64, _of: u64| {
        count += 1;
        progress.iter_mut().for_each(|p| p.at_in(what, count.min(passes)));
    };
    let result = compute(&scene, &a.objective, &a.wrt, a.method, a.threads, &read_trace, &mut tell);
    progress.iter().for_each(Progress::done);
    let (results, doc) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("lagra: {e}");
            return ExitCode::from(1);
        }
    };
    if a.json {
        println!("{doc}");
        return ExitCode::SUCCESS;
    }
    let doc: serde_json::Value = serde_json::from_str(&doc).expect("written above");
    let first = &results[0];
    println!("scene       {}", scene.name);
    println!("objective   {} = {}", a.objective, first.value);
    println!(
        "method      {}: {} steps of velocity_verlet, {} states kept at most, {:.3} s, peak memory {}",
        a.method.name(),
        first.steps,
        first.states_kept,
        doc["seconds"].as_f64().unwrap_or(0.0),
        peak_memory().map_or("?".into(), |b| format!("{:.1} MB", b as f64 / 1e6))
    );
    let width = first.gradient.iter().map(|g| g.0.len()).max().unwrap_or(0);
    for (name, g) in &first.gradient {
        println!("∂J/∂{name:<width$} = {g:.10e}");
    }
    if let Some(d) = doc["max_relative_difference"].as_f64() {
        println!("check       forward mode agrees to {d:.1e} (largest difference over the largest derivative)");
    }
    if let Some(w) = doc["warning"].as_str() {
        println!("warning     {w}");
    }
    ExitCode::SUCCESS
}

/// The fit's problem: the mean squared distance from the target as a function of the parameters.
struct Fit<'a> {
    scene: &'a Scene,
    objective: &'a Objective,
    wrt: &'a [Named],
    threads: usize,
    /// The evaluations so far, shown on the progress bar.
    evaluations: std::cell::Cell<u64>,
    progress: &'a std::cell::RefCell<Option<Progress>>,
}

impl Fit<'_> {
    fn count(&self) {
        self.evaluations.set(self.evaluations.get() + 1);
        if let Some(p) = self.progress.borrow_mut().as_mut() {
            p.at_in("evaluations", self.evaluations.get());
        }
    }

    fn at(&self, p: &[f64]) -> Result<Scene, argmin::core::Error> {
        let mut s = self.scene.clone();
        for (n, &v) in self.wrt.iter().zip(p) {
            n.param.set(&mut s, v).map_err(|e| argmin::core::Error::msg(format!("{}: {e}", n.name)))?;
        }
        Ok(s)
    }
}

impl CostFunction for Fit<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        self.count();
        objective_value(&self.at(p)?, self.objective, self.threads).map_err(argmin::core::Error::msg)
    }
}

impl ArgminGradient for Fit<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, p: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        self.count();
        let s = self.at(p)?;
        let r = Request { scene: &s, objective: self.objective, wrt: self.wrt, threads: self.threads, progress: None };
        Ok(gradient(r, Method::Reverse).map_err(argmin::core::Error::msg)?.gradient.into_iter().map(|g| g.1).collect())
    }
}

#[derive(serde::Serialize)]
struct FitReport<'a> {
    target: String,
    fitted: Ordered<'a>,
    initial: Ordered<'a>,
    initial_loss: f64,
    final_loss: f64,
    iterations: u64,
    termination: String,
    seconds: f64,
}

pub fn fit(a: FitArgs) -> ExitCode {
    let scene = match load(&a.file, &a.set, None) {
        Ok(s) => s,
        Err(e) => return bad(e),
    };
    let target = format!("mse:{}", a.target.display());
    let objective = match Objective::parse(&target, &scene) {
        Ok(o) => o,
        Err(e) => return bad(e),
    };
    let wrt = match params::parse_list(&a.wrt, &scene) {
        Ok(w) => w,
        Err(e) => return bad(e),
    };
    let start = Instant::now();
    let initial: Vec<f64> = wrt.iter().map(|n| n.param.get(&scene)).collect();
    // L-BFGS with a Moré–Thuente line search: about three evaluations an iteration
    let progress = std::cell::RefCell::new(Progress::new(a.progress.unless(a.quiet), 3 * a.iterations));
    let problem = Fit {
        scene: &scene,
        objective: &objective,
        wrt: &wrt,
        threads: a.threads,
        evaluations: Default::default(),
        progress: &progress,
    };
    let initial_loss = match problem.cost(&initial) {
        Ok(l) => l,
        Err(e) => return bad(e),
    };
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_cost(1e-14)
        .and_then(|s| s.with_tolerance_grad(1e-12))
        .expect("valid tolerances");
    let result = Executor::new(problem, solver).configure(|s| s.param(initial.clone()).max_iters(a.iterations)).run();
    progress.borrow().iter().for_each(Progress::done);
    let res = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("lagra: the fit stopped: {e}");
            return ExitCode::from(1);
        }
    };
    let state = res.state();
    let best = state.get_best_param().cloned().unwrap_or(initial.clone());
    let named = |v: &[f64]| -> Vec<(String, f64)> { wrt.iter().zip(v).map(|(n, &x)| (n.name.clone(), x)).collect() };
    let (fitted, start_values) = (named(&best), named(&initial));
    let report = FitReport {
        target: a.target.display().to_string(),
        fitted: Ordered(&fitted),
        initial: Ordered(&start_values),
        initial_loss,
        final_loss: state.get_best_cost(),
        iterations: state.get_iter(),
        termination: state.get_termination_status().to_string(),
        seconds: start.elapsed().as_secs_f64(),
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report).expect("plain data"));
    } else {
        println!("fit         {} to {} (mean squared distance of the positions)", scene.name, report.target);
        for ((name, x), (_, x0)) in fitted.iter().zip(&start_values) {
            println!("{name} = {x:.12} (from {x0})");
        }
        println!(
            "loss        {:.3e} → {:.3e} in {} L-BFGS iterations ({}), {:.2} s",
            report.initial_loss, report.final_loss, report.iterations, report.termination, report.seconds
        );
    }
    ExitCode::SUCCESS
}
