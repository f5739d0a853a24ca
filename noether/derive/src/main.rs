//! `lagra-derive`: derives the term × symmetry table with symbolica and writes
//! `noether/derived.json` and `docs/noether.md`; `--check` only compares them with what it
//! derives (exit 1 if stale). Results go to files, messages to stderr: symbolica prints its
//! licence notice on stdout, which this program does not otherwise use.

use lagra_noether_derive::{derive, lock::Exclusive, render};
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let check = match std::env::args().nth(1).as_deref() {
        None => false,
        Some("--check") => true,
        Some(_) => {
            eprintln!("usage: lagra-derive [--check]\n  writes noether/derived.json and docs/noether.md (from the repository root)");
            return ExitCode::from(2);
        }
    };
    let _lock = match Exclusive::take() {
        Ok(l) => l,
        Err(e) => {
            eprintln!("lagra-derive: {e}");
            return ExitCode::from(2);
        }
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let table = derive::table();
    let files = [
        (root.join("noether/derived.json"), serde_json::to_string_pretty(&table).expect("a table serializes") + "\n"),
        (root.join("docs/noether.md"), render::markdown(&table)),
    ];
    let mut stale = false;
    for (path, text) in &files {
        let same = std::fs::read_to_string(path).is_ok_and(|old| &old == text);
        if check {
            if !same {
                eprintln!(
                    "lagra-derive: {} is stale: run `cargo run --release -p lagra-noether-derive`",
                    path.display()
                );
                stale = true;
            }
        } else if let Err(e) = std::fs::write(path, text) {
            eprintln!("lagra-derive: cannot write {}: {e}", path.display());
            return ExitCode::from(2);
        } else {
            eprintln!("lagra-derive: wrote {}", path.display());
        }
    }
    if stale {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
