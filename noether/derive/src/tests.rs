//! The derivation, end to end, in one test: symbolica allows one thread per user, so everything
//! that touches it runs here in order, under the same lock `lagra-derive` takes. (A unit test of
//! the library, not an integration test: an integration test would have `cargo test` build the
//! `lagra-derive` binary with the release profile's fat LTO over all of symbolica, CI's longest
//! link, only to start it once.)

use crate::{derive, lock::Exclusive, render, sym};
use lagra_checker::model::Snapshot;
use lagra_checker::quantities::Lifted;
use lagra_checker::terms::{Kind, Shape};
use lagra_noether::{parameter_names, Symmetry, Table, Verdict};
use lagra_run::compile;
use lagra_run::run::{run, Options};
use lagra_run::trace::{Format, Writer};
use std::collections::HashMap;
use std::path::Path;
use symbolica::prelude::*;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

#[test]
fn the_derivation() {
    // Symbolica counts a thread as its user until the thread ends, so the work runs on a thread
    // of its own that takes the lock, and the lock is let go only once that thread is gone.
    let (locked, wait) = std::sync::mpsc::channel();
    let worker = std::thread::spawn(move || {
        let lock = Exclusive::take().expect("the symbolica lock");
        locked.send(()).unwrap();
        derivation();
        lock
    });
    wait.recv().expect("the worker took the lock");
    // A second derivation started now, in another process (this test binary again, running the
    // ignored test below), must wait for this one, not be killed by symbolica's one-thread rule:
    // it says so, and finishes once the lock is free.
    let mut second = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--ignored", "--exact", "tests::a_second_derivation", "--nocapture", "--test-threads=1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let lock = worker.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
    assert!(second.try_wait().unwrap().is_none(), "the second derivation did not wait for the lock");
    drop(lock);
    let out = second.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && err.contains("waiting for it"), "{:?} {err}", out.status);
}

/// The second process of `the_derivation`: takes the lock as `lagra-derive` does and derives
/// one row, which must be the checked-in one. Not run on its own (`--ignored` runs it alone).
#[test]
#[ignore = "run by the_derivation as a second process, to prove that it waits for the lock"]
fn a_second_derivation() {
    let _lock = Exclusive::take().expect("the symbolica lock");
    let row = std::thread::spawn(|| derive::rows(&[Kind::HarmonicBond], |_, _| ())).join().unwrap();
    let table: Table = serde_json::from_str(lagra_noether::DERIVED).unwrap();
    assert_eq!(row["HarmonicBond"], table.terms["HarmonicBond"]);
}

fn derivation() {
    // binary64 constants enter as the exact rationals they are
    assert_eq!(sym::exact(0.5), Atom::num(1) / Atom::num(2));
    assert_eq!(sym::exact(-3.0), Atom::num(-3));
    assert_eq!(sym::exact(0.1) * Atom::num(2).pow(Atom::num(55)), Atom::num(3602879701896397i64));

    let table = derive::table();
    checked_in_copies_are_current(&table);
    verdicts_are_the_physics(&table);
    for entry in std::fs::read_dir(root().join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "lagra") {
            charges_agree_with_the_checker(&table, &path);
        }
    }
}

/// `noether/derived.json` and `docs/noether.md` are what the derivation gives today.
fn checked_in_copies_are_current(table: &Table) {
    let json = serde_json::to_string_pretty(table).unwrap() + "\n";
    assert!(
        json == lagra_noether::DERIVED,
        "noether/derived.json is stale: run `cargo run --release -p lagra-noether-derive`"
    );
    let md = std::fs::read_to_string(root().join("docs/noether.md")).unwrap();
    assert!(
        render::markdown(table) == md,
        "docs/noether.md is stale: run `cargo run --release -p lagra-noether-derive`"
    );
}

