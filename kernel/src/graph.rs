//! The Lagrangian graph: bodies (the vertices), the term instances and the constraints (the
//! edges), the terms grouped by kind so the kernel dispatches once per group, not once per edge.
//! A kind the scene does not use has no group and costs nothing.
//!
//! The graph also offers the few operations a step is made of — evaluate the forces (all of
//! them, or all but the gyroscopic ones), kick, drift, rotate by the gyroscopic ω, project onto
//! the constraints — and each solver (`solvers/`) is a short program over them.

use crate::constraints::{Constraints, Swept, Tolerance, Unconverged};
use crate::contact::Solids;
use crate::forces::derivative::{Adjoint, Direction, Wanted};
use crate::forces::{group, Force, Frame, Kept, Parts, Pool, Singularity};
use crate::neighbours::LANES;
use crate::pieces::PIECE_CLUSTERS;
use crate::rigid::{self, Spin};
use crate::spread::SPREAD_FROM;
use crate::state::State;
use crate::step::{self, Stride};
use crate::sum::Sum;
use lagra_checker::model::{Body, Model};
use lagra_checker::terms::Kind;
use nalgebra::Vector3;
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
    constraints: Option<Constraints>,
    /// The rigid bodies' principal moments, in body order (what `State::spin` holds).
    moments: Vec<Vector3<f64>>,
    /// Whether each body is rigid (has a spin in `State::spin`).
    rigid: Vec<bool>,
    /// What can touch, if anything.
    solids: Option<Solids>,
    /// The run's threads, if it has more than one.
    pool: Pool,
}

/// A pool of `threads` for the forces (none for one), which graphs may share.
pub fn threads_of(threads: usize) -> Result<Pool, String> {
    Ok(match threads {
        0 => return Err("the thread count must be at least 1".into()),
        1 => None,
        n => Some(Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("lagra-kernel-{i}"))
                .start_handler(crate::spread::never_clocked)
                .build()
                .map_err(|e| format!("starting {n} threads: {e}"))?,
        )),
    })
}

/// `f` of each body, in order: on the pool's threads for a model of `SPREAD_FROM` bodies or
/// more, where the arrays' fresh memory is first touched there too.
fn per_body<U: Send>(pool: &Pool, model: &Model, f: impl Fn(&Body) -> U + Sync + Send) -> Vec<U> {
    let n = model.bodies.len();
    crate::spread::each(pool.as_deref().filter(|_| n >= SPREAD_FROM), n, |i| f(&model.bodies[i]))
}

/// Which forces an evaluation adds up.
#[derive(Clone, Copy, PartialEq)]
enum Which {
    All,
    /// Every group but the gyroscopic ones, which a solver rotates by instead (Boris).
    Positional,
}

impl LagrangianGraph {
    /// On one thread.
    pub fn new(model: &Model) -> Self {
        Self::with_pool(model, None)
    }

    /// On `threads` threads of a pool of its own (the forces come out the same to the bit).
    pub fn with_threads(model: &Model, threads: usize) -> Result<Self, String> {
        Ok(Self::with_pool(model, threads_of(threads)?))
    }

    /// On the threads of `pool` (none: one thread), shared with other graphs.
    pub fn with_pool(model: &Model, pool: Pool) -> Self {
        let mut groups = vec![];
        for &kind in Kind::ALL {
            let instances: Vec<_> = model.terms.iter().enumerate().filter(|t| t.1.kind == kind).collect();
            if !instances.is_empty() {
                groups.push((kind, group(kind, &instances, model, &pool)));
            }
        }
        let masses = per_body(&pool, model, |b| b.mass);
        let charges = per_body(&pool, model, |b| b.charge);
        let inverse_masses = per_body(&pool, model, |b| 1.0 / b.mass);
        let velocity_dependent = groups.iter().any(|g| g.1.velocity_dependent());
        let colours = per_body(&pool, model, |b| b.colour);
        let constraints = Constraints::of(model);
        let moments = model.rigid().map(Vector3::from).collect();
        let rigid = per_body(&pool, model, |b| b.moments.is_some());
        LagrangianGraph {
            masses,
            inverse_masses,
            velocity_dependent,
            charges,
            colours,
            groups,
            constraints,
            moments,
            rigid,
            solids: Solids::of(model),
            pool,
        }
    }

