//! `lagra view TRACE.jsonl`: one self-contained HTML file (no network at view time) that plays a
//! run in 3D — bodies coloured by the scene (colour charge, or electric charge), bonds and rods
//! drawn, the periodic box — with a time slider and plots of the energy witness, the momentum
//! and each claim's certified bound per checkpoint, a failing step marked in red. A pure
//! function of the trace (the contract between run and viewer), with the scene and the
//! certificate adding the looks and the bounds.

use lagra_checker::certificate::Certificate;
use lagra_checker::model::{Extent, Model};
use lagra_checker::terms::Shape;
use lagra_lang::scene::Scene;
use lagra_run::thinned::Thinned;
use lagra_run::trace::{Format, Frames, Writer};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

const TEMPLATE: &str = include_str!("view.html");

/// The trace text a page made by `lagra run --view` holds at most (a page much larger does not
/// load in a browser): past it, the frames are thinned (`lagra_run::thinned`).
pub const PAGE_TRACE_BYTES: usize = 64 << 20;

/// The frames of a page made during a run, as trace lines, thinned to `PAGE_TRACE_BYTES`.
pub struct PageFrames {
    lines: Option<Thinned<Vec<u8>>>,
    cell: Option<lagra_checker::model::Cell>,
    rigid: Vec<usize>,
}

impl PageFrames {
    pub fn new(model: &Model) -> Self {
        PageFrames { lines: None, cell: model.cell, rigid: lagra_run::trace::rigid_bodies(model) }
    }

    /// The trace text, and every how many frames one was kept.
    pub fn text(self) -> (String, u64) {
        let stride = self.lines.as_ref().map_or(1, Thinned::stride);
        let bytes = self.lines.map(Thinned::into_items).unwrap_or_default().concat();
        (String::from_utf8(bytes).expect("the trace writer writes UTF-8"), stride)
    }
}

impl Frames for PageFrames {
    fn frame(&mut self, s: &lagra_kernel::state::State, energy: f64) -> std::io::Result<()> {
        let mut line = Writer { out: vec![], format: Format::Jsonl, cell: self.cell, rigid: self.rigid.clone() };
        line.frame(s, energy)?;
        let lines = self.lines.get_or_insert_with(|| Thinned::new(PAGE_TRACE_BYTES / line.out.len().max(1)));
        lines.push(line.out);
        Ok(())
    }
}

#[derive(clap::Args)]
pub struct Args {
    /// The trace `lagra run --trace` wrote (one JSON line per frame).
    trace: PathBuf,
    /// The scene, for the bodies' sizes and colours, the bonds and the box.
    #[arg(long, value_name = "FILE.lagra")]
    scene: Option<PathBuf>,
    /// The run's certificate, for each claim's certified bound per checkpoint (and the model, if
    /// no scene is given).
    #[arg(long, value_name = "FILE")]
    certificate: Option<PathBuf>,
    /// Where to write the page (default: the trace's name with .html).
    #[arg(short, long, value_name = "FILE.html")]
    out: Option<PathBuf>,
}

#[derive(Serialize)]
struct Frame {
    step: u64,
    t: f64,
    x: Vec<[f64; 3]>,
    /// Each body's orientation (w, x, y, z), where the trace has them.
    #[serde(skip_serializing_if = "Option::is_none")]
    q: Option<Vec<[f64; 4]>>,
}

#[derive(Serialize)]
struct Body {
    size: f64,
    colour: String,
    /// A rigid body's solid (a box's half edges, a ball's radius), drawn turned as its frame's
    /// orientation says.
    #[serde(skip_serializing_if = "Option::is_none")]
    solid: Option<Extent>,
}

#[derive(Serialize)]
struct ClaimPlot {
    label: String,
    tol: f64,
    /// (step, certified upper bound of the deviation) per checkpoint.
    marks: Vec<[f64; 2]>,
    /// The checkpoint where it certainly failed.
    fail: Option<u64>,
}

