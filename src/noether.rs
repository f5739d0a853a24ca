//! Noether in the front: `lagra noether FILE` (what the scene's symmetries conserve and what
//! breaks the rest), and, for `lagra run`, the claims `@expect noether` stands for and the
//! warnings for declared claims the symmetries cannot support. The table comes from
//! `lagra-noether` (checked-in data): symbolica is never linked here.

use lagra_checker::claims::{Claim, ClaimKind};
use lagra_checker::model::Snapshot;
use lagra_checker::quantities::Lifted;
use lagra_lang::scene::Scene;
use lagra_lang::Diagnostic;
use lagra_noether::{analyse, Analysis, Status, Symmetry, Table};
use lagra_run::compile;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// The relative energy tolerance of a generated energy claim, when `@expect noether` gives none:
/// what velocity Verlet keeps at the time steps the shipped scenes use (they reach 1.2e-4).
pub const DEFAULT_TOL: f64 = 1e-3;

/// A generated momentum claim whose charge has a term's share (a magnetic field's) is held to
/// this fraction of the charge's scale: the integrator conserves such a charge only to its
/// truncation error, not to round-off (velocity Verlet with the implicit magnetic kick keeps the
/// charged particle's pseudo-momentum to about (ω dt)², bounded: 2e-6 of its scale at ω dt =
/// 2e-3 over 10⁵ steps).
pub const SHARE_TOL: f64 = 1e-4;

/// The scene's analysis, the warnings for declared claims it contradicts (as `file:line:col`
/// diagnostics), and, if the scene asks with `@expect noether`, its claims extended by the
/// generated ones. Returns how many were generated.
pub fn apply(scene: &mut Scene, path: &str, source: &str) -> (Analysis, Vec<String>, usize) {
    let analysis = analyse(&scene.model, Table::derived());
    let warnings = scene
        .claims
        .iter()
        .zip(&scene.claim_spans)
        .filter_map(|(c, at)| {
            analysis.contradiction(c).map(|why| {
                Diagnostic::new(*at, format!("warning: {} is not implied by the scene's symmetries: {why}", c.label()))
                    .render(path, source)
                    .to_string()
            })
        })
        .collect();
    let Some(req) = scene.noether.clone() else { return (analysis, warnings, 0) };
    let scale = charge_scales(scene);
    let generated = analysis.claims(req.tol.unwrap_or(DEFAULT_TOL), req.every, &scene.claims, |kind| {
        SHARE_TOL * if kind == ClaimKind::MomentumConservation { scale[0] } else { scale[1] }
    });
    let n = generated.len();
    scene.claim_spans.extend(std::iter::repeat_n(req.at, n));
    scene.claims.extend(generated);
    (analysis, warnings, n)
}

/// The scale of the momentum and the angular momentum: Σ m|v|₁ plus |P₀|₁, and that times a
/// length, the farthest a body starts from the origin plus the distance the fastest could cover
/// in the run, plus |L₀|₁; so that a tolerance relative to it means something even for a body
/// that starts at the origin.
fn charge_scales(scene: &Scene) -> [f64; 2] {
    let s = Snapshot { step: 0, t: 0.0, x: &scene.x0, v: &scene.v0, chain: &[], spin: &scene.spin0 };
    let q = Lifted::new(&scene.model, &s, &0.0);
    let norm1 = |v: &[f64; 3]| v.iter().map(|c| c.abs()).sum::<f64>();
    let largest = |a: &[[f64; 3]]| a.iter().map(norm1).fold(0.0, f64::max);
    let duration = scene.solver.dt * scene.solver.steps as f64;
    let length = largest(&scene.x0) + largest(&scene.v0) * duration;
    let mv: f64 = scene.v0.iter().zip(&scene.model.bodies).map(|(v, b)| b.mass * norm1(v)).sum();
    let p = mv + norm1(&q.momentum(&scene.model));
    [p, p * length + norm1(&q.angular_momentum(&scene.model))]
}