    /// Bodies `first..` are ghosts whose forces the caller drops (a domain's copies of other
    /// ranks' atoms): the pair groups leave out the pairs among them.
    pub fn leave_out_pairs_among(&self, first: usize) {
        self.groups.iter().for_each(|g| g.1.leave_out_pairs_among(first));
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

    /// Whether a velocity-dependent group is left once the gyroscopic ones are rotated by.
    pub fn velocity_dependent_positional(&self) -> bool {
        self.groups.iter().any(|g| g.1.velocity_dependent() && !g.1.gyroscopic())
    }

    /// Writes the generalized forces into `f` and returns the potential energy (a witness).
    pub fn forces(&self, s: &State, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        self.evaluate(s, f, true, Which::All)
    }

    /// Writes the generalized forces into `f`, and nothing else: for the steps no one sees.
    pub fn forces_only(&self, s: &State, f: &mut [[f64; 3]]) -> Result<(), Singularity> {
        self.evaluate(s, f, false, Which::All).map(|_| ())
    }

    /// The forces of every group but the gyroscopic ones, and the potential energy (theirs is
    /// zero): what Boris kicks with.
    pub fn positional_forces(&self, s: &State, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        self.evaluate(s, f, true, Which::Positional)
    }

    /// The potential energy and virial of every group with each interaction weighted by the
    /// share of its bodies below `owned` (`Force::owned_sums`): a rank's part of the whole
    /// system's, its ghosts from `owned` on. `None` if a group is not one the domains cut.
    pub fn owned_sums(&self, s: &State, owned: usize) -> Option<Result<[f64; 2], Singularity>> {
        let frame = self.frame_parts().frame(s);
        let (mut e, mut w) = (Sum::default(), Sum::default());
        for (_, g) in &self.groups {
            match g.owned_sums(&frame, owned)? {
                Ok([a, b]) => (e.add(a), w.add(b)),
                Err(err) => return Some(Err(err)),
            };
        }
        Some(Ok([e.value(), w.value()]))
    }

    /// The virial W = Σ r·F of every group (`Force::virial`), for the pressure; `None` if a
    /// group acts from outside (a field).
    pub fn virial(&self, s: &State) -> Option<Result<f64, Singularity>> {
        let frame = self.frame_parts().frame(s);
        let each: Option<Vec<_>> = self.groups.iter().map(|(_, g)| g.virial(&frame)).collect();
        Some(each?.into_iter().collect::<Result<Sum, _>>().map(|w| w.value()))
    }

    /// Each body's ω from the gyroscopic groups (F = m ω × v), into `w`.
    pub fn gyration(&self, s: &State, w: &mut [[f64; 3]]) {
        w.iter_mut().for_each(|wi| *wi = [0.0; 3]);
        let frame = self.frame_parts().frame(s);
        self.groups.iter().for_each(|(_, g)| g.gyration(&frame, w));
    }

    /// v += h·F/m.
    pub fn kick(&self, v: &mut [[f64; 3]], f: &[[f64; 3]], h: f64) {
        step::kick_on(v, f, &self.inverse_masses, h, self.spread());
    }

    /// The rigid bodies turn freely for `steps` steps of `h` (`rigid::free_step`): no term
    /// exerts a torque, so their rotation commutes with the rest of a step and is composed after
    /// it, the same bits whenever it runs.
    pub fn turn(&self, spin: &mut [Spin], h: f64, steps: u64) {
        for (s, &m) in spin.iter_mut().zip(&self.moments) {
            (0..steps).for_each(|_| rigid::free_step(s, m, h));
        }
    }

    /// The rigid bodies' principal moments, in the order of `State::spin`.
    pub fn moments(&self) -> &[Vector3<f64>] {
        &self.moments
    }

    /// The solids and floor the contact solver keeps apart (none: nothing can touch).
    pub fn solids(&self) -> Option<Solids> {
        self.solids.clone()
    }

    /// Whether body `i` is rigid.
    pub fn is_rigid(&self, i: usize) -> bool {
        self.rigid[i]
    }

    /// The threads a pass over the bodies (a kick, a drift) spreads over: the run's, from
    /// `SPREAD_FROM` bodies (below, waking them costs more than the pass).
    pub fn spread(&self) -> Option<&rayon::ThreadPool> {
        self.pool.as_deref().filter(|_| self.masses.len() >= SPREAD_FROM)
    }

    /// Whether a step of this graph spreads over its pool: at this size a pass over the bodies
    /// does, or the pair list is cut into pieces enough to share (`Pieces::count_for`). If not,
    /// sending its steps to the pool whole only wakes it (Kepler, checked every step, took 2.0 s
    /// on two threads that way against 0.9 s on the run's thread).
    pub fn steps_spread(&self) -> bool {
        self.pool.is_some() && self.masses.len() >= (2 * PIECE_CLUSTERS * LANES).min(SPREAD_FROM)
    }

    /// The run's threads, if it has more than one (for a pass that spreads at any size).
    pub fn pool(&self) -> Option<&rayon::ThreadPool> {
        self.pool.as_deref()
    }

    /// x += h·v.
    pub fn drift(&self, s: &mut State, h: f64) {
        step::drift(&mut s.x, &s.v, h);
    }

    /// The graph's only group, if it has one.
    pub fn sole(&self) -> Option<&dyn Force> {
        match self.groups.as_slice() {
            [(_, g)] => Some(g.as_ref()),
            _ => None,
        }
    }

    /// The inner steps of a conservative velocity Verlet run, monomorphized around the force
    /// code where the graph has one group.
    pub fn stride(&self, stride: Stride) -> Result<(), Singularity> {
        match self.sole() {
            Some(group) => group.stride(stride, self.frame_parts()),
            None => stride.run(|s, f| self.forces_only(s, f)),
        }
    }

    /// What a force group reads of the bodies besides the state: masses, charges, colours.
    pub fn frame_parts(&self) -> Parts<'_> {
        Parts { m: &self.masses, q: &self.charges, c: &self.colours }
    }

