//! `lagra-check CERTIFICATE [--states FILE]`: the re-check, with no kernel code linked.

use lagra_checker::cli::{check, USAGE};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let (mut cert, mut states) = (None, None);
    while let Some(a) = args.next() {
        match a.as_str() {
            "-h" | "--help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            "--states" => match args.next() {
                Some(s) => states = Some(PathBuf::from(s)),
                None => return usage("--states needs a file"),
            },
            _ if a.starts_with('-') => return usage(&format!("unknown option {a}")),
            _ if cert.is_none() => cert = Some(PathBuf::from(a)),
            _ => return usage(&format!("unexpected argument {a}")),
        }
    }
    let Some(cert) = cert else { return usage("no certificate given") };
    let r = check(&cert, states.as_deref());
    print!("{}", r.stdout);
    eprint!("{}", r.stderr);
    let _ = std::io::stdout().flush();
    ExitCode::from(r.code)
}

fn usage(msg: &str) -> ExitCode {
    eprintln!("lagra-check: {msg}\n\n{USAGE}");
    ExitCode::from(2)
}
