//! `lagra-check CERTIFICATE... [--states FILE]...`: the re-check, with no kernel code linked.

use lagra_checker::cli::{check_chain, USAGE};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let (mut certs, mut states) = (vec![], vec![]);
    while let Some(a) = args.next() {
        match a.as_str() {
            "-h" | "--help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            "--states" => match args.next() {
                Some(s) => states.push(PathBuf::from(s)),
                None => return usage("--states needs a file"),
            },
            _ if a.starts_with('-') => return usage(&format!("unknown option {a}")),
            _ => certs.push(PathBuf::from(a)),
        }
    }
    if certs.is_empty() {
        return usage("no certificate given");
    }
    if !states.is_empty() && states.len() != certs.len() {
        return usage(&format!(
            "{} state files for {} certificates: one per certificate, in order",
            states.len(),
            certs.len()
        ));
    }
    let r = check_chain(&paths(&certs), &paths(&states));
    print!("{}", r.stdout);
    eprint!("{}", r.stderr);
    let _ = std::io::stdout().flush();
    ExitCode::from(r.code)
}

fn usage(msg: &str) -> ExitCode {
    eprintln!("lagra-check: {msg}\n\n{USAGE}");
    ExitCode::from(2)
}

fn paths(v: &[PathBuf]) -> Vec<&std::path::Path> {
    v.iter().map(PathBuf::as_path).collect()
}
