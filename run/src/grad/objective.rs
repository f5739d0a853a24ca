//! The scalar a gradient is of: an observable at the final state (`@end`) or summed over the
//! run's frames (`@sum`: step 0, every `steps_per_frame`-th step and the last, as `--trace`
//! writes them), or the mean squared distance of the positions from a target trace
//! (`mse:FILE.jsonl`, Lagra's trace format, at the steps the file holds).
//!
//! Observables: `position[I].x` (`.y`, `.z`), `velocity[I].x`, `kinetic`, `potential`,
//! `energy` (T + V), `distance[I,J]` (the nearest image in a periodic box).

use lagra_checker::model::Cell;
use lagra_kernel::forces::derivative::{Adjoint, Wanted};
use lagra_kernel::forces::Singularity;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::state::{kinetic, State};
use lagra_lang::scene::Scene;

#[derive(Clone, Debug, PartialEq)]
pub enum Quantity {
    Position(usize, usize),
    Velocity(usize, usize),
    Kinetic,
    Potential,
    Energy,
    Distance(usize, usize),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Objective {
    /// At the last step (`sum: false`) or summed over the frames.
    Observed { quantity: Quantity, sum: bool },
    /// (1/(F·N)) Σ_frames Σ_bodies |xᵢ − x*ᵢ|² over the target's F frames of N bodies.
    Mse { file: String, target: Vec<(u64, Vec<[f64; 3]>)> },
}

const SPELLINGS: &str =
    "position[I].x, velocity[I].x, kinetic, potential, energy or distance[I,J], then @end or @sum; or mse:FILE.jsonl";

fn index(s: &str, n: usize, what: &str) -> Result<usize, String> {
    let i: usize = s.trim().parse().map_err(|_| format!("`{s}` is not a body index in {what}"))?;
    if i >= n {
        return Err(format!("{what}: body {i} does not exist: the scene has {n} bodies"));
    }
    Ok(i)
}

impl Objective {
    pub fn parse(spelling: &str, scene: &Scene) -> Result<Objective, String> {
        Objective::parse_reading(spelling, scene, &|f| std::fs::read_to_string(f).map_err(|e| e.to_string()))
    }

    /// `parse`, with the target trace of `mse:FILE` read by `read` (a front's bounded reader,
    /// confined to its roots where it has some).
    pub fn parse_reading(
        spelling: &str,
        scene: &Scene,
        read: &dyn Fn(&str) -> Result<String, String>,
    ) -> Result<Objective, String> {
        let n = scene.model.bodies.len();
        if let Some(file) = spelling.strip_prefix("mse:") {
            let text = read(file).map_err(|e| format!("cannot read the target trace {file}: {e}"))?;
            return Objective::mse(file, &text, n, scene.solver.steps);
        }
        let (what, when) = spelling
            .rsplit_once('@')
            .ok_or_else(|| format!("objective `{spelling}` needs @end or @sum; objectives: {SPELLINGS}"))?;
        let sum = match when {
            "end" => false,
            "sum" => true,
            _ => return Err(format!("objective `{spelling}`: `@{when}` is not @end or @sum")),
        };
        let quantity = match what {
            "kinetic" => Quantity::Kinetic,
            "potential" => Quantity::Potential,
            "energy" => Quantity::Energy,
            _ => {
                let (name, rest) = what
                    .split_once('[')
                    .ok_or_else(|| format!("unknown objective `{spelling}`; objectives: {SPELLINGS}"))?;
                let (inside, tail) =
                    rest.split_once(']').ok_or_else(|| format!("objective `{spelling}`: a `]` is missing"))?;
                let axis = |tail: &str| -> Result<usize, String> {
                    ["x", "y", "z"]
                        .iter()
                        .position(|a| tail == format!(".{a}"))
                        .ok_or_else(|| format!("objective `{spelling}`: name one axis, .x, .y or .z"))
                };
                match name {
                    "position" => Quantity::Position(index(inside, n, spelling)?, axis(tail)?),
                    "velocity" => Quantity::Velocity(index(inside, n, spelling)?, axis(tail)?),
                    "distance" if tail.is_empty() => {
                        let (i, j) = inside
                            .split_once(',')
                            .ok_or_else(|| format!("objective `{spelling}`: write distance[I,J]"))?;
                        let (i, j) = (index(i, n, spelling)?, index(j, n, spelling)?);
                        if i == j {
                            return Err(format!("objective `{spelling}`: a distance needs two different bodies"));
                        }
                        Quantity::Distance(i, j)
                    }
                    _ => return Err(format!("unknown objective `{spelling}`; objectives: {SPELLINGS}")),
                }
            }
        };
        Ok(Objective::Observed { quantity, sum })
    }

    /// The target trace: every line's step and positions, in the run's span.
    fn mse(file: &str, text: &str, n: usize, steps: u64) -> Result<Objective, String> {
        let mut target: Vec<(u64, Vec<[f64; 3]>)> = vec![];
        for (k, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
            let at = format!("{file}:{}", k + 1);
            let v: serde_json::Value =
                serde_json::from_str(line).map_err(|e| format!("{at}: not a trace line: {e}"))?;
            let step = v["step"].as_u64().ok_or_else(|| format!("{at}: no `step`"))?;
            let x: Vec<[f64; 3]> = serde_json::from_value(v["x"].clone())
                .map_err(|e| format!("{at}: `x` is not a list of positions: {e}"))?;
            if x.len() != n {
                return Err(format!("{at}: {} positions for a scene of {n} bodies", x.len()));
            }
            if let Some(bad) = x.iter().flatten().find(|c| !c.is_finite()) {
                return Err(format!("{at}: a position is not finite ({bad})"));
            }
            if target.last().is_some_and(|l| l.0 >= step) {
                return Err(format!("{at}: steps must rise, but {step} follows {}", target.last().map_or(0, |l| l.0)));
            }
            target.push((step, x));
        }
        if target.is_empty() {
            return Err(format!("the target trace {file} holds no frame"));
        }
        let last = target.last().map_or(0, |l| l.0);
        if last > steps {
            return Err(format!("the target trace {file} goes to step {last}, past the run's {steps} steps"));
        }
        Ok(Objective::Mse { file: file.into(), target })
    }

