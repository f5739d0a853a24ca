//! `lagra list [DIR]`: the scenes, with their domains, terms and claims.

use lagra_kernel::lang::compile;
use serde::Serialize;
use std::path::PathBuf;
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
struct Entry {
    file: String,
    scene: String,
    domain: Option<String>,
    bodies: usize,
    terms: Vec<&'static str>,
    claims: Vec<String>,
    predictions: Vec<&'static str>,
}

pub fn main(a: Args) -> ExitCode {
    let mut files: Vec<PathBuf> = match std::fs::read_dir(&a.dir) {
        Ok(d) => {
            d.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|e| e == "lagra")).collect()
        }
        Err(e) => {
            eprintln!("lagra: cannot read {}: {e}", a.dir.display());
            return ExitCode::from(2);
        }
    };
    files.sort();
    let mut entries = vec![];
    for f in &files {
        let path = f.display().to_string();
        let source = std::fs::read_to_string(f).unwrap_or_default();
        match compile(&source) {
            Ok(s) => {
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
            Err(d) => {
                eprintln!("{}", d.render(&path, &source));
                return ExitCode::from(2);
            }
        }
    }
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