    /// Whether the graph has constraints to keep.
    pub fn constrained(&self) -> bool {
        self.constraints.is_some()
    }

    /// SHAKE: the positions moved onto the constraints along the rods as they were at
    /// `before`, the velocities by the same over `dt`.
    pub fn shake(&self, before: &[[f64; 3]], s: &mut State, dt: f64, tol: Tolerance) -> Result<Swept, Unconverged> {
        match &self.constraints {
            None => Ok(Swept { sweeps: 0, error: 0.0 }),
            Some(c) => c.positions(before, &mut s.x, &mut s.v, &self.inverse_masses, dt, tol),
        }
    }

    /// RATTLE: the velocities made tangent to the constraints.
    pub fn rattle(&self, s: &mut State, dt: f64, tol: Tolerance) -> Result<Swept, Unconverged> {
        match &self.constraints {
            None => Ok(Swept { sweeps: 0, error: 0.0 }),
            Some(c) => c.velocities(&s.x, &mut s.v, &self.inverse_masses, dt, tol),
        }
    }

    /// The derivative of the forces along `dir` (positions, velocities, masses, charges,
    /// parameters), into `df`: from the terms' definitions.
    pub fn tangent(&self, s: &State, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity> {
        df.iter_mut().for_each(|d| *d = [0.0; 3]);
        let frame = self.frame_parts().frame(s);
        self.groups.iter().try_for_each(|(_, g)| g.tangent(&frame, dir, df))
    }

    /// Adds the forces' derivatives, transposed, applied to `g`, to `out`.
    pub fn pullback(&self, s: &State, g: &[[f64; 3]], wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        let frame = self.frame_parts().frame(s);
        self.groups.iter().try_for_each(|(_, k)| k.pullback(&frame, g, wanted, out))
    }

    /// Adds the gradient of the potential energy to `out`.
    pub fn potential_pullback(&self, s: &State, wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        let frame = self.frame_parts().frame(s);
        self.groups.iter().try_for_each(|(_, k)| k.potential_pullback(&frame, wanted, out))
    }

    /// What the groups keep between evaluations (their neighbour lists), saved: a replay that
    /// starts from a saved state with them (`resume`) is the same bits as the run.
    pub fn keep(&self) -> Vec<Option<Kept>> {
        self.groups.iter().map(|(_, g)| g.save()).collect()
    }

    pub fn resume(&self, kept: &[Option<Kept>]) {
        for ((_, g), k) in self.groups.iter().zip(kept) {
            if let Some(k) = k {
                g.restore(k);
            }
        }
    }

    /// Where each group's kept list was last built (`Force::built_at`), in the order of the
    /// groups: a restart file's.
    pub fn lists_built_at(&self) -> Vec<Option<Vec<[f64; 3]>>> {
        self.groups.iter().map(|(_, g)| g.built_at()).collect()
    }

    /// Builds each group's list where `lists_built_at` said (before the first force evaluation
    /// of a resumed run). The error is a restart that does not fit this graph.
    pub fn build_lists_at(&self, at: &[Option<Vec<[f64; 3]>>]) -> Result<(), String> {
        if at.len() != self.groups.len() {
            return Err(format!("it holds lists for {} term groups, the scene has {}", at.len(), self.groups.len()));
        }
        for ((kind, g), x) in self.groups.iter().zip(at) {
            match x {
                Some(x) if x.len() != self.masses.len() => {
                    return Err(format!(
                        "its {} list has {} bodies, the scene {}",
                        kind.name(),
                        x.len(),
                        self.masses.len()
                    ))
                }
                Some(x) if x.iter().flatten().any(|c| !c.is_finite()) => {
                    return Err(format!("its {} list was built at non-finite positions", kind.name()))
                }
                Some(x) => g.build_at(x),
                None => {}
            }
        }
        Ok(())
    }

    /// How many times the kept lists have been built, in all (it changes when one is rebuilt).
    pub fn builds(&self) -> u64 {
        self.groups.iter().map(|(_, g)| g.builds()).sum()
    }

    fn evaluate(&self, s: &State, f: &mut [[f64; 3]], energy: bool, which: Which) -> Result<f64, Singularity> {
        f.iter_mut().for_each(|fi| *fi = [0.0; 3]);
        let frame = Frame { x: &s.x, v: &s.v, m: &self.masses, q: &self.charges, c: &self.colours };
        let mut potential = Sum::default();
        for (_, g) in self.groups.iter().filter(|g| which == Which::All || !g.1.gyroscopic()) {
            potential.add(g.accumulate(&frame, f, energy)?);
        }
        Ok(potential.value())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::compile;

    /// 5,324 Lennard-Jones atoms (enough to split the pair list into chunks), a few steps into a
    /// melt so that the list is stale and images cross the box.
    /// An LJ liquid of `cells`³ fcc cells.
    fn liquid(cells: usize) -> lagra_lang::Scene {
        let text = format!(
            "scene m {{ entity atom {{ mass: 1 }}
               lattice {{ type: atom, density: 0.8442, cells: [{cells}, {cells}, {cells}], temperature: 3.0, seed: 9 }}
               interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
               solver {{ dt: 0.005, steps: 1 }} }}"
        );
        compile(&text).unwrap()
    }

