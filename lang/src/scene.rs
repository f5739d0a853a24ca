//! A compiled scene, data only: the canonical model the checker sees, the initial state, the
//! claims, the solver's name and settings, the predictions to compare against, and where each
//! thing was written (for what the engine finds wrong before the first step).

use crate::diagnostic::Span;
use crate::integrator::{Integrator, Settings};
use crate::prediction::Prediction;
use crate::thermostat::{Bath, Thermostat};
use lagra_checker::claims::Claim;
use lagra_checker::model::Model;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct Solver {
    pub integrator: Integrator,
    /// What an iterating integrator iterates to (its defaults where the scene gives none).
    pub settings: Settings,
    pub dt: f64,
    pub steps: u64,
    pub steps_per_frame: u64,
}

/// `@expect noether { tol, every }`: every conservation law the scene's symmetries imply, as
/// claims (the front derives them: the kernel knows no Noether table).
#[derive(Clone, Debug, PartialEq)]
pub struct NoetherRequest {
    pub at: Span,
    /// The relative energy tolerance of the generated energy claim.
    pub tol: Option<f64>,
    pub every: u64,
}

impl Scene {
    /// The temperature the scene's thermostat holds, if it has one.
    pub fn bath(&self) -> Option<Bath> {
        self.thermostat.as_ref().map(|t| Bath::of(t, &self.model))
    }

    /// Works the predictions out again from the model and initial state as they are now (after
    /// a parameter was set): a prediction that no longer applies is an error naming it.
    pub fn repredict(&mut self) -> Result<(), String> {
        let bath = self.bath();
        for p in &mut self.predictions {
            p.predicted = p
                .kind
                .predict(&self.model, &self.x0, &self.v0, bath)
                .map_err(|why| format!("{}: {why}", p.kind.name()))?;
        }
        Ok(())
    }
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub description: Option<String>,
    /// The physics domain named by `uses` (recorded, not interpreted).
    pub domain: Option<String>,
    /// Shared (`Arc`) with the checker's monitor of a run, which reads it and never changes it.
    pub model: Arc<Model>,
    pub x0: Vec<[f64; 3]>,
    pub v0: Vec<[f64; 3]>,
    /// Each rigid body's initial orientation and angular momentum (`State::spin`).
    pub spin0: Vec<[f64; 7]>,
    /// Display size of each body (from `size` or its type); not part of the physics.
    pub sizes: Vec<f64>,
    pub claims: Vec<Claim>,
    /// Where each of `claims` was declared.
    pub claim_spans: Vec<Span>,
    pub noether: Option<NoetherRequest>,
    pub predictions: Vec<Prediction>,
    pub solver: Solver,
    pub thermostat: Option<Thermostat>,
    /// What the run measures along the way (after `equilibrate`), if anything.
    pub sampling: Option<Sampling>,
    /// Where the things the engine checks before the first step were written.
    pub spans: Spans,
}

/// Where a scene wrote what the engine may still refuse (`lagra_run::compile`): the initial
/// state placed on the constraints, solids apart, tail corrections worked out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spans {
    /// Each of `model.constraints`.
    pub constraints: Vec<Span>,
    /// Each body's entity if it is a rigid body.
    pub solids: Vec<Option<Span>>,
    /// The rigid floor.
    pub floor: Option<Span>,
    /// `tail_corrections: true`.
    pub tail_corrections: Option<Span>,
    /// Each of `predictions`.
    pub predictions: Vec<Span>,
    /// Each of `model.terms` (its keyword).
    pub terms: Vec<Span>,
}

/// `equilibrate`, `sample_every`, `tail_corrections` in the solver block: the observables are
/// averaged over the states from time `equilibrate` on, every `every` steps.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sampling {
    pub equilibrate: f64,
    pub every: u64,
    /// Add each pair term's share beyond its cutoff to the energy and pressure, taking the
    /// bodies as evenly spread there (g(r) = 1).
    pub tail_corrections: bool,
}
