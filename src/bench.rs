//! `lagra bench precision`: run time against error. Every integrator that applies at a ladder of
//! time steps on problems with a known answer — the harmonic oscillator (closed form), Kepler
//! orbits at e = 0.5 and 0.9 (back where they started after whole periods), the LJ liquid
//! (energy drift), a charge in a magnetic field and a rigid rotor (circles) — written as a CSV,
//! a log-log plot (one line per integrator) and the fitted orders.

use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::solvers::Stepper;
use lagra_kernel::state::{kinetic, State};
use lagra_lang::integrator::Integrator;
use lagra_run::compile;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use Integrator::*;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    study: Study,
}

#[derive(clap::Subcommand)]
enum Study {
    /// Work-precision study: precision.csv, precision.svg and precision.md in --out.
    Precision {
        /// Where to write the results.
        #[arg(long, default_value = "docs/bench")]
        out: PathBuf,
        /// Two time steps per problem and a short LJ run: a smoke test, not a study.
        #[arg(long)]
        quick: bool,
    },
    /// The per-step overhead of the engine: the two-bead oscillator through `lagra`'s run loop
    /// against a hand-written velocity Verlet loop, interleaved in one process; prints the ratio.
    Overhead {
        /// Steps per timing.
        #[arg(long, default_value_t = 2_000_000)]
        steps: u64,
        /// Timings of each; the fastest counts (the least disturbed by other load).
        #[arg(long, default_value_t = 7)]
        repeats: u32,
        /// Both timings and their ratio as one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// The cost of a gradient: the reverse-mode gradient of energy@end with respect to the LJ
    /// parameters against the forward run alone, on the 256-atom liquid and the 32,000-atom
    /// benchmark, interleaved in one process (the fastest of --repeats of each).
    Gradient {
        /// Timings of each; the fastest counts.
        #[arg(long, default_value_t = 3)]
        repeats: u32,
        /// Only the 256-atom liquid (a smoke run).
        #[arg(long)]
        quick: bool,
        /// Threads for both the forward run and the gradient (the same bits on any count).
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Each system's forward and gradient times and their ratio as JSON.
        #[arg(long)]
        json: bool,
    },
    /// The Lennard-Jones fluid against the NIST Monte Carlo NVT table: each state point's scene
    /// run under its Nosé–Hoover chain, ⟨U⟩/N and ⟨P⟩ beside the published values.
    Validation {
        /// Where the table (nist_mc_nvt.csv) and its scenes are.
        #[arg(long, default_value = "scenes/validation")]
        dir: PathBuf,
        /// Also write the table as validation_table.md here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Only the state points whose scene path contains this (e.g. `t085_rho0860`).
        #[arg(long)]
        only: Option<String>,
        /// 12,000 steps each, equilibrating over the first 10 time units: a smoke run.
        #[arg(long)]
        quick: bool,
        /// Each state point's measured and published values as JSON.
        #[arg(long)]
        json: bool,
    },
    /// What compensated summation buys: the energy and momentum witnesses of the 32,000-atom LJ
    /// benchmark summed plainly, compensated (Neumaier) and exactly, at the start and after
    /// --steps steps.
    Summation {
        /// Steps between the first and the last state compared.
        #[arg(long, default_value_t = 100)]
        steps: u64,
        /// The three sums of each witness at both states, as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// One problem: a scene, how long to run it, the time steps to try, its error measure, the
/// integrators that apply, and the time an action window spans (a fraction of the fastest
/// period: the descent contracts by about (ω·window)² a round).
struct Problem {
    name: &'static str,
    scene: String,
    t_end: f64,
    dts: Vec<f64>,
    error: fn(&State, &State, &Energy) -> f64,
    what: &'static str,
    integrators: &'static [Integrator],
    window: f64,
}

/// The integrators for conservative point masses (Boris and RATTLE are Verlet there).
const CONSERVATIVE: &[Integrator] = &[VelocityVerlet, SymplecticEuler, Yoshida4, Rk4, ActionDescent];

/// The total energy at the start and at the end of a run (f64 witnesses).
struct Energy {
    start: f64,
    end: f64,
}

/// A harmonic pair, μ = ½, k = 2 (ω = 2), stretched by 0.7 at rest: r(t) = 2 + 0.7 cos 2t.
const OSCILLATOR: &str = "scene o {
  entity { position: [-1.35, 0, 0], mass: 1 }
  entity { position: [1.35, 0, 0], mass: 1 }
  bond harmonic [0, 1] { k: 2, r0: 2 }
  solver { dt: 0.01 } }";

/// A two-body Kepler orbit with a = 1, GM = 1 (period 2π), released at apoapsis.
fn kepler(e: f64) -> String {
    let (sep, v) = (1.0 + e, ((1.0 - e) / (1.0 + e)).sqrt());
    format!(
        "scene k {{
  entity {{ position: [{}, 0, 0], velocity: [0, {}, 0], mass: 0.9 }}
  entity {{ position: [{}, 0, 0], velocity: [0, {}, 0], mass: 0.1 }}
  interaction gravity {{ G: 1 }}
  solver {{ dt: 0.01 }} }}",
        -0.1 * sep,
        -0.1 * v,
        0.9 * sep,
        0.9 * v
    )
}