    /// The steps at which it reads the state, in a run of `steps` steps with a frame every
    /// `every` steps.
    pub fn steps(&self, steps: u64, every: u64) -> Vec<u64> {
        match self {
            Objective::Observed { sum: false, .. } => vec![steps],
            Objective::Observed { sum: true, .. } => {
                let mut v: Vec<u64> = (0..=steps).step_by(every.max(1) as usize).collect();
                if v.last() != Some(&steps) {
                    v.push(steps);
                }
                v
            }
            Objective::Mse { target, .. } => target.iter().map(|t| t.0).collect(),
        }
    }

    /// Its share at a state it reads (`step` among `steps()`), from the state and its potential
    /// energy `v` (the solver's witness: no evaluation here, so that a pass that computes the
    /// value changes nothing of the run it watches).
    pub fn value(&self, step: u64, s: &State, masses: &[f64], v: f64, cell: &Option<Cell>) -> f64 {
        match self {
            Objective::Mse { target, .. } => target.iter().find(|t| t.0 == step).map_or(0.0, |(_, x)| {
                let scale = 1.0 / (target.len() * x.len()) as f64;
                s.x.iter().zip(x).map(|(p, q)| (0..3).map(|c| scale * (p[c] - q[c]) * (p[c] - q[c])).sum::<f64>()).sum()
            }),
            Objective::Observed { quantity, .. } => match *quantity {
                Quantity::Position(i, c) => s.x[i][c],
                Quantity::Velocity(i, c) => s.v[i][c],
                Quantity::Distance(i, j) => {
                    let d = Cell::image(cell, std::array::from_fn(|c| s.x[j][c] - s.x[i][c]));
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                }
                Quantity::Kinetic => kinetic(s, masses),
                Quantity::Potential => v,
                Quantity::Energy => kinetic(s, masses) + v,
            },
        }
    }

    /// Adds its share's gradient at a state it reads to `out`: positions, velocities, and the
    /// masses and parameters `wanted` names.
    pub fn gradient(
        &self,
        step: u64,
        s: &State,
        g: &LagrangianGraph,
        cell: &Option<Cell>,
        wanted: &Wanted,
        out: &mut Adjoint,
    ) -> Result<(), Singularity> {
        match self {
            Objective::Mse { target, .. } => {
                if let Some((_, x)) = target.iter().find(|t| t.0 == step) {
                    let scale = 1.0 / (target.len() * x.len()) as f64;
                    for ((o, p), q) in out.x.iter_mut().zip(&s.x).zip(x) {
                        (0..3).for_each(|c| o[c] += 2.0 * scale * (p[c] - q[c]));
                    }
                }
            }
            Objective::Observed { quantity, .. } => match *quantity {
                Quantity::Position(i, c) => out.x[i][c] += 1.0,
                Quantity::Velocity(i, c) => out.v[i][c] += 1.0,
                Quantity::Distance(i, j) => {
                    let d = Cell::image(cell, std::array::from_fn(|c| s.x[j][c] - s.x[i][c]));
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    for c in 0..3 {
                        out.x[j][c] += d[c] / r;
                        out.x[i][c] -= d[c] / r;
                    }
                }
                Quantity::Kinetic => kinetic_gradient(s, &g.masses, wanted, out),
                Quantity::Potential => g.potential_pullback(s, wanted, out)?,
                Quantity::Energy => {
                    kinetic_gradient(s, &g.masses, wanted, out);
                    g.potential_pullback(s, wanted, out)?;
                }
            },
        }
        Ok(())
    }
}

/// ∂T/∂v = m v and ∂T/∂m = ½|v|².
fn kinetic_gradient(s: &State, masses: &[f64], wanted: &Wanted, out: &mut Adjoint) {
    for (i, (v, m)) in s.v.iter().zip(masses).enumerate() {
        for c in 0..3 {
            out.v[i][c] += m * v[c];
        }
        if wanted.masses {
            out.m[i] += 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile;

    #[test]
    fn spellings_and_their_errors() {
        let s = compile("scene s { entity { position: [0, 0, 0], mass: 1 } entity { position: [1, 0, 0], mass: 1 } solver { dt: 0.1, steps: 10 } }").unwrap();
        assert_eq!(
            Objective::parse("position[1].y@end", &s).unwrap(),
            Objective::Observed { quantity: Quantity::Position(1, 1), sum: false }
        );
        assert_eq!(
            Objective::parse("distance[0,1]@sum", &s).unwrap(),
            Objective::Observed { quantity: Quantity::Distance(0, 1), sum: true }
        );
        assert_eq!(Objective::parse("energy@sum", &s).unwrap().steps(10, 4), [0, 4, 8, 10]);
        for (bad, message) in [
            ("energy", "needs @end or @sum"),
            ("energy@start", "`@start` is not @end or @sum"),
            ("position[2].x@end", "body 2 does not exist"),
            ("position[0]@end", "name one axis"),
            ("distance[0,0]@end", "two different bodies"),
            ("spin@end", "unknown objective"),
            ("mse:/no/such/file.jsonl", "cannot read the target trace"),
        ] {
            let e = Objective::parse(bad, &s).unwrap_err();
            assert!(e.contains(message), "{bad}: {e}");
        }
    }
}