/// A note for a declared claim that FAILed although the symmetries support it.
pub fn note(analysis: &Analysis, c: &Claim) -> Option<String> {
    analysis.supports(c).then(|| {
        format!(
            "{}: the scene's symmetries conserve it (Noether), so its failure points at the integrator or a force, not at the physics",
            c.label()
        )
    })
}

#[derive(clap::Args)]
pub struct Args {
    /// The scene file.
    file: PathBuf,
    /// Print the analysis as one JSON document.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Line {
    symmetry: &'static str,
    charge: &'static str,
    /// conserved, balance or broken
    status: &'static str,
    /// What breaks it, or (for a balance) what dissipates.
    by: Vec<String>,
    /// The charge as a formula: the free bodies' part and each term's share.
    formula: String,
}

fn free_part(s: Symmetry) -> String {
    let axis = s.axis().map(|a| ["x", "y", "z"][a]).unwrap_or("");
    match s {
        Symmetry::TranslationX | Symmetry::TranslationY | Symmetry::TranslationZ => format!("Σ m v_{axis}"),
        Symmetry::RotationX | Symmetry::RotationY | Symmetry::RotationZ => format!("Σ m (x × v)_{axis}"),
        Symmetry::Time => "Σ ½ m |v|² + V".into(),
        Symmetry::BoostX | Symmetry::BoostY | Symmetry::BoostZ => format!("Σ m x_{axis} − t Σ m v_{axis}"),
    }
}

fn lines(a: &Analysis) -> Vec<Line> {
    let table = Table::derived();
    a.laws
        .iter()
        .map(|l| {
            let (status, by, shares) = match &l.status {
                Status::Conserved { shares } => ("conserved", vec![], shares.clone()),
                Status::Balance { by } => ("balance", by.iter().map(|k| k.name().to_string()).collect(), vec![]),
                Status::Broken { by } => ("broken", by.clone(), vec![]),
            };
            let mut formula = free_part(l.symmetry);
            for k in shares {
                if let Some(share) = table.of(k).and_then(|t| t.charge_share.get(&l.symmetry)) {
                    formula += &format!(" + Σ {}: {share}", k.name());
                }
            }
            Line { symmetry: l.symmetry.name(), charge: l.symmetry.charge(), status, by, formula }
        })
        .collect()
}

/// What `lagra noether` prints for a scene's source, as JSON and as text.
pub fn report(source: &str, path: &str) -> Result<(serde_json::Value, String), String> {
    let mut scene = compile(source).map_err(|d| d.render(path, source).to_string())?;
    let (analysis, _, _) = apply(&mut scene, path, source);
    let lines = lines(&analysis);
    let doc = serde_json::json!({ "scene": scene.name, "derived_by": Table::derived().derived_by, "laws": lines });
    let mut text = format!("scene {} — what its symmetries conserve (Noether), from the derived table\n", scene.name);
    for l in &lines {
        let what = match l.status {
            "conserved" => format!("conserved: {}", l.formula),
            "balance" => format!("a balance H + Q = H₀: dissipated by {}", l.by.join(", ")),
            _ => format!("broken by {}", l.by.join(", ")),
        };
        text += &format!("{:<20} {what}\n", l.charge);
    }
    Ok((doc, text))
}

pub fn main(a: Args) -> ExitCode {
    let path = a.file.display().to_string();
    let source = match crate::reading::text(&a.file, crate::reading::Limits::from_env().scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("lagra: {e}");
            return ExitCode::from(2);
        }
    };
    if let Ok(mut scene) = compile(&source) {
        apply(&mut scene, &path, &source).1.iter().for_each(|w| eprintln!("{w}"));
    }
    match report(&source, &path) {
        Ok((doc, text)) => {
            if a.json {
                println!("{}", serde_json::to_string_pretty(&doc).expect("plain data"));
            } else {
                print!("{text}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}
