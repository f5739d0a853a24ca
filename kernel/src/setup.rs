//! From a compiled scene (`lagra_lang::Scene`, data) to the state a run starts from, and what
//! only the kernel can check before the first step: the initial state moved onto the scene's
//! constraints (to the solver's tolerance, the velocities made tangent), solids apart.

use crate::constraints::{Constraints, Tolerance};
use crate::contact::Solids;
use crate::state::State;
use lagra_lang::{Diagnostic, Scene, Threads};

/// The state the run starts from: step 0, the initial positions and velocities, a thermostat
/// chain at rest.
pub fn start(scene: &Scene) -> State {
    start_on(scene, None)
}

/// [`start`], a large scene's positions and velocities copied on `pool`'s threads.
pub fn start_on(scene: &Scene, pool: Option<&rayon::ThreadPool>) -> State {
    State {
        step: 0,
        t: 0.0,
        x: crate::spread::copied(pool, &scene.x0),
        v: crate::spread::copied(pool, &scene.v0),
        chain: vec![[0.0; 2]; scene.model.links()],
        spin: scene.spin0.clone(),
    }
}

/// Compiles a scene (`lagra_lang::compile`) and places its initial state (`place`).
pub fn compile(source: &str) -> Result<Scene, Diagnostic> {
    compile_on(source, &|_| None)
}

/// [`compile`], a large lattice laid out on the threads `threads` gives
/// (`lagra_lang::compile_on`).
pub fn compile_on<'a>(source: &'a str, threads: Threads<'a>) -> Result<Scene, Diagnostic> {
    let mut scene = lagra_lang::compile_on(source, threads)?;
    place(&mut scene)?;
    Ok(scene)
}

/// Moves the initial state onto the constraints and checks that solids start apart; an error
/// names the constraint or the entity where the scene wrote it.
pub fn place(scene: &mut Scene) -> Result<(), Diagnostic> {
    if let Some(k) = Constraints::of(&scene.model) {
        let settings = scene.solver.settings;
        let tol = Tolerance { tol: settings.tol.min(1e-12), sweeps: settings.iterations.max(1000) };
        let inverse: Vec<f64> = scene.model.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let before = scene.x0.clone();
        let mut scratch = scene.v0.clone();
        let placed = k
            .positions(&before, &mut scene.x0, &mut scratch, &inverse, 1.0, tol)
            .and_then(|_| k.velocities(&scene.x0, &mut scene.v0, &inverse, 1.0, tol));
        if let Err(e) = placed {
            return Err(Diagnostic::new(
                scene.spans.constraints[e.constraint],
                format!("the initial state cannot be placed on the constraints: {e}"),
            ));
        }
        // the predictions' closed forms read the initial state, which the constraints moved
        let bath = scene.bath();
        for (p, at) in scene.predictions.iter_mut().zip(&scene.spans.predictions) {
            p.predicted = p
                .kind
                .predict(&scene.model, &scene.x0, &scene.v0, bath)
                .map_err(|why| Diagnostic::new(*at, format!("{}: {why}", p.kind.name())))?;
        }
    }
    apart(scene)
}

/// Solids must start apart and above the floor: the contact solver would fling overlapping
/// bodies apart. An overlap is an error at the later body's entity (or at the floor).
fn apart(scene: &Scene) -> Result<(), Diagnostic> {
    let Some(solids) = Solids::of(&scene.model) else { return Ok(()) };
    // well above rounding, well below any overlap the solver would have to undo
    let tolerance = 1e-6 * solids.margin;
    let touches = solids.touching(&solids.poses(&scene.x0, &scene.spin0), None);
    let Some(t) = touches.into_iter().find(|t| t.depth > tolerance) else { return Ok(()) };
    let (at, depth) = (&scene.spans, t.depth);
    Err(match t.a {
        None => Diagnostic::new(
            at.solids[t.b].or(at.floor).expect("a floor contact has a floor"),
            format!("body {} starts {depth:.3e} below the floor: solids must start apart", t.b),
        ),
        Some(a) => Diagnostic::new(
            at.solids[a.max(t.b)].expect("a solid was declared"),
            format!("bodies {a} and {} start interpenetrated by {depth:.3e}: solids must start apart", t.b),
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROD: &str = r#"scene s {
  entity { position: [0, 0, 0], mass: 1, velocity: [0.3, 0, 0] }
  entity { position: [1.0000004, 0, 0], mass: 2 }
  constraint [0, 1] { length: 1 }
  thermostat nose_hoover { T: 0.5, tau: 0.2 }
  solver { dt: 0.01, steps: 10 }
}"#;

    /// The language leaves the state as written; placing moves it onto the constraint and its
    /// velocities tangent to it, and the run starts there with the chain at rest.
    #[test]
    fn a_compiled_scene_starts_on_its_constraints() {
        let written = lagra_lang::compile(ROD.replace("  thermostat nose_hoover { T: 0.5, tau: 0.2 }\n", "").as_str());
        assert_eq!(written.unwrap().x0[1][0], 1.0000004);
        let placed = compile(&ROD.replace("  thermostat nose_hoover { T: 0.5, tau: 0.2 }\n", "")).unwrap();
        let d: Vec<f64> = (0..3).map(|c| placed.x0[1][c] - placed.x0[0][c]).collect();
        assert!(((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - 1.0).abs() < 1e-12, "{d:?}");
        let along: f64 = (0..3).map(|c| (placed.v0[1][c] - placed.v0[0][c]) * d[c]).sum();
        assert!(along.abs() < 1e-12, "the velocities are tangent: {along}");
        let s = start(&placed);
        assert_eq!((s.step, s.t, &s.x, &s.v), (0, 0.0, &placed.x0, &placed.v0));
    }

    #[test]
    fn a_chain_starts_at_rest() {
        let scene = lagra_lang::compile(&ROD.replace("  constraint [0, 1] { length: 1 }\n", "")).unwrap();
        assert_eq!(scene.model.links(), 3);
        assert_eq!(start(&scene).chain, vec![[0.0; 2]; 3]);
    }

    /// Solids that start overlapping are refused at the later one's entity.
    #[test]
    fn solids_must_start_apart() {
        let src = "scene s {\n  entity { shape: box, size: [1, 1, 1], mass: 1, position: [0, 0, 0] }\n  entity { shape: box, size: [1, 1, 1], mass: 1, position: [0.5, 0, 0] }\n  solver { dt: 0.01, steps: 10 }\n}";
        let d = compile(src).unwrap_err();
        assert_eq!(d.line_col(src), (3, 10));
        assert!(d.message.starts_with("bodies 0 and 1 start interpenetrated by 5.000e-1"), "{}", d.message);
    }
}