/// A charge (q = m = 1) in B = 2ẑ on a circle of radius ½ about the origin (ω = 2).
const CYCLOTRON: &str = "scene c {
  entity { position: [0.5, 0, 0], velocity: [0, -1, 0], mass: 1, charge: 1 }
  magnetic { B: [0, 0, 2] }
  solver { dt: 0.01 } }";

/// Two unit masses held 1 apart by a rod, spinning at ω = 2 about their centre.
const ROTOR: &str = "scene r {
  entity { position: [-0.5, 0, 0], velocity: [0, -1, 0], mass: 1 }
  entity { position: [0.5, 0, 0], velocity: [0, 1, 0], mass: 1 }
  constraint [0, 1] { length: 1 }
  solver { dt: 0.01 } }";

/// How far a body is from the point at angle ±2t on the circle of radius ½ it started on.
fn off_circle(s: &State, body: usize, sense: f64) -> f64 {
    distance(s.x[body], [0.5 * (2.0 * s.t).cos(), sense * 0.5 * (2.0 * s.t).sin(), 0.0])
}

fn separation(s: &State) -> [f64; 3] {
    std::array::from_fn(|c| s.x[1][c] - s.x[0][c])
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
}

fn problems(quick: bool) -> Vec<Problem> {
    let ladder = |first: f64, n: usize| (0..n).map(|k| first / 2f64.powi(k as i32)).collect::<Vec<_>>();
    let n = if quick { 2 } else { 6 };
    let orbits = if quick { 1.0 } else { 10.0 };
    let lj = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/lj_liquid.lagra"))
        .expect("scenes/lj_liquid.lagra ships with the source");
    vec![
        Problem {
            name: "oscillator",
            scene: OSCILLATOR.into(),
            t_end: 10.0,
            dts: ladder(0.2, n),
            error: |_, s, _| (distance(s.x[0], s.x[1]) - (2.0 + 0.7 * (2.0 * s.t).cos())).abs(),
            what: "error of r(t) against the closed form at t = 10",
            integrators: CONSERVATIVE,
            window: 0.1,
        },
        Problem {
            name: "kepler_e0.5",
            scene: kepler(0.5),
            t_end: orbits * std::f64::consts::TAU,
            dts: ladder(0.02, n),
            error: |s0, s, _| distance(separation(s), separation(s0)),
            what: "distance from the start after 10 periods (phase and period error)",
            integrators: CONSERVATIVE,
            window: 0.02,
        },
        Problem {
            name: "kepler_e0.9",
            scene: kepler(0.9),
            t_end: orbits * std::f64::consts::TAU,
            dts: ladder(0.004, n),
            error: |s0, s, _| distance(separation(s), separation(s0)),
            what: "distance from the start after 10 periods (phase and period error)",
            integrators: CONSERVATIVE,
            window: 0.004,
        },
        Problem {
            name: "lj_liquid",
            scene: lj,
            t_end: if quick { 0.1 } else { 5.0 },
            dts: ladder(0.01, if quick { 2 } else { 4 }),
            error: |_, _, e| ((e.end - e.start) / e.start).abs(),
            what: "relative energy error at t = 5 (256 atoms)",
            integrators: CONSERVATIVE,
            window: 0.04,
        },
        Problem {
            name: "cyclotron",
            scene: CYCLOTRON.into(),
            t_end: 10.0,
            dts: ladder(0.2, n),
            error: |_, s, _| off_circle(s, 0, -1.0),
            what: "distance from the exact circle at t = 10 (charge in B)",
            integrators: &[VelocityVerlet, Boris, Yoshida4, Rk4],
            window: 0.0,
        },
        Problem {
            name: "rigid_rotor",
            scene: ROTOR.into(),
            t_end: 10.0,
            dts: ladder(0.2, n),
            error: |_, s, _| off_circle(s, 1, 1.0),
            what: "distance from the exact circle at t = 10 (two bodies on a rod)",
            integrators: &[Rattle],
            window: 0.0,
        },
    ]
}