    fn melt() -> (Model, State) {
        let scene = liquid(11);
        let mut s = crate::setup::start(&scene);
        s.x.iter_mut().zip(&s.v).for_each(|(x, v)| (0..3).for_each(|c| x[c] += 0.02 * v[c] - 40.0));
        (Arc::unwrap_or_clone(scene.model), s)
    }

    /// A step spreads where its pair list is cut into pieces (5,324 atoms), not on a handful of
    /// atoms, and never without a pool.
    #[test]
    fn steps_spread_where_the_pairs_are_cut_into_pieces() {
        let (model, _) = melt();
        assert!(LagrangianGraph::with_threads(&model, 2).unwrap().steps_spread());
        assert!(!LagrangianGraph::with_threads(&model, 1).unwrap().steps_spread());
        assert!(!LagrangianGraph::with_threads(&liquid(3).model, 2).unwrap().steps_spread());
    }

    /// Bodies ordered along x, the last third ghosts: the pairs among them are left out, the
    /// forces on the others are the same to round-off.
    #[test]
    fn pairs_among_ghosts_are_left_out_and_the_others_forces_stay() {
        let (model, mut s) = melt();
        let mut order: Vec<usize> = (0..s.x.len()).collect();
        order.sort_by(|&a, &b| s.x[a][0].rem_euclid(40.0).total_cmp(&s.x[b][0].rem_euclid(40.0)));
        s.x = order.iter().map(|&i| s.x[i]).collect();
        let (n, first) = (s.x.len(), 2 * s.x.len() / 3);
        let (whole, cut) = (LagrangianGraph::new(&model), LagrangianGraph::new(&model));
        cut.leave_out_pairs_among(first);
        let (mut f, mut g) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
        whole.forces(&s, &mut f).unwrap();
        cut.forces(&s, &mut g).unwrap();
        let off = (0..first)
            .flat_map(|i| (0..3).map(move |c| (i, c)))
            .map(|(i, c)| (f[i][c] - g[i][c]).abs())
            .fold(0.0, f64::max);
        assert!(off < 1e-10, "the owned bodies' forces moved by {off:e}");
        let pairs = |g: &LagrangianGraph| {
            g.plan()[0].1.split(" cluster pairs").next().unwrap().rsplit(' ').next().unwrap().parse::<usize>().unwrap()
        };
        assert!(pairs(&cut) < pairs(&whole) * 9 / 10, "{} of {} cluster pairs", pairs(&cut), pairs(&whole));
        // the ghosts' own forces lack the pairs left out
        assert!((first..n).any(|i| f[i] != g[i]));
    }

