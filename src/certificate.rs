//! The certificate a run writes: what was run (scene digest, canonical graph, claims, solver),
//! what the checker saw (every checkpoint's enclosure of every claim's deviation), and what it
//! concluded.

use crate::report::Summary;
use lagra_checker::claims::Claim;
use lagra_checker::model::Model;
use lagra_checker::monitor::Trail;
use lagra_kernel::run::Report;
use lagra_kernel::scene::Scene;
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::io::{BufWriter, Write};
use std::path::Path;

pub const FORMAT: &str = "lagra-certificate/0";

#[derive(Serialize)]
struct Run<'a> {
    integrator: &'a str,
    dt: f64,
    steps: u64,
}

#[derive(Serialize)]
struct Certificate<'a> {
    format: &'static str,
    scene: &'a str,
    /// SHA-256 of the scene's source text.
    digest: String,
    model: &'a Model,
    claims: &'a [Claim],
    run: Run<'a>,
    trails: &'a [Trail],
    verdicts: Vec<&'a str>,
}

pub fn write(path: &Path, source: &str, scene: &Scene, r: &Report, s: &Summary) -> std::io::Result<()> {
    let digest: String = Sha256::digest(source.as_bytes()).iter().map(|b| format!("{b:02x}")).collect();
    let c = Certificate {
        format: FORMAT,
        scene: &scene.name,
        digest: format!("sha256:{digest}"),
        model: &scene.model,
        claims: &scene.claims,
        run: Run { integrator: scene.solver.integrator.name(), dt: scene.solver.dt, steps: r.steps },
        trails: &r.outcome.trails,
        verdicts: s.claims.iter().map(|c| c.line.as_str()).collect(),
    };
    let mut w = BufWriter::new(std::fs::File::create(path)?);
    serde_json::to_writer(&mut w, &c)?;
    writeln!(w)?;
    w.flush()
}
