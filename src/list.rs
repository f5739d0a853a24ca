//! `lagra list [DIR]`: the scenes, with their domains, terms and claims.

use lagra_run::compile;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// The folder to list (default: scenes).
    #[arg(default_value = "scenes")]
    dir: PathBuf,
    /// One JSON document instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
pub struct Entry {
    file: String,
    scene: String,
    domain: Option<String>,
    bodies: usize,
    terms: Vec<&'static str>,
    claims: Vec<String>,
    predictions: Vec<&'static str>,
}

/// The `.lagra` files of a folder, sorted.
pub fn files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let d = std::fs::read_dir(dir).map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> =
        d.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|e| e == "lagra")).collect();
    files.sort();
    Ok(files)
}

/// Every scene of a folder, or the first one that does not compile (its located diagnostic).
pub fn entries(dir: &Path) -> Result<Vec<Entry>, String> {
    entries_within(dir, &|f| Ok(f.to_path_buf()))
}

/// The same, of the files `allowed` resolves (the MCP server's roots); the others are left out.
pub fn entries_within(dir: &Path, allowed: &dyn Fn(&Path) -> Result<PathBuf, String>) -> Result<Vec<Entry>, String> {
    let mut entries = vec![];
    for f in files(dir)? {
        let Ok(file) = allowed(&f) else { continue };
        let path = f.display().to_string();
        let source = crate::reading::text(&file, crate::reading::Limits::from_env().scene)?;
        let s = compile(&source).map_err(|d| d.render(&path, &source).to_string())?;
        let mut terms: Vec<&str> = vec![];
        for t in &s.model.terms {
            if !terms.contains(&t.kind.name()) {
                terms.push(t.kind.name());
            }
        }
        entries.push(Entry {
            file: path,
            scene: s.name,
            domain: s.domain,
            bodies: s.model.bodies.len(),
            terms,
            claims: s.claims.iter().map(|c| c.label()).collect(),
            predictions: s.predictions.iter().map(|p| p.kind.name()).collect(),
        });
    }
    Ok(entries)
}

pub fn main(a: Args) -> ExitCode {
    let entries = match entries(&a.dir) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("{}", if e.starts_with("cannot read") { format!("lagra: {e}") } else { e });
            return ExitCode::from(2);
        }
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&entries).expect("plain data"));
    } else {
        for e in &entries {
            println!("{}  ({}, {} bodies, {})", e.scene, e.file, e.bodies, e.domain.as_deref().unwrap_or("no domain"));
            println!("    terms        {}", e.terms.join(", "));
            println!("    claims       {}", e.claims.join(", "));
            if !e.predictions.is_empty() {
                println!("    predictions  {}", e.predictions.join(", "));
            }
        }
    }
    ExitCode::SUCCESS
}
