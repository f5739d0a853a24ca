//! What every end-to-end test does: run the `lagra` binary from the repository root, read what
//! it said, write a scene to a file.
#![allow(dead_code)] // each test crate uses what it needs

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn lagra(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lagra")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Writes forged state-file bytes `b` back with their checksum made good, and the certificate
/// resealed to name it: what a forger who knows the formats would do, so only the re-evaluation
/// of the states can catch the forgery.
pub fn reseal(states: &Path, cert: &Path, mut b: Vec<u8>) {
    use lagra_checker::checksum::{label, Fnv};
    let n = b.len();
    let sum = Fnv::of(&b[..n - 8]);
    b[n - 8..].copy_from_slice(&sum.to_le_bytes());
    std::fs::write(states, &b).unwrap();
    let mut sealed: lagra_checker::certificate::Certificate =
        serde_json::from_str(&std::fs::read_to_string(cert).unwrap()).unwrap();
    sealed.states_checksum = Some(label(sum));
    std::fs::write(cert, sealed.seal().unwrap().to_json()).unwrap();
}

/// The text of the shipped scene `scenes/NAME`.
pub fn shipped(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).unwrap()
}

/// `lagra run --json ARGS`, its output and the report it printed.
pub fn run_json(args: &[&str]) -> (Output, serde_json::Value) {
    let mut a = vec!["run", "--json"];
    a.extend_from_slice(args);
    let o = lagra(&a);
    let v = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(&o)));
    (o, v)
}