fn verdicts_are_the_physics(t: &Table) {
    let v = |k: Kind, s: Symmetry| t.of(k).unwrap().lagrangian[&s].clone();
    let d = |k: Kind, s: Symmetry| t.of(k).unwrap().dissipation[&s].clone();
    // a spring keeps every symmetry; its damping acts on relative velocities and keeps them too,
    // but dissipates energy unless it is zero
    for s in Symmetry::ALL {
        assert_eq!(v(Kind::HarmonicBond, s), Verdict::Invariant, "{}", s.name());
        let diss = if s == Symmetry::Time {
            Verdict::WhenZero { any_of: vec![vec!["damping".into()]] }
        } else {
            Verdict::Invariant
        };
        assert_eq!(d(Kind::HarmonicBond, s), diss, "{}", s.name());
    }
    // every pair and bond term: all translations, rotations, boosts
    for &k in Kind::ALL.iter().filter(|k| !matches!(k.spec().shape, Shape::External)) {
        assert!(Symmetry::ALL.iter().all(|&s| v(k, s) == Verdict::Invariant), "{}", k.name());
    }
    // a floor breaks the translation along its normal and the rotations that tilt it
    for s in [Symmetry::TranslationY, Symmetry::RotationX, Symmetry::RotationZ] {
        assert!(!matches!(v(Kind::ContactFloor, s), Verdict::Invariant | Verdict::UpToBoundary { .. }), "{}", s.name());
    }
    for s in [Symmetry::TranslationX, Symmetry::TranslationZ, Symmetry::RotationY, Symmetry::Time] {
        assert_eq!(v(Kind::ContactFloor, s), Verdict::Invariant, "{}", s.name());
    }
    // uniform gravity breaks the translation along g, only if g has a component there; keeps energy
    assert_eq!(
        v(Kind::UniformAcceleration, Symmetry::TranslationY),
        Verdict::WhenZero { any_of: vec![vec!["g_1".into()]] }
    );
    assert_eq!(v(Kind::UniformAcceleration, Symmetry::Time), Verdict::Invariant);
    // a magnetic field: translations up to a boundary term (the pseudo-momentum), rotation about B
    assert!(matches!(v(Kind::MagneticField, Symmetry::TranslationX), Verdict::UpToBoundary { .. }));
    assert_eq!(
        v(Kind::MagneticField, Symmetry::RotationZ),
        Verdict::WhenZero { any_of: vec![vec!["B_0".into(), "B_1".into()]] }
    );
    // a trap keeps the rotations about an axis through its centre
    assert!(
        matches!(v(Kind::HarmonicTrap, Symmetry::RotationZ), Verdict::WhenZero { any_of } if any_of.contains(&vec!["center_0".into(), "center_1".into()]))
    );
    // drag keeps the Lagrangian's symmetries but its dissipation breaks every charge
    assert_eq!(
        d(Kind::Drag, Symmetry::TranslationX),
        Verdict::WhenZero { any_of: vec![vec![parameter_names(Kind::Drag)[0].clone()]] }
    );
}

/// The derived charges — Σ m v and Σ m x × v plus every term's symbolic share, evaluated in f64
/// through symbolica — equal the checker's momentum and angular momentum along a short run, to
/// round-off.
fn charges_agree_with_the_checker(t: &Table, path: &Path) {
    let source = std::fs::read_to_string(path).unwrap();
    let scene = compile(&source).unwrap_or_else(|d| panic!("{}", d.render(&path.display().to_string(), &source)));
    let mut trace = Writer::new(vec![], Format::Jsonl, &scene.model);
    let steps = scene.solver.steps.min(200);
    let opts = Options { trace: Some(&mut trace), ..Options::plain(Some(steps)) };
    run(&scene, opts).unwrap();
    let frames: Vec<serde_json::Value> =
        String::from_utf8(trace.out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert!(!frames.is_empty());
    let symbols = ["translation", "rotation"];
    for f in frames {
        let vec3 = |k: &str| -> Vec<[f64; 3]> { serde_json::from_value(f[k].clone()).unwrap() };
        let (x, v) = (vec3("x"), vec3("v"));
        let snap = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
        let q = Lifted::new(&scene.model, &snap, &0.0);
        let checker = [q.momentum(&scene.model), q.angular_momentum(&scene.model)];
        for (which, name) in symbols.iter().enumerate() {
            for a in 0..3 {
                let s =
                    Symmetry::ALL.into_iter().find(|s| s.name() == format!("{name}_{}", ["x", "y", "z"][a])).unwrap();
                let mut derived: f64 = scene
                    .model
                    .bodies
                    .iter()
                    .enumerate()
                    .map(|(i, b)| {
                        let (b1, b2) = ((a + 1) % 3, (a + 2) % 3);
                        b.mass * if which == 0 { v[i][a] } else { x[i][b1] * v[i][b2] - x[i][b2] * v[i][b1] }
                    })
                    .sum();
                for term in &scene.model.terms {
                    let Some(share) = t.of(term.kind).and_then(|e| e.charge_share.get(&s)) else { continue };
                    let expr = parse!(share);
                    let on: Vec<usize> =
                        if term.sites.is_empty() { (0..x.len()).collect() } else { term.sites.clone() };
                    for i in on {
                        let mut values: HashMap<Atom, f64> = HashMap::new();
                        for c in 0..3 {
                            values.insert(parse!(&format!("x0_{c}")), x[i][c]);
                            values.insert(parse!(&format!("v0_{c}")), v[i][c]);
                        }
                        values.insert(parse!("m0"), scene.model.bodies[i].mass);
                        values.insert(parse!("q0"), scene.model.bodies[i].charge);
                        for (name, p) in parameter_names(term.kind).iter().zip(&term.params) {
                            values.insert(parse!(name), *p);
                        }
                        derived += expr.evaluate(&values).unwrap_or_else(|e| panic!("{share}: {e:?}"));
                    }
                }
                let want = checker[which][a];
                let scale = 1e-12 * (1.0 + want.abs());
                assert!(
                    (derived - want).abs() <= scale,
                    "{}: {} derived {derived}, checker {want}",
                    path.display(),
                    s.charge()
                );
            }
        }
    }
}
