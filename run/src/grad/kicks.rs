//! The transposes of a step's kicks and drift, body by body: the passes of the backward pass
//! between two pullbacks. Each body's arithmetic is its own, so they spread over the run's
//! threads (`LagrangianGraph::spread`) with the same bits as on one; the pullback's scratch is
//! kept and cleared rather than allocated at every step. On one thread these passes were a few
//! per cent of a gradient; left serial they would bound it on sixteen (Amdahl).

use super::Run;
use lagra_kernel::forces::derivative::Adjoint;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::spread::{self, SPREAD_FROM};
use lagra_kernel::step::BLOCK;
use rayon::prelude::*;

/// What a pullback writes into and reads: its adjoint, and the covector (h/m)·a it is applied to.
pub(super) struct Scratch {
    pub pb: Adjoint,
    pub kicked: Vec<[f64; 3]>,
}

impl Scratch {
    pub fn new(run: &Run) -> Scratch {
        Scratch { pb: run.zero(), kicked: vec![[0.0; 3]; run.scene.x0.len()] }
    }

    /// The pullback's adjoint zeroed, and the covector (h/m)·(λ_v + b) for the closing kick of a
    /// step (b the opening kick's covector of the step after it): the same arithmetic as
    /// `Run::kick` of their sum.
    pub fn closing_kick(&mut self, run: &Run, lam_v: &[[f64; 3]], opening: &[[f64; 3]]) {
        let h = 0.5 * run.dt;
        let pb = &mut self.pb;
        pb.params.iter_mut().flatten().for_each(|p| *p = 0.0);
        let one = |((((k, x), v), (m, q)), ((a, b), w)): BodyPass<'_>| {
            (*x, *v, *m, *q) = ([0.0; 3], [0.0; 3], 0.0, 0.0);
            *k = std::array::from_fn(|c| h * w * (a[c] + b[c]));
        };
        let g = &run.graph;
        spread::pass_if(lam_v.len() >= SPREAD_FROM, || match g.spread() {
            Some(pool) => pool.install(|| {
                let mine = (self.kicked.par_iter_mut().zip(pb.x.par_iter_mut()).zip(pb.v.par_iter_mut()))
                    .zip(pb.m.par_iter_mut().zip(pb.q.par_iter_mut()));
                let read = lam_v.par_iter().zip(opening.par_iter()).zip(g.inverse_masses.par_iter());
                mine.zip(read).with_min_len(BLOCK).for_each(one)
            }),
            None => {
                let mine = (self.kicked.iter_mut().zip(pb.x.iter_mut()).zip(pb.v.iter_mut()))
                    .zip(pb.m.iter_mut().zip(pb.q.iter_mut()));
                mine.zip(lam_v.iter().zip(opening).zip(&g.inverse_masses)).for_each(one)
            }
        })
    }
}

type BodyPass<'a> = (
    (((&'a mut [f64; 3], &'a mut [f64; 3]), &'a mut [f64; 3]), (&'a mut f64, &'a mut f64)),
    ((&'a [f64; 3], &'a [f64; 3]), &'a f64),
);

/// After the closing kick's pullback `pb` at a state with forces `f`: its adjoints added to λ
/// (positions, masses, charges, parameters), the kick's own derivative by the masses if they are
/// wanted (with the covector λ_v + b), then the drift's transpose, λ_v ← λ_v + dt·λ_x, which is
/// also the next opening covector `opening`. The order of the operations of `add_into`,
/// `masses_through_kick` and the drift as they were written one after another.
pub(super) fn closing_and_drift(run: &Run, lam: &mut Adjoint, pb: &Adjoint, f: &[[f64; 3]], opening: &mut [[f64; 3]]) {
    for (a, b) in lam.params.iter_mut().zip(&pb.params) {
        a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
    }
    let (h, dt, masses) = (0.5 * run.dt, run.dt, run.wanted.masses);
    let one = |((((x, v), o), (m, q)), (((px, pm), pq), (f, w))): DriftPass<'_>| {
        (0..3).for_each(|c| x[c] += px[c]);
        *m += pm;
        *q += pq;
        if masses {
            let a: [f64; 3] = std::array::from_fn(|c| v[c] + o[c]);
            *m -= h * w * w * (f[0] * a[0] + f[1] * a[1] + f[2] * a[2]);
        }
        let next: [f64; 3] = std::array::from_fn(|c| v[c] + dt * x[c]);
        (*o, *v) = (next, next);
    };
    let g: &LagrangianGraph = &run.graph;
    spread::pass_if(f.len() >= SPREAD_FROM, || match g.spread() {
        Some(pool) => pool.install(|| {
            let mine = (lam.x.par_iter_mut().zip(lam.v.par_iter_mut()).zip(opening.par_iter_mut()))
                .zip(lam.m.par_iter_mut().zip(lam.q.par_iter_mut()));
            let read = (pb.x.par_iter().zip(pb.m.par_iter()).zip(pb.q.par_iter()))
                .zip(f.par_iter().zip(g.inverse_masses.par_iter()));
            mine.zip(read).with_min_len(BLOCK).for_each(one)
        }),
        None => {
            let mine = lam
                .x
                .iter_mut()
                .zip(lam.v.iter_mut())
                .zip(opening.iter_mut())
                .zip(lam.m.iter_mut().zip(lam.q.iter_mut()));
            let read = pb.x.iter().zip(&pb.m).zip(&pb.q).zip(f.iter().zip(&g.inverse_masses));
            mine.zip(read).for_each(one)
        }
    })
}

type DriftPass<'a> = (
    (((&'a mut [f64; 3], &'a mut [f64; 3]), &'a mut [f64; 3]), (&'a mut f64, &'a mut f64)),
    (((&'a [f64; 3], &'a f64), &'a f64), (&'a [f64; 3], &'a f64)),
);

/// |λ| over positions and velocities, summed in blocks of `BLOCK` bodies added in order: the
/// same bits on any number of threads.
pub(super) fn norm(g: &LagrangianGraph, a: &Adjoint) -> f64 {
    let block = |(x, v): (&[[f64; 3]], &[[f64; 3]])| x.iter().chain(v).flatten().map(|c| c * c).sum::<f64>();
    let parts: Vec<f64> = spread::pass_if(a.x.len() >= SPREAD_FROM, || match g.spread() {
        Some(pool) => pool.install(|| a.x.par_chunks(BLOCK).zip(a.v.par_chunks(BLOCK)).map(block).collect()),
        None => a.x.chunks(BLOCK).zip(a.v.chunks(BLOCK)).map(block).collect(),
    });
    parts.iter().sum::<f64>().sqrt()
}