struct Row {
    problem: &'static str,
    integrator: Integrator,
    dt: f64,
    steps: u64,
    wall_s: f64,
    error: f64,
}

/// Runs to exactly `t_end`: the time step is the nominal one shortened to divide it, since a
/// final time off by a fraction of a step would add a first-order phase error to every method.
fn measure(p: &Problem, integrator: Integrator, nominal: f64) -> Result<Row, String> {
    let scene = compile(&p.scene).map_err(|d| d.render(p.name, &p.scene).to_string())?;
    let graph = LagrangianGraph::new(&scene.model);
    let s0 = lagra_kernel::setup::start(&scene);
    let mut s = s0.clone();
    let steps = (p.t_end / nominal).ceil() as u64;
    let dt = p.t_end / steps as f64;
    let mut settings = integrator.defaults();
    settings.window = ((p.window / dt).floor() as u32).max(1);
    let start = Instant::now();
    let mut stepper = Stepper::new(integrator, settings, &graph, &s).map_err(|e| e.to_string())?;
    let e0 = kinetic(&s, &graph.masses) + stepper.potential();
    for _ in 0..steps {
        stepper.step(&graph, &mut s, dt).map_err(|e| format!("{} {} dt {dt}: {e}", p.name, integrator.name()))?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let energy = Energy { start: e0, end: kinetic(&s, &graph.masses) + stepper.potential() };
    Ok(Row { problem: p.name, integrator, dt, steps, wall_s, error: (p.error)(&s0, &s, &energy) })
}

/// The least-squares slope of log(error) against log(dt): the observed order.
fn order(rows: &[&Row]) -> Option<f64> {
    let pts: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.error > 0.0 && r.error.is_finite()).map(|r| (r.dt.ln(), r.error.ln())).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    Some(sxy / sxx)
}

