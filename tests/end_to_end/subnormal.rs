//! The checker's arithmetic meets no subnormal number and makes none. On x86-64 the CPU keeps
//! sticky flags in MXCSR for an operand that was subnormal (DE) and for a result that
//! underflowed (UE): the same architectural flags on Intel and AMD. Intel cores take a ~40 ns
//! microcode assist for either, AMD's none, so a timing on an AMD machine cannot show the trap,
//! but the flags show it on any. Each scene's checkpoints (its first state, and the state 20
//! steps on, with its pairs listed ahead) are judged on this thread with the flags cleared,
//! and must leave DE and UE clear. (Before the step outward's floor was 2⁻⁵¹¹, a zero stepped
//! out to ±2⁻¹⁰²² and its square underflowed: at every pair of a lattice, every body at rest or
//! in a plane: 16 of the 21 scenes raised UE, 10 of them DE too.)
#![cfg(target_arch = "x86_64")]

use lagra_checker::monitor::Monitor;
use lagra_run::compile;
use lagra_run::run::{run, Options};
use std::arch::asm;
use std::path::PathBuf;

/// MXCSR's sticky flags: DE, an operand was subnormal; UE, a result underflowed.
const DE: u32 = 1 << 1;
const UE: u32 = 1 << 4;

fn mxcsr() -> u32 {
    let mut m: u32 = 0;
    // SAFETY: stmxcsr writes the four bytes of `m`
    unsafe { asm!("stmxcsr [{}]", in(reg) &mut m, options(nostack)) };
    m
}

/// Clears the six sticky exception flags (the masks and the rounding mode stay).
fn clear_flags() {
    let m = mxcsr() & !0x3f;
    // SAFETY: ldmxcsr reads the four bytes of `m`, a valid MXCSR (only flags cleared)
    unsafe { asm!("ldmxcsr [{}]", in(reg) &m, options(nostack, readonly)) };
}

/// Which of DE and UE `f` raised on this thread.
fn raised(f: impl FnOnce()) -> u32 {
    clear_flags();
    f();
    mxcsr() & (DE | UE)
}

/// The scenes with claims, up to 40,000 bodies (the 4M-atom one is left to the benchmarks).
fn scenes() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut all: Vec<PathBuf> = [root.clone(), root.join("bench")]
        .iter()
        .flat_map(|d| std::fs::read_dir(d).expect("the scenes folder"))
        .map(|e| e.expect("a folder entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lagra"))
        .collect();
    all.sort();
    all
}

#[test]
fn the_checker_raises_no_underflow_and_meets_no_subnormal_on_any_scene() {
    let (mut judged, mut trapped) = (0, vec![]);
    for path in scenes() {
        let text = std::fs::read_to_string(&path).expect("a scene");
        let s = compile(&text).unwrap_or_else(|d| panic!("{}", d.render(&path.display().to_string(), &text)));
        if s.claims.is_empty() || s.x0.len() > 40_000 {
            continue;
        }
        let first = lagra_kernel::setup::start(&s);
        let later = run(&s, Options::plain(Some(20))).expect("20 steps").state;
        let mut m = Monitor::new(s.model.clone(), s.claims.clone(), 20).expect("a valid model");
        m.set_threads(1);
        let flags = raised(|| {
            let _ = m.observe(&first.snapshot());
            m.foresee(&first.snapshot());
            let _ = m.observe(&later.snapshot());
        });
        judged += 1;
        if flags != 0 {
            trapped.push(format!("{} (DE {}, UE {})", path.display(), flags & DE != 0, flags & UE != 0));
        }
    }
    assert!(judged >= 20, "only {judged} scenes judged");
    assert!(trapped.is_empty(), "subnormal arithmetic in the checker: {trapped:#?}");
}

/// The flags are read, not assumed: the square of a subnormal raises both.
#[test]
fn the_flags_see_a_subnormal_square() {
    let tiny = std::hint::black_box(f64::MIN_POSITIVE / 4.0);
    assert_eq!(raised(|| assert_eq!(std::hint::black_box(tiny * tiny), 0.0)), DE | UE);
    assert_eq!(raised(|| assert_eq!(std::hint::black_box(1.5 * 2.0), 3.0)), 0);
}
