//! The `lagra-derive` command (its `main`, `src/main.rs`, is one line): derives the term ×
//! symmetry table with symbolica and writes `noether/derived.json` and `docs/noether.md`;
//! `--check` only compares them with what it derives (exit 1 if stale); `--term NAME`
//! (repeatable) derives only those rows and takes the others from the checked-in table, for a
//! term just added or changed. Results go to files, messages (one line per term, with its time)
//! to stderr: symbolica prints its licence notice on stdout, which this program does not
//! otherwise use.

use crate::{derive, lock::Exclusive, render};
use lagra_checker::terms::Kind;
use lagra_noether::Table;
use std::path::Path;
use std::process::ExitCode;

const USAGE: &str = "usage: lagra-derive [--check] [--term NAME]...
  derives every term's symmetries with symbolica and writes noether/derived.json and
  docs/noether.md (from the repository root)
  --check      compare with the checked-in files instead of writing them (exit 1 if stale)
  --term NAME  derive only this term, named as in the table (Sph, HarmonicBond; repeatable):
               the other rows are the checked-in ones";

#[derive(Debug)]
struct Args {
    check: bool,
    only: Vec<Kind>,
}

/// The arguments after the program's name; `Ok(None)` when help was asked for.
fn args(mut it: impl Iterator<Item = String>) -> Result<Option<Args>, String> {
    let mut out = Args { check: false, only: vec![] };
    while let Some(a) = it.next() {
        match a.as_str() {
            "--check" => out.check = true,
            "--term" => {
                let name = it.next().ok_or("--term needs a term's name")?;
                let kind = Kind::ALL.iter().find(|k| k.name() == name).ok_or_else(|| {
                    let known: Vec<&str> = Kind::ALL.iter().map(|k| k.name()).collect();
                    format!("no term is called '{name}' (known: {})", known.join(", "))
                })?;
                out.only.push(*kind);
            }
            "-h" | "--help" => return Ok(None),
            other => return Err(format!("unknown argument '{other}'")),
        }
    }
    Ok(Some(out))
}

/// The checked-in table, whose other rows `--term` keeps: read before deriving, so that an
/// unreadable one is said at once rather than after minutes of symbolica.
fn checked_in(root: &Path) -> Result<Table, String> {
    let path = root.join("noether/derived.json");
    std::fs::read_to_string(&path)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
        .map_err(|e| format!("--term keeps the other rows of {}, which cannot be read: {e}", path.display()))
}

/// The command, given the arguments after the program's name.
pub fn main(argv: Vec<String>) -> ExitCode {
    let args = match args(argv.into_iter()) {
        Ok(Some(a)) => a,
        Ok(None) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("lagra-derive: {e}\n{USAGE}");
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
    let (kinds, kept) = if args.only.is_empty() {
        (Kind::ALL, Default::default())
    } else {
        match checked_in(&root) {
            Ok(t) => (&args.only[..], t.terms),
            Err(e) => {
                eprintln!("lagra-derive: {e}");
                return ExitCode::from(2);
            }
        }
    };
    let rows =
        derive::rows(kinds, |k, took| eprintln!("lagra-derive: {} derived in {:.1} s", k.name(), took.as_secs_f64()));
    let mut table = Table { derived_by: derive::derived_by(), terms: kept };
    table.terms.extend(rows);
    let files = [
        (root.join("noether/derived.json"), serde_json::to_string_pretty(&table).expect("a table serializes") + "\n"),
        (root.join("docs/noether.md"), render::markdown(&table)),
    ];
    let mut stale = false;
    for (path, text) in &files {
        let same = std::fs::read_to_string(path).is_ok_and(|old| &old == text);
        if args.check {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(a: &[&str]) -> Result<Option<Args>, String> {
        args(a.iter().map(|s| s.to_string()))
    }

    #[test]
    fn terms_are_named_as_in_the_table_and_help_is_not_an_error() {
        let a = parse(&["--check", "--term", "Sph", "--term", "HarmonicBond"]).unwrap().unwrap();
        assert!(a.check && a.only == [Kind::Sph, Kind::HarmonicBond]);
        assert!(parse(&["--help"]).unwrap().is_none());
        assert!(parse(&["--term", "Spring"]).unwrap_err().contains("no term is called 'Spring' (known: "));
        assert_eq!(parse(&["--term"]).unwrap_err(), "--term needs a term's name");
        assert_eq!(parse(&["-x"]).unwrap_err(), "unknown argument '-x'");
    }
}