fn plot(path: &PathBuf, problems: &[Problem], rows: &[Row]) -> Result<(), String> {
    let root = SVGBackend::new(path, (1100, 1350)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let colours = [RED, BLUE, BLACK, GREEN, MAGENTA, CYAN, RGBColor(230, 140, 0)];
    for (area, p) in root.split_evenly((3, 2)).iter().zip(problems) {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.problem == p.name && r.error > 0.0).collect();
        let bounds = |f: fn(&Row) -> f64| {
            mine.iter().map(|r| f(r)).fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)))
        };
        let ((t0, t1), (e0, e1)) = (bounds(|r| r.wall_s.max(1e-6)), bounds(|r| r.error.max(1e-16)));
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{}: {}", p.name, p.what), ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d((t0 / 2.0..t1 * 2.0).log_scale(), (e0 / 10.0..e1 * 10.0).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("wall time (s)")
            .y_desc("error")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        for (integrator, colour) in Integrator::ALL.into_iter().zip(colours).filter(|(i, _)| p.integrators.contains(i))
        {
            let pts: Vec<(f64, f64)> = mine
                .iter()
                .filter(|r| r.integrator == integrator)
                .map(|r| (r.wall_s.max(1e-6), r.error.max(1e-16)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(integrator.name())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}

pub fn main(a: Args) -> ExitCode {
    let result = match a.study {
        Study::Precision { out, quick } => precision(&out, quick),
        Study::Overhead { steps, repeats, json } => overhead(steps, repeats, json),
        Study::Gradient { repeats, quick, threads, json } => gradient_cost(repeats, quick, threads, json),
        Study::Validation { dir, out, only, quick, json } => {
            crate::validation::study(&dir, out.as_deref(), only.as_deref(), quick, json)
        }
        Study::Summation { steps, json } => crate::summation::study(steps).and_then(|s| {
            if json {
                serde_json::to_string_pretty(&s).map(|t| t + "\n").map_err(|e| e.to_string())
            } else {
                Ok(s.render())
            }
        }),
    };
    match result {
        Ok(summary) => {
            print!("{summary}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("lagra: {e}");
            ExitCode::from(2)
        }
    }
}

fn precision(out: &PathBuf, quick: bool) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let problems = problems(quick);
    let mut rows = vec![];
    for p in &problems {
        for &integrator in p.integrators {
            for &dt in &p.dts {
                eprint!("\r{:<12} {:<16} dt {dt:<10}", p.name, integrator.name());
                rows.push(measure(p, integrator, dt)?);
            }
        }
    }
    eprintln!();
    let mut csv = String::from("problem,integrator,dt,steps,wall_s,error\n");
    for r in &rows {
        let _ =
            writeln!(csv, "{},{},{:e},{},{:e},{:e}", r.problem, r.integrator.name(), r.dt, r.steps, r.wall_s, r.error);
    }
    let write = |name: &str, text: &str| {
        std::fs::write(out.join(name), text).map_err(|e| format!("cannot write {}: {e}", out.join(name).display()))
    };
    write("precision.csv", &csv)?;
    plot(&out.join("precision.svg"), &problems, &rows)?;
    // a column for each integrator some problem runs (the contact solvers have none here)
    let used: Vec<Integrator> =
        Integrator::ALL.into_iter().filter(|i| problems.iter().any(|p| p.integrators.contains(i))).collect();
    let names: Vec<&str> = used.iter().map(|i| i.name()).collect();
    let mut md = format!(
        "| problem | error measure | {} |\n|---|---|{}\n| | theory | {} |\n",
        names.join(" | "),
        "---|".repeat(names.len()),
        used.iter().map(|i| i.order().to_string()).collect::<Vec<_>>().join(" | ")
    );
    for p in &problems {
        let orders: Vec<String> = used
            .iter()
            .copied()
            .map(|i| {
                let mine: Vec<&Row> = rows.iter().filter(|r| r.problem == p.name && r.integrator == i).collect();
                order(&mine).map_or("—".into(), |o| format!("{o:.2}"))
            })
            .collect();
        let _ = writeln!(md, "| {} | {} | {} |", p.name, p.what, orders.join(" | "));
    }
    write("precision.md", &md)?;
    // keep the table in the folder's README (docs/bench/README.md) true
    let readme = out.join("README.md");
    if let Ok(text) = std::fs::read_to_string(&readme) {
        let (open, close) = ("<!-- precision: begin -->\n", "<!-- precision: end -->");
        if let (Some(a), Some(b)) = (text.find(open), text.find(close)) {
            write("README.md", &format!("{}{open}{md}{}", &text[..a], &text[b..]))?;
        }
    }
    Ok(format!("observed orders (slope of log error against log dt):\n{md}wrote precision.csv, precision.svg, precision.md in {}\n", out.display()))
}

/// One row of `lagra bench gradient`.
#[derive(serde::Serialize)]
struct GradientCost {
    system: String,
    bodies: usize,
    steps: u64,
    forward_s: f64,
    reverse_s: f64,
    ratio: f64,
    /// Of `reverse_s`, the share outside every pass that spreads over threads
    /// (`lagra_kernel::spread`): what more threads cannot shorten.
    reverse_serial: f64,
    states_kept: usize,
    /// The states the reverse pass keeps at once (positions, velocities, forces), in bytes.
    state_bytes: usize,
}

fn gradient_cost(repeats: u32, quick: bool, threads: usize, json: bool) -> Result<String, String> {
    let threads = lagra_run::run::threads_for(0, Some(threads))?;
    use lagra_lang::params;
    use lagra_run::grad::{gradient, objective_value, Method, Objective, Request};
    let root = env!("CARGO_MANIFEST_DIR");
    let mut systems = vec![("lj_liquid", format!("{root}/scenes/lj_liquid.lagra"), 1000u64, "lj_shifted")];
    if !quick {
        systems.push(("lj_32k", format!("{root}/scenes/bench/lj_32k.lagra"), 100, "lj"));
    }
    let mut rows = vec![];
    for (name, path, steps, term) in systems {
        let text = std::fs::read_to_string(&path).map_err(|e| format!("{path}: {e}"))?;
        let mut scene = compile(&text).map_err(|d| d.render(&path, &text).to_string())?;
        scene.solver.steps = steps;
        let objective = Objective::parse("energy@end", &scene)?;
        let wrt = params::parse_list(&format!("{term}.epsilon,{term}.sigma"), &scene)?;
        let (mut forward, mut reverse, mut kept, mut serial) = (f64::INFINITY, f64::INFINITY, 0, 0.0);
        for _ in 0..repeats.max(1) {
            let t = Instant::now();
            std::hint::black_box(objective_value(&scene, &objective, threads)?);
            forward = forward.min(t.elapsed().as_secs_f64());
            let (t, spread) = (Instant::now(), lagra_kernel::spread::spent());
            let g = gradient(
                Request { scene: &scene, objective: &objective, wrt: &wrt, threads, progress: None },
                Method::Reverse,
            )?;
            let (wall, spread) = (t.elapsed().as_secs_f64(), (lagra_kernel::spread::spent() - spread).as_secs_f64());
            if wall < reverse {
                (reverse, serial) = (wall, 1.0 - spread / wall);
            }
            kept = g.states_kept;
        }
        let bodies = scene.x0.len();
        rows.push(GradientCost {
            system: name.into(),
            bodies,
            steps,
            forward_s: forward,
            reverse_s: reverse,
            ratio: reverse / forward,
            reverse_serial: serial,
            states_kept: kept,
            state_bytes: kept * bodies * 72,
        });
    }
    if json {
        return serde_json::to_string_pretty(&rows).map(|t| t + "\n").map_err(|e| e.to_string());
    }
    let mut out = String::from("| system | bodies | steps | forward run | reverse gradient | ratio | its serial part | states kept | their memory |\n|---|---|---|---|---|---|---|---|---|\n");
    for r in &rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.3} s | {:.3} s | {:.2} | {:.1}% | {} | {:.1} MB |",
            r.system,
            r.bodies,
            r.steps,
            r.forward_s,
            r.reverse_s,
            r.ratio,
            100.0 * r.reverse_serial,
            r.states_kept,
            r.state_bytes as f64 / 1e6
        );
    }
    Ok(out)
}

