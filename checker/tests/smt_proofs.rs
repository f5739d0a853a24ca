//! The SMT-LIB models in `checker/proofs/` are proved by z3: every query must be `unsat`.
//! z3 comes from PyPI (`z3-solver`); `setup.sh` installs it.

use std::path::Path;
use std::process::Command;

fn prove(file: &str, queries: usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("proofs").join(file);
    // a limit on the whole file, well above its need: the three files, proved side by side on
    // two cores, took 288 s in a CI run, and outward.smt2 once ran past 300 s under more load
    let out = Command::new("z3").arg("-T:900").arg(&path).output().unwrap_or_else(|e| {
        panic!("z3 is needed to prove {file} ({e}); `bash setup.sh` installs it from PyPI (z3-solver)")
    });
    let text = String::from_utf8_lossy(&out.stdout);
    let answers: Vec<&str> = text.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    assert_eq!(answers, vec!["unsat"; queries], "{file}: {text}{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn classify_is_sound_for_every_binary64() {
    prove("classify.smt2", 4);
}

#[test]
fn state_file_lengths_give_back_their_count() {
    prove("lengths.smt2", 1);
}

#[test]
fn outward_rounding_encloses_every_binary64_result() {
    prove("outward.smt2", 12);
}
