//! What a run measures at equilibrium: the potential energy per body, the kinetic temperature,
//! the pressure by the virial (nearest images in a periodic box), the diffusion coefficient
//! (Einstein: ⟨|Δx|²⟩ = 6Dt) and the radial distribution g(r), from the states after
//! `equilibrate`, every `sample_every` steps. Means come with standard errors from block
//! averages: the samples cut into `BLOCKS` consecutive blocks, each block's mean taken as one
//! independent measurement (so the error is honest only if a block is longer than the
//! correlation time; the report says how many samples each block held).

use crate::tail::Tail;
use lagra_checker::model::Cell;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::state::{kinetic, State};
use lagra_kernel::traverse;
use lagra_lang::scene::{Sampling, Scene};
use lagra_lang::thermostat::degrees_of_freedom;
use serde::Serialize;

/// Blocks a production run is cut into for the standard errors.
pub const BLOCKS: usize = 10;
/// g(r) is sampled at every `RDF_EVERY`-th sample: neighbouring samples add little.
const RDF_EVERY: u64 = 10;
/// Bins of g(r), out to half the box.
const RDF_BINS: usize = 100;
/// Above this many bodies g(r) is not measured (its pair loop reaches half the box).
const RDF_MOST: usize = 20_000;

/// A mean and its standard error.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Estimate {
    pub mean: f64,
    /// From the spread of the block means; `None` with fewer than two blocks.
    pub stderr: Option<f64>,
    pub samples: u64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Rdf {
    /// Bin centres.
    pub r: Vec<f64>,
    pub g: Vec<f64>,
    pub samples: u64,
}