#[derive(Serialize)]
struct Data {
    about: String,
    frames: Vec<Frame>,
    bodies: Vec<Body>,
    bonds: Vec<[usize; 2]>,
    #[serde(rename = "box")]
    cell: Option<[f64; 3]>,
    energy: Vec<[f64; 2]>,
    momentum: Vec<[f64; 2]>,
    claims: Vec<ClaimPlot>,
    verdicts: Vec<String>,
}

/// The colour a body is drawn in: its colour charge if it has one (red, green, blue and the
/// antis as their complements), else by its electric charge.
fn colour(weight: [f64; 2], charge: f64) -> String {
    const SU3: [([f64; 2], &str); 6] = [
        ([0.5, 0.2887], "#e53935"),
        ([-0.5, 0.2887], "#43a047"),
        ([0.0, -0.5774], "#1e88e5"),
        ([-0.5, -0.2887], "#00acc1"),
        ([0.5, -0.2887], "#d81b60"),
        ([0.0, 0.5774], "#fdd835"),
    ];
    if let Some((_, c)) = SU3.iter().find(|(w, _)| (w[0] - weight[0]).abs() < 1e-3 && (w[1] - weight[1]).abs() < 1e-3) {
        return c.to_string();
    }
    match charge.partial_cmp(&0.0) {
        Some(std::cmp::Ordering::Greater) => "#ef6c00".into(),
        Some(std::cmp::Ordering::Less) => "#3949ab".into(),
        _ => "#78909c".into(),
    }
}

/// The page for a trace, with what the scene and the certificate add.
pub fn page(trace: &str, name: &str, scene: Option<&Scene>, cert: Option<&Certificate>) -> Result<String, String> {
    let mut frames = vec![];
    let mut energy = vec![];
    for (k, line) in trace.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let at = format!("{name}:{}", k + 1);
        let v: serde_json::Value = serde_json::from_str(line).map_err(|e| format!("{at}: not a trace line: {e}"))?;
        let step = v["step"].as_u64().ok_or_else(|| format!("{at}: no `step`"))?;
        let t = v["t"].as_f64().ok_or_else(|| format!("{at}: no `t`"))?;
        let x: Vec<[f64; 3]> = serde_json::from_value(v["x"].clone()).map_err(|e| format!("{at}: `x`: {e}"))?;
        let vel: Vec<[f64; 3]> = serde_json::from_value(v["v"].clone()).map_err(|e| format!("{at}: `v`: {e}"))?;
        if x.iter().chain(&vel).flatten().any(|c| !c.is_finite()) {
            return Err(format!("{at}: a coordinate is not finite"));
        }
        let q: Option<Vec<[f64; 4]>> = match &v["q"] {
            serde_json::Value::Null => None,
            q => Some(serde_json::from_value(q.clone()).map_err(|e| format!("{at}: `q`: {e}"))?),
        };
        if let Some(q) = &q {
            let good = |q: &[f64; 4]| q.iter().all(|c| c.is_finite()) && q.iter().any(|&c| c != 0.0);
            if q.len() != x.len() || !q.iter().all(good) {
                return Err(format!(
                    "{at}: `q` must hold a finite, non-zero quaternion for each of the {} bodies",
                    x.len()
                ));
            }
        }
        if let Some(first) = frames.first().map(|f: &(Frame, Vec<[f64; 3]>)| f.0.x.len()) {
            if x.len() != first {
                return Err(format!("{at}: {} bodies where the first frame has {first}", x.len()));
            }
        }
        energy.push([t, v["energy"].as_f64().unwrap_or(f64::NAN)]);
        frames.push((Frame { step, t, x, q }, vel));
    }
    if frames.is_empty() {
        return Err(format!("{name} holds no frame"));
    }
    let n = frames[0].0.x.len();
    let model: Option<&Model> = scene.map(|s| &*s.model).or(cert.map(|c| &c.model));
    if let Some(m) = model.filter(|m| m.bodies.len() != n) {
        return Err(format!("the trace has {n} bodies, the scene {}", m.bodies.len()));
    }
    let e0 = energy[0][1];
    let energy: Vec<[f64; 2]> = energy
        .iter()
        .filter(|e| e[1].is_finite())
        .map(|e| [e[0], (e[1] - e0) / if e0 == 0.0 { 1.0 } else { e0.abs() }])
        .collect();
    let momentum = model.map_or(vec![], |m| {
        let p = |v: &[[f64; 3]]| -> [f64; 3] {
            std::array::from_fn(|c| v.iter().zip(&m.bodies).map(|(v, b)| b.mass * v[c]).sum())
        };
        let p0 = p(&frames[0].1);
        frames
            .iter()
            .map(|(f, v)| [f.t, p(v).iter().zip(p0).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()])
            .collect()
    });
    let bodies = (0..n)
        .map(|i| Body {
            size: scene.map_or(0.0, |s| s.sizes[i]),
            colour: model.map_or("#78909c".into(), |m| colour(m.bodies[i].colour, m.bodies[i].charge)),
            solid: model.and_then(|m| m.bodies[i].solid).map(|s| s.extent),
        })
        .collect();
    let bonds = model.map_or(vec![], |m| {
        let bonded = m.terms.iter().filter(|t| t.kind.spec().shape == Shape::Bond(2)).map(|t| [t.sites[0], t.sites[1]]);
        bonded.chain(m.constraints.iter().map(|c| c.bodies)).collect()
    });
    let cell = model.and_then(|m| m.cell).map(|c| c.size);
    let claims = cert.map_or(vec![], |c| {
        c.claims
            .iter()
            .zip(&c.trails)
            .map(|(claim, trail)| ClaimPlot {
                label: claim.label(),
                tol: trail.marks.iter().map(|m| m.tol).fold(0.0, f64::max),
                marks: trail.marks.iter().filter(|m| m.hi.is_finite()).map(|m| [m.step as f64, m.hi]).collect(),
                fail: trail.marks.iter().find(|m| m.lo > m.tol).map(|m| m.step),
            })
            .collect()
    });
    let title = scene.map(|s| s.name.clone()).or(cert.map(|c| c.scene.clone())).unwrap_or_else(|| name.to_string());
    let last = frames.last().map_or(0, |f| f.0.step);
    let data = Data {
        about: format!("{n} bodies, {} frames to step {last}", frames.len()),
        frames: frames.into_iter().map(|f| f.0).collect(),
        bodies,
        bonds,
        cell,
        energy,
        momentum,
        claims,
        verdicts: cert.map_or(vec![], |c| c.verdicts.clone()),
    };
    let json = serde_json::to_string(&data).map_err(|e| e.to_string())?;
    // `</` would end the script element early
    let json = json.replace("</", "<\\/");
    let title = title.replace('<', "&lt;");
    Ok(TEMPLATE.replace("__TITLE__", &title).replace("__DATA__", &json))
}