    /// The virial through the force kernel against the double loop over every pair: W = Σ r·F,
    /// the force on i from j being s·(xⱼ − xᵢ) with s the shifted LJ's; the same bits on any
    /// number of threads.
    #[test]
    fn the_virial_through_the_list_is_that_of_every_pair() {
        let (model, s) = melt();
        let mut w = crate::sum::Sum::default();
        crate::traverse::pairs::<()>(&s.x, &model.cell, None, |_, _, d| {
            let r2: f64 = d.iter().map(|c| c * c).sum();
            if r2 < 6.25 {
                let inv6 = r2.powi(-3);
                w.add(-24.0 * (inv6 - 2.0 * inv6 * inv6));
            }
            Ok(())
        })
        .unwrap();
        let every = w.value();
        let one = LagrangianGraph::with_threads(&model, 1).unwrap().virial(&s).unwrap().unwrap();
        assert!((one - every).abs() < 1e-11 * every.abs(), "{one} against {every}");
        let two = LagrangianGraph::with_threads(&model, 2).unwrap().virial(&s).unwrap().unwrap();
        assert_eq!(one.to_bits(), two.to_bits());
    }

    /// Two ranks' parts, each with its own bodies first and the other's after (as ghosts), add
    /// up to the whole system's potential energy and virial: a pair within a part counts once,
    /// a pair across the two half on each side.
    #[test]
    fn the_owned_parts_add_up_to_the_whole() {
        let (model, s) = melt();
        let g = LagrangianGraph::new(&model);
        let whole = [g.forces(&s, &mut vec![[0.0; 3]; s.x.len()]).unwrap(), g.virial(&s).unwrap().unwrap()];
        let all = g.owned_sums(&s, s.x.len()).unwrap().unwrap();
        // every body owned: the whole's bits (one domain steps and measures as one process)
        assert_eq!(all.map(f64::to_bits), whole.map(f64::to_bits), "{all:?} against {whole:?}");
        let first = s.x.len() / 3;
        let a = g.owned_sums(&s, first).unwrap().unwrap();
        let mut turned = s.clone();
        turned.x.rotate_left(first);
        let b = LagrangianGraph::new(&model).owned_sums(&turned, s.x.len() - first).unwrap().unwrap();
        for k in 0..2 {
            let close = |x: f64| (x - whole[k]).abs() < 1e-10 * whole[k].abs();
            assert!(
                close(all[k]) && close(a[k] + b[k]),
                "sum {k}: {} and {} + {} against {}",
                all[k],
                a[k],
                b[k],
                whole[k]
            );
            assert!(a[k].abs() < 0.5 * whole[k].abs(), "a third of the bodies hold about a third");
        }
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
        assert!(g.plan()[0].1.starts_with("cluster-pair list"), "{:?}", g.plan());
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