impl Rdf {
    /// The first peak: (r, g).
    pub fn peak(&self) -> Option<(f64, f64)> {
        self.r.iter().zip(&self.g).map(|(r, g)| (*r, *g)).max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Observables {
    pub from_step: u64,
    pub every: u64,
    pub blocks: usize,
    pub potential_energy_per_body: Estimate,
    pub kinetic_temperature: Estimate,
    pub pressure: Option<Estimate>,
    pub diffusion: Option<Estimate>,
    pub rdf: Option<Rdf>,
    /// Added to the energy and the pressure, if the scene asked (`tail_corrections`).
    pub tail: Option<Tail>,
    /// Why an observable is missing.
    pub notes: Vec<String>,
}

/// Gathers the samples along a run (a restart file carries them).
#[derive(Clone, Serialize, serde::Deserialize)]
pub struct Observer {
    sampling: Sampling,
    /// The first step sampled: `equilibrate` in steps, rounded.
    from: u64,
    bodies: f64,
    masses: Vec<f64>,
    dof: f64,
    volume: Option<f64>,
    tail: Option<Tail>,
    cell: Option<Cell>,
    /// Half the shortest side of a box periodic along every axis.
    half_box: Option<f64>,
    virial: bool,
    energy: Vec<f64>,
    temperature: Vec<f64>,
    pressure: Vec<f64>,
    /// The sample indices that bound the diffusion blocks, and the positions seen there.
    bounds: Vec<u64>,
    ends: Vec<(f64, Vec<[f64; 3]>)>,
    histogram: Vec<f64>,
    rdf_samples: u64,
    notes: Vec<String>,
}

impl Observer {
    /// For a run of `steps` steps of `scene` (`None` if it measures nothing).
    pub fn new(scene: &Scene, g: &LagrangianGraph, steps: u64) -> Result<Option<Observer>, String> {
        let Some(sampling) = scene.sampling else { return Ok(None) };
        let model = &scene.model;
        let mut notes = vec![];
        let cell = model.cell.filter(|c| c.periodic == [true; 3]);
        let volume = cell.map(|c| c.size.iter().product::<f64>());
        let probe = g.virial(&lagra_kernel::setup::start(&scene)).is_some();
        let virial = volume.is_some() && probe;
        if volume.is_none() {
            notes.push("pressure: needs a box periodic along every axis".into());
        } else if !probe {
            notes.push("pressure: a field term acts from outside the box, so the virial has no meaning".into());
        }
        let tail = sampling.tail_corrections.then(|| Tail::of(model)).transpose()?;
        let half_box = cell.map(|c| 0.5 * c.size.iter().fold(f64::INFINITY, |a, &b| a.min(b)));
        if half_box.is_none() {
            notes.push("rdf: needs a box periodic along every axis".into());
        } else if model.bodies.len() > RDF_MOST {
            notes.push(format!("rdf: not measured above {RDF_MOST} bodies"));
        }
        let dof = scene.bath().map_or_else(|| degrees_of_freedom(model), |b| b.dof);
        let from = (sampling.equilibrate / scene.solver.dt).round().min(u64::MAX as f64) as u64;
        let planned = if steps >= from { (steps - from) / sampling.every + 1 } else { 0 };
        let bounds = if planned >= 2 * BLOCKS as u64 {
            (0..=BLOCKS as u64).map(|k| k * (planned - 1) / BLOCKS as u64).collect()
        } else {
            vec![]
        };
        if bounds.is_empty() {
            notes.push(format!("diffusion: needs {} samples at least, the run has {planned}", 2 * BLOCKS));
        }
        Ok(Some(Observer {
            sampling,
            from,
            bodies: model.bodies.len() as f64,
            masses: g.masses.clone(),
            dof,
            volume,
            tail,
            cell,
            half_box: half_box.filter(|_| model.bodies.len() <= RDF_MOST),
            virial,
            energy: vec![],
            temperature: vec![],
            pressure: vec![],
            bounds,
            ends: vec![],
            histogram: vec![0.0; RDF_BINS],
            rdf_samples: 0,
            notes,
        }))
    }

    /// Whether the state at `step` is sampled.
    pub fn due(&self, step: u64) -> bool {
        step >= self.from && (step - self.from).is_multiple_of(self.sampling.every)
    }

    /// The first sampled step after `step`.
    pub fn next_due(&self, step: u64) -> u64 {
        let (from, every) = (self.from, self.sampling.every);
        if step < from {
            from
        } else {
            from + ((step - from) / every + 1) * every
        }
    }

    /// One sampled state, with the potential energy there (the solver's witness) and, if known
    /// (a run in domains measures it), the virial.
    pub fn observe(
        &mut self,
        g: &LagrangianGraph,
        s: &State,
        potential: f64,
        virial: Option<f64>,
    ) -> Result<(), String> {
        let index = self.energy.len() as u64;
        let twice_kinetic = 2.0 * kinetic(s, &self.masses);
        let tail = self.tail.unwrap_or(Tail { energy_per_body: 0.0, pressure: 0.0 });
        self.energy.push(potential / self.bodies + tail.energy_per_body);
        self.temperature.push(twice_kinetic / self.dof);
        if let (true, Some(volume)) = (self.virial, self.volume) {
            let w = match virial {
                Some(w) => w,
                None => g.virial(s).expect("a virial where there was one").map_err(|e| e.to_string())?,
            };
            self.pressure.push((twice_kinetic + w) / (3.0 * volume) + tail.pressure);
        }
        if self.bounds.contains(&index) {
            self.ends.push((s.t, s.x.clone()));
        }
        if let Some(half) = self.half_box.filter(|_| index.is_multiple_of(RDF_EVERY)) {
            let width = half / RDF_BINS as f64;
            let histogram = &mut self.histogram;
            traverse::pairs(&s.x, &self.cell, Some(half), |_, _, d| {
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if r < half {
                    histogram[(r / width) as usize] += 1.0;
                }
                Ok::<(), ()>(())
            })
            .expect("counting cannot fail");
            self.rdf_samples += 1;
        }
        Ok(())
    }

    /// The means and their errors, or nothing if no state was sampled.
    pub fn finish(self) -> Option<Observables> {
        if self.energy.is_empty() {
            return None;
        }
        let rdf = self.half_box.filter(|_| self.rdf_samples > 0).map(|half| {
            let width = half / RDF_BINS as f64;
            let pairs = self.bodies * (self.bodies - 1.0) / 2.0;
            let density = pairs / self.volume.expect("a box") * self.rdf_samples as f64;
            let shell = |k: usize| {
                4.0 / 3.0 * std::f64::consts::PI * (((k + 1) as f64 * width).powi(3) - (k as f64 * width).powi(3))
            };
            Rdf {
                r: (0..RDF_BINS).map(|k| (k as f64 + 0.5) * width).collect(),
                g: self.histogram.iter().enumerate().map(|(k, n)| n / (density * shell(k))).collect(),
                samples: self.rdf_samples,
            }
        });
        Some(Observables {
            from_step: self.from,
            every: self.sampling.every,
            blocks: BLOCKS,
            potential_energy_per_body: estimate(&self.energy),
            kinetic_temperature: estimate(&self.temperature),
            pressure: (!self.pressure.is_empty()).then(|| estimate(&self.pressure)),
            diffusion: diffusion(&self.ends, &self.masses),
            rdf,
            tail: self.tail,
            notes: self.notes,
        })
    }
}

/// The mean of all samples, and the standard error of the mean of `BLOCKS` block means.
pub fn estimate(samples: &[f64]) -> Estimate {
    let n = samples.len();
    let mean = samples.iter().sum::<f64>() / n as f64;
    let size = n / BLOCKS;
    let stderr = (size > 0).then(|| {
        let means: Vec<f64> =
            samples.chunks_exact(size).take(BLOCKS).map(|b| b.iter().sum::<f64>() / size as f64).collect();
        let m = means.iter().sum::<f64>() / BLOCKS as f64;
        (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (BLOCKS * (BLOCKS - 1)) as f64).sqrt()
    });
    Estimate { mean, stderr, samples: n as u64 }
}

/// D from each block's mean squared displacement (about the centre of mass) over its length,
/// ⟨|Δx|²⟩/6Δt; the mean over the blocks and its standard error.
fn diffusion(ends: &[(f64, Vec<[f64; 3]>)], masses: &[f64]) -> Option<Estimate> {
    if ends.len() < 3 {
        return None;
    }
    let total: f64 = masses.iter().sum();
    let per_block: Vec<f64> = ends
        .windows(2)
        .map(|w| {
            let ((t0, a), (t1, b)) = (&w[0], &w[1]);
            let d: Vec<[f64; 3]> = a.iter().zip(b).map(|(a, b)| std::array::from_fn(|c| b[c] - a[c])).collect();
            let cm: [f64; 3] =
                std::array::from_fn(|c| d.iter().zip(masses).map(|(d, m)| m * d[c]).sum::<f64>() / total);
            let msd =
                d.iter().map(|d| (0..3).map(|c| (d[c] - cm[c]).powi(2)).sum::<f64>()).sum::<f64>() / d.len() as f64;
            msd / (6.0 * (t1 - t0))
        })
        .collect();
    let n = per_block.len() as f64;
    let mean = per_block.iter().sum::<f64>() / n;
    let stderr = (per_block.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n * (n - 1.0))).sqrt();
    Some(Estimate { mean, stderr: Some(stderr), samples: per_block.len() as u64 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_errors_shrink_like_one_over_root_n_for_independent_samples() {
        let draw = |n: u64| (0..n).map(|i| lagra_lang::random::normal(3, 0, i)).collect::<Vec<f64>>();
        let (small, large) = (estimate(&draw(1000)), estimate(&draw(100_000)));
        let ratio = small.stderr.unwrap() / large.stderr.unwrap();
        assert!((5.0..20.0).contains(&ratio), "{ratio}: √100 = 10 expected");
        assert!(large.mean.abs() < 4.0 * large.stderr.unwrap(), "{large:?}");
        assert_eq!(estimate(&[1.0, 2.0]).stderr, None);
    }

    #[test]
    fn a_random_walk_has_its_diffusion_coefficient() {
        // steps of variance 2D·dt per axis: ⟨|Δx|²⟩ = 6Dt
        let (d, dt, n) = (0.3, 0.01, 2000usize);
        let mut x = vec![[0.0; 3]; n];
        let mut ends = vec![];
        for step in 0..=5000u64 {
            if step % 500 == 0 {
                ends.push((step as f64 * dt, x.clone()));
            }
            for (i, xi) in x.iter_mut().enumerate() {
                for (c, xc) in xi.iter_mut().enumerate() {
                    *xc += (2.0 * d * dt).sqrt() * lagra_lang::random::normal(5, step, 3 * i as u64 + c as u64);
                }
            }
        }
        let e = diffusion(&ends, &vec![1.0; n]).unwrap();
        assert!((e.mean - d).abs() < 4.0 * e.stderr.unwrap() && (e.mean / d - 1.0).abs() < 0.03, "{e:?}");
    }
}

#[cfg(test)]
mod virial {
    use crate::compile;
    use lagra_kernel::graph::LagrangianGraph;

    /// The virial is the energy's response to stretching the box: with every position and the
    /// box scaled by λ, dU/dλ at λ = 1 is −W (through the neighbour list, with periodic images,
    /// for pairs and bonds alike).
    #[test]
    fn the_virial_is_minus_the_energys_response_to_stretching() {
        let scene = compile(
            "scene v { entity atom { mass: 1 }
               lattice { type: atom, density: 0.8, cells: [4, 4, 4], temperature: 1.5, seed: 2 }
               interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
               bond harmonic [0, 1] { k: 5, r0: 1.1 }
               bond angle [2, 3, 4] { k: 3, theta0: 2.0 }
               solver { dt: 0.005 } }",
        )
        .unwrap();
        // melt a little, so that no pair sits on a lattice distance
        let g = LagrangianGraph::new(&scene.model);
        let mut s = lagra_kernel::setup::start(&scene);
        let mut st = lagra_kernel::solvers::Stepper::for_scene(&scene, &g, &s).unwrap();
        st.advance_to(&g, &mut s, 0.005, 50).unwrap();
        let w = g.virial(&s).unwrap().unwrap();
        let energy = |l: f64| {
            let mut model = (*scene.model).clone();
            let cell = model.cell.as_mut().unwrap();
            cell.size = cell.size.map(|c| c * l);
            let g = LagrangianGraph::new(&model);
            let mut t = s.clone();
            t.x.iter_mut().flatten().for_each(|c| *c *= l);
            let mut f = vec![[0.0; 3]; t.x.len()];
            g.forces(&t, &mut f).unwrap()
        };
        let h = 1e-6;
        let du = (energy(1.0 + h) - energy(1.0 - h)) / (2.0 * h);
        assert!((du + w).abs() < 1e-5 * w.abs(), "dU/dλ = {du}, W = {w}");
    }

    #[test]
    fn a_field_has_no_virial() {
        let scene =
            compile("scene f { entity { position: [0, 0, 0], mass: 1 } gravity { g: [0, -1, 0] } solver { dt: 0.1 } }")
                .unwrap();
        assert!(LagrangianGraph::new(&scene.model).virial(&lagra_kernel::setup::start(&scene)).is_none());
    }
}
