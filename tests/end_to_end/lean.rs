//! Lean 4 from the binary: the package's definitions are what the checker prints today, and a
//! certificate's obligations are exact and the same bytes every time (lean/check.sh has Lean
//! check both).

use crate::common::{lagra, stderr, stdout};
use std::path::Path;

/// The Lean definitions and invariance theorems in lean/Lagra are what the checker's term
/// definitions print today (lean/check.sh then has Lean check them).
#[test]
fn lean_definitions_are_current() {
    let dir = tempfile::tempdir().unwrap();
    let o = lagra(&["lean", "--definitions", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for f in ["Terms.lean", "Invariance.lean"] {
        let fresh = std::fs::read_to_string(dir.path().join(f)).unwrap();
        let shipped =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("lean/Lagra").join(f)).unwrap();
        assert!(fresh == shipped, "lean/Lagra/{f} is stale: run `lagra lean --definitions lean/Lagra`");
    }
}

/// `lagra lean CERT` writes one theorem per certified claim, with the checkpoints' binary64
/// values as exact rationals, the same bytes every time; a damaged certificate is refused.
#[test]
fn lean_obligations_are_exact_and_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let cert = dir.path().join("o.cert");
    let o = lagra(&["run", "scenes/oscillator.lagra", "--steps", "3000", "--certificate", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let a = lagra(&["lean", cert.to_str().unwrap()]);
    let b = lagra(&["lean", cert.to_str().unwrap()]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    assert!(a.stdout == b.stdout);
    let lean = stdout(&a);
    for t in [
        "theorem energy_conservation_holds",
        "theorem momentum_conservation_holds",
        "by decide +kernel",
        "Mark.flatten_ok",
    ] {
        assert!(lean.contains(t), "{t}");
    }
    // tol 1e-5 is the dyadic 5902958103587057 · 2^-69, written exactly
    assert!(lean.contains(", 5902958103587057, -69⟩"), "{lean}");
    let text = std::fs::read_to_string(&cert).unwrap();
    std::fs::write(&cert, &text[..text.len() / 2]).unwrap();
    let o = lagra(&["lean", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
}
