//! The Lagrangian graph: bodies (the vertices) and the term instances (the edges), grouped by
//! kind so the kernel dispatches once per group, not once per edge. A kind the scene does not
//! use has no group and costs nothing.

use crate::forces::{group, Force, Frame, Singularity};
use crate::state::State;
use crate::sum::Sum;
use lagra_checker::model::Model;
use lagra_checker::terms::Kind;

pub struct LagrangianGraph {
    pub masses: Vec<f64>,
    charges: Vec<f64>,
    colours: Vec<[f64; 2]>,
    groups: Vec<(Kind, Box<dyn Force>)>,
}

impl LagrangianGraph {
    pub fn new(model: &Model) -> Self {
        let mut groups = vec![];
        for &kind in Kind::ALL {
            let instances: Vec<_> = model.terms.iter().filter(|t| t.kind == kind).collect();
            if !instances.is_empty() {
                groups.push((kind, group(kind, &instances, model)));
            }
        }
        let masses = model.bodies.iter().map(|b| b.mass).collect();
        let charges = model.bodies.iter().map(|b| b.charge).collect();
        LagrangianGraph { masses, charges, colours: model.bodies.iter().map(|b| b.colour).collect(), groups }
    }

    /// The kinds present, in dispatch order.
    pub fn kinds(&self) -> impl Iterator<Item = Kind> + '_ {
        self.groups.iter().map(|g| g.0)
    }

    /// Whether any group has a velocity-dependent force.
    pub fn velocity_dependent(&self) -> bool {
        self.groups.iter().any(|g| g.1.velocity_dependent())
    }

    /// Writes the generalized forces into `f` and returns the potential energy (a witness).
    pub fn forces(&self, s: &State, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        f.iter_mut().for_each(|fi| *fi = [0.0; 3]);
        let frame = Frame { x: &s.x, v: &s.v, m: &self.masses, q: &self.charges, c: &self.colours };
        let mut potential = Sum::default();
        for (_, g) in &self.groups {
            potential.add(g.accumulate(&frame, f)?);
        }
        Ok(potential.value())
    }
}