pub fn main(a: Args) -> ExitCode {
    let bad = |m: String| {
        eprintln!("lagra: {m}");
        ExitCode::from(2)
    };
    let name = a.trace.display().to_string();
    let trace = match crate::reading::text(&a.trace, crate::reading::Limits::from_env().certificate) {
        Ok(t) => t,
        Err(e) => return bad(e),
    };
    let scene = match &a.scene {
        None => None,
        Some(p) => {
            let path = p.display().to_string();
            match crate::reading::text(p, crate::reading::Limits::from_env().scene)
                .and_then(|s| lagra_run::compile(&s).map_err(|d| d.render(&path, &s).to_string()))
            {
                Ok(s) => Some(s),
                Err(e) => return bad(e),
            }
        }
    };
    let cert = match &a.certificate {
        None => None,
        Some(p) => match crate::reading::text(p, crate::reading::Limits::from_env().certificate)
            .and_then(|t| Certificate::read(&t))
        {
            Ok(c) => Some(c),
            Err(e) => return bad(format!("{}: {e}", p.display())),
        },
    };
    let out = a.out.unwrap_or_else(|| a.trace.with_extension("html"));
    match page(&trace, &name, scene.as_ref(), cert.as_ref())
        .and_then(|html| std::fs::write(&out, html).map_err(|e| format!("cannot write {}: {e}", out.display())))
    {
        Ok(()) => {
            println!("wrote {}", out.display());
            ExitCode::SUCCESS
        }
        Err(e) => bad(e),
    }
}