/// The oscillator of `OSCILLATOR` by hand: the loop a person would write for two beads and one
/// spring, with nothing the engine adds (no graph, no dispatch, no checker, no trace).
fn hand_oscillator(steps: u64, dt: f64) -> [f64; 3] {
    let (k, r0, m) = (2.0, 2.0, 1.0);
    let mut x = [[-1.35, 0.0, 0.0], [1.35, 0.0, 0.0]];
    let mut v = [[0.0; 3]; 2];
    let force = |x: &[[f64; 3]; 2]| {
        let d: [f64; 3] = std::array::from_fn(|c| x[1][c] - x[0][c]);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let s = k * (r - r0) / r;
        std::array::from_fn::<f64, 3, _>(|c| s * d[c])
    };
    let mut f = force(&x);
    for _ in 0..steps {
        for c in 0..3 {
            v[0][c] += 0.5 * dt * f[c] / m;
            v[1][c] -= 0.5 * dt * f[c] / m;
            x[0][c] += dt * v[0][c];
            x[1][c] += dt * v[1][c];
        }
        f = force(&x);
        for c in 0..3 {
            v[0][c] += 0.5 * dt * f[c] / m;
            v[1][c] -= 0.5 * dt * f[c] / m;
        }
    }
    std::hint::black_box(x[1])
}

fn overhead(steps: u64, repeats: u32, json: bool) -> Result<String, String> {
    let scene = compile(OSCILLATOR).map_err(|d| d.render("oscillator", OSCILLATOR).to_string())?;
    let dt = scene.solver.dt;
    let (mut engine, mut hand) = (f64::INFINITY, f64::INFINITY);
    let mut agree = 0.0;
    for _ in 0..repeats {
        let t = Instant::now();
        let x = hand_oscillator(steps, dt);
        hand = hand.min(t.elapsed().as_secs_f64());
        let opts = lagra_run::run::Options::plain(Some(steps));
        let rep = lagra_run::run::run(&scene, opts)?;
        engine = engine.min(rep.wall_s);
        agree = distance(x, rep.state.x[1]);
    }
    let ratio = engine / hand;
    Ok(if json {
        format!("{{\"steps\": {steps}, \"engine_s\": {engine}, \"hand_s\": {hand}, \"ratio\": {ratio}, \"final_position_difference\": {agree}}}\n")
    } else {
        format!(
            "oscillator, {steps} steps, fastest of {repeats}: lagra {:.1} ns/step, hand-written loop {:.1} ns/step, ratio {ratio:.3}\n(final positions differ by {agree:.1e}: the same arithmetic up to the order of operations)\n",
            engine * 1e9 / steps as f64,
            hand * 1e9 / steps as f64
        )
    })
}
