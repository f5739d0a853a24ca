//! `lagra-run`: a run of a scene and its analyses. The engine's last check of a compiled scene
//! (`compile`), the run loop that steps the kernel and hands each checkpoint's exact state to
//! the checker (`run`, `checking`), the trace it writes (`trace`), and what is measured of it:
//! observables and their tail corrections, the scene's predictions, gradients of whole runs.

pub mod checking;
pub mod domains;
pub mod grad;
pub mod marks;
pub mod observables;
pub mod predict;
pub mod restart;
pub mod run;
pub mod tail;
pub mod thinned;
pub mod trace;

use lagra_lang::{Diagnostic, Scene};
use tail::Tail;

/// Compiles a scene and makes it ready to run: the language's compile and the kernel's placing
/// (`lagra_kernel::setup::compile`), then its tail corrections worked out where it asks for
/// them. Every error names where the scene wrote it.
pub fn compile(source: &str) -> Result<Scene, Diagnostic> {
    compile_on(source, &|_| None)
}

/// [`compile`], a large lattice laid out on the threads `threads` gives
/// (`lagra_lang::compile_on`): the same scene, to the bit.
pub fn compile_on<'a>(source: &'a str, threads: lagra_lang::Threads<'a>) -> Result<Scene, Diagnostic> {
    let scene = lagra_kernel::setup::compile_on(source, threads)?;
    if let Some(at) = scene.spans.tail_corrections {
        Tail::of(&scene.model).map_err(|e| Diagnostic::new(at, e))?;
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::compile;

    const TWO_BEADS: &str = r#"scene s {
  entity { position: [0, 0, 0], mass: 1 }
  entity { position: [1, 0, 0], mass: 1 }
  bond harmonic [0, 1] { k: 2.0, r0: 1.0 }
  solver { dt: 0.01, steps: 10, equilibrate: 0, tail_corrections: true }
}"#;

    /// What the language cannot judge is still an error at the place the scene wrote it.
    #[test]
    fn tail_corrections_need_a_periodic_box() {
        assert!(lagra_lang::compile(TWO_BEADS).is_ok());
        let d = compile(TWO_BEADS).unwrap_err();
        assert_eq!(d.line_col(TWO_BEADS), (5, 67));
        assert_eq!(d.message, "tail corrections need a box periodic along every axis");
    }
}
