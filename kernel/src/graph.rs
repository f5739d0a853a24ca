//! The Lagrangian graph: bodies (the vertices) and the term instances (the edges), grouped by
//! kind so the kernel dispatches once per group, not once per edge. A kind the scene does not
//! use has no group and costs nothing.

use crate::forces::{group, Force, Frame, Parts, Pool, Singularity};
use crate::state::State;
use crate::sum::Sum;
use lagra_checker::model::Model;
use lagra_checker::terms::Kind;
use std::sync::Arc;

pub struct LagrangianGraph {
    pub masses: Vec<f64>,
    /// 1/m, so a kick multiplies.
    pub inverse_masses: Vec<f64>,
    /// Whether any group's force depends on velocities (asked every step: kept, not recomputed).
    velocity_dependent: bool,
    charges: Vec<f64>,
    colours: Vec<[f64; 2]>,
    groups: Vec<(Kind, Box<dyn Force>)>,
}

impl LagrangianGraph {
    /// On one thread.
    pub fn new(model: &Model) -> Self {
        Self::with_pool(model, None)
    }

    /// On `threads` threads of a pool of its own (the forces come out the same to the bit).
    pub fn with_threads(model: &Model, threads: usize) -> Result<Self, String> {
        let pool = match threads {
            0 => return Err("the thread count must be at least 1".into()),
            1 => None,
            n => Some(Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .thread_name(|i| format!("lagra-kernel-{i}"))
                    .build()
                    .map_err(|e| format!("starting {n} threads: {e}"))?,
            )),
        };
        Ok(Self::with_pool(model, pool))
    }

    fn with_pool(model: &Model, pool: Pool) -> Self {
        let mut groups = vec![];
        for &kind in Kind::ALL {
            let instances: Vec<_> = model.terms.iter().filter(|t| t.kind == kind).collect();
            if !instances.is_empty() {
                groups.push((kind, group(kind, &instances, model, &pool)));
            }
        }
        let masses = model.bodies.iter().map(|b| b.mass).collect();
        let charges = model.bodies.iter().map(|b| b.charge).collect();
        let inverse_masses = model.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let velocity_dependent = groups.iter().any(|g| g.1.velocity_dependent());
        let colours = model.bodies.iter().map(|b| b.colour).collect();
        LagrangianGraph { masses, inverse_masses, velocity_dependent, charges, colours, groups }
    }

    /// The kinds present, in dispatch order.
    pub fn kinds(&self) -> impl Iterator<Item = Kind> + '_ {
        self.groups.iter().map(|g| g.0)
    }

    /// Each group's kind and how it visits its bodies.
    pub fn plan(&self) -> Vec<(Kind, String)> {
        self.groups.iter().map(|(k, g)| (*k, g.plan())).collect()
    }

    /// Whether any group has a velocity-dependent force.
    pub fn velocity_dependent(&self) -> bool {
        self.velocity_dependent
    }

    /// Writes the generalized forces into `f` and returns the potential energy (a witness).
    pub fn forces(&self, s: &State, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        self.evaluate(s, f, true)
    }

    /// Writes the generalized forces into `f`, and nothing else: for the steps no one sees.
    pub fn forces_only(&self, s: &State, f: &mut [[f64; 3]]) -> Result<(), Singularity> {
        self.evaluate(s, f, false).map(|_| ())
    }

    /// The graph's only group, if it has one.
    pub fn sole(&self) -> Option<&dyn Force> {
        match self.groups.as_slice() {
            [(_, g)] => Some(g.as_ref()),
            _ => None,
        }
    }

    /// What a force group reads of the bodies besides the state: masses, charges, colours.
    pub fn frame_parts(&self) -> Parts<'_> {
        Parts { m: &self.masses, q: &self.charges, c: &self.colours }
    }

    fn evaluate(&self, s: &State, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity> {
        f.iter_mut().for_each(|fi| *fi = [0.0; 3]);
        let frame = Frame { x: &s.x, v: &s.v, m: &self.masses, q: &self.charges, c: &self.colours };
        let mut potential = Sum::default();
        for (_, g) in &self.groups {
            potential.add(g.accumulate(&frame, f, energy)?);
        }
        Ok(potential.value())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lang::compile;

    /// 5,324 Lennard-Jones atoms (enough to split the pair list into chunks), a few steps into a
    /// melt so that the list is stale and images cross the box.
    fn melt() -> (Model, State) {
        let scene = compile(
            "scene m { entity atom { mass: 1 }
               lattice { type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 3.0, seed: 9 }
               interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
               solver { dt: 0.005, steps: 1 } }",
        )
        .unwrap();
        let mut s = State { step: 0, t: 0.0, x: scene.x0.clone(), v: scene.v0.clone() };
        s.x.iter_mut().zip(&s.v).for_each(|(x, v)| (0..3).for_each(|c| x[c] += 0.02 * v[c] - 40.0));
        (scene.model, s)
    }

    #[test]
    fn forces_are_the_same_bits_on_any_number_of_threads() {
        let (model, s) = melt();
        let mut one = vec![[0.0; 3]; s.x.len()];
        let e1 = LagrangianGraph::with_threads(&model, 1).unwrap().forces(&s, &mut one).unwrap();
        for threads in [2, 3] {
            let mut many = vec![[0.0; 3]; s.x.len()];
            let e = LagrangianGraph::with_threads(&model, threads).unwrap().forces(&s, &mut many).unwrap();
            assert_eq!(e.to_bits(), e1.to_bits());
            assert!(one.iter().flatten().zip(many.iter().flatten()).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
        assert!(LagrangianGraph::with_threads(&model, 0).is_err());
    }

    /// The Verlet list and the plain loop over every pair agree to round-off.
    #[test]
    fn the_neighbour_list_gives_the_forces_of_every_pair() {
        let (model, s) = melt();
        let g = LagrangianGraph::new(&model);
        assert!(g.plan()[0].1.starts_with("Verlet list"), "{:?}", g.plan());
        let mut listed = vec![[0.0; 3]; s.x.len()];
        let e = g.forces(&s, &mut listed).unwrap();
        // every pair by the plain double loop, the shifted LJ formula written out
        let mut every = vec![[0.0; 3]; s.x.len()];
        let mut energy = 0.0;
        crate::traverse::pairs::<()>(&s.x, &model.cell, None, |i, j, d| {
            let r2: f64 = d.iter().map(|c| c * c).sum();
            if r2 < 6.25 {
                let (inv6, vc) = (r2.powi(-3), 4.0 * (2.5f64.powi(-12) - 2.5f64.powi(-6)));
                energy += 4.0 * (inv6 * inv6 - inv6) - vc;
                let s = 24.0 * (inv6 - 2.0 * inv6 * inv6) / r2;
                for c in 0..3 {
                    every[i][c] += s * d[c];
                    every[j][c] -= s * d[c];
                }
            }
            Ok(())
        })
        .unwrap();
        assert!((e - energy).abs() < 1e-9 * energy.abs(), "{e} {energy}");
        let worst = listed.iter().flatten().zip(every.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-9, "{worst}");
    }
}
