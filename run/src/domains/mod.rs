//! A scene cut into domains across the ranks of a job (`mpirun -np P lagra run SCENE`): the
//! periodic box cut into bricks (`bricks`), each rank owning the atoms in its brick and taking
//! as ghosts every atom within the halo (the terms' reach plus a skin) of it, velocity Verlet
//! stepped on each rank over its own atoms with the kernel's forces of its local system, the
//! ghosts' positions exchanged every step, and atoms moved to their owners (and the ghosts
//! chosen again) when one has moved half the skin since the last choice.
//!
//! What the kernel sees on a rank is an ordinary graph: the scene's model with the rank's atoms
//! then its ghosts as bodies. The pair terms' nearest image in the whole box makes one copy of
//! each ghost enough, so any rank may need a ghost from any other: the exchanges are
//! all-to-all. A force on a ghost is computed and dropped; a pair across two bricks is computed
//! on both ranks (LAMMPS's `newton off`), so no force travels back.
//!
//! The bits: a rank's atoms are kept in the order of their numbers, its ghosts in the order of
//! their senders and then of the senders' atoms, so a run on P ranks gives the same bits every
//! time and on any thread count. A different P sums each atom's pair forces in another order,
//! so trajectories agree with the one-process run to round-off that grows as the dynamics
//! amplifies it (tested against a bound in `tests`).
//!
//! A thermostat is stepped as one process steps it (`Bath`): a Nosé–Hoover chain on every rank,
//! moved by the kinetic energy gathered from the ranks; a Langevin bath's noise drawn for each
//! atom's number.
//!
//! The claims are judged by rank 0's checker, on the whole state gathered at each state it is
//! shown (`Shared::advance_to`), so that the certificate records every state a single process
//! would and `lagra-check` re-checks it anywhere. At a checkpoint of energy or momentum each
//! rank also encloses its own part of both with the checker's arithmetic (`enclose`: its atoms'
//! kinetic energy and momentum, its pairs with a ghost counted half, the bonded instances whose
//! first atom it owns), and rank 0's checker adds the parts outward where they cover the whole
//! (`lagra_checker::quantities::Parts`): the checker's pair sums run on every rank over its own
//! domain instead of on rank 0 over the whole. A trace frame's energy and a sample's potential
//! energy and virial are the ranks' own f64 sums (`EnergyAndVirial`), added on every rank.

mod asks;
pub mod bonded;
pub mod bricks;
pub mod exchange;

pub use asks::{Asks, EnergyAndVirial, Reached};
use bonded::Bonded;
use bricks::Bricks;
use exchange::Exchange;
use lagra_checker::model::{Model, TermInstance};
use lagra_checker::terms::Shape;
use lagra_kernel::forces::Pool;
use lagra_kernel::graph::LagrangianGraph;
use lagra_kernel::state::State;
use lagra_kernel::step::{drift, kick, kick_drift};
use lagra_kernel::sum::Sum;
use lagra_kernel::thermostat::{chain_half, langevin_bath};
use lagra_lang::integrator::Integrator;
use lagra_lang::scene::Scene;
use lagra_lang::thermostat::Thermostat;
use std::sync::Arc;
use std::time::Instant;

/// The skin beyond the reach, as a fraction of it (the kernel's lists use the same).
const SKIN: f64 = 0.12;

/// What rank 0 broadcasts to end the followers' loop.
const STOP: u64 = u64::MAX;

/// Why a scene cannot be cut into domains, if it cannot: what this first decomposition does
/// not carry across ranks yet runs whole on rank 0 instead.
pub fn fits(scene: &Scene) -> Result<(), String> {
    let m = &scene.model;
    let not = |why: &str| Err(format!("it {why}, which the domains do not carry across ranks yet"));
    match m.cell {
        Some(c) if c.periodic.iter().all(|&p| p) => {}
        _ => return Err("it has no box periodic along all three axes to cut into bricks".into()),
    }
    if scene.solver.integrator != Integrator::VelocityVerlet {
        return not(&format!("is stepped by {}, not velocity_verlet", scene.solver.integrator.name()));
    }
    let pairs = |t: &&TermInstance| t.kind.spec().shape == Shape::Pairwise;
    let bonds = |t: &&TermInstance| matches!(t.kind.spec().shape, Shape::Bond(_)) && !t.sites.is_empty();
    if let Some(t) = m.terms.iter().find(|t| !pairs(t) && !bonds(t)) {
        return not(&format!("has a {} term (interactions between pairs and bonded terms are cut)", t.kind.name()));
    }
    if let Some(t) = m.terms.iter().filter(pairs).find(|t| !t.kind.reach(&t.params).is_finite()) {
        return not(&format!("has a {} term without a cut-off", t.kind.name()));
    }
    if let Some(t) = m.terms.iter().find(|t| t.kind.reads().v || t.dissipates()) {
        return not(&format!("has a {} term whose force depends on the velocities", t.kind.name()));
    }
    if m.terms.is_empty() {
        return not("has no interaction");
    }
    if !m.constraints.is_empty() || !m.pins.is_empty() || m.floor.is_some() {
        return not("has constraints, joints or a floor");
    }
    if m.bodies.iter().any(|b| b.moments.is_some() || b.solid.is_some()) {
        return not("has rigid or solid bodies");
    }
    if !scene.predictions.is_empty() {
        return not("has predictions (measured at every step on rank 0)");
    }
    Ok(())
}

/// Steps taken by every rank together, seen from rank 0's run loop: advance to a step and
/// gather the whole state there, and what is asked of the state reached.
pub trait Shared {
    fn advance_to(&mut self, s: &mut State, until: u64, asks: Asks) -> Result<Reached, String>;
    /// How the work was shared, for `--explain`.
    fn plan(&self) -> String;
}

/// One rank's share of the run: its atoms, its ghosts, and the kernel's graph of them.
pub struct Domain<E: Exchange> {
    ex: E,
    bricks: Bricks,
    reach: f64,
    halo: f64,
    dt: f64,
    pool: Pool,
    /// The scene's model without its bodies, and the whole scene's: the local graph's bodies
    /// are the owned atoms' and the ghosts'.
    model: Model,
    whole: Arc<Model>,
    /// The local graph's model (for the checker's part), and the numbers of its bonded
    /// instances among the whole's.
    local_model: Model,
    instances: Vec<usize>,
    threads: usize,
    bonded: Bonded,
    bath: Bath,
    /// The atoms this rank owns, by number, ascending.
    owned: Vec<usize>,
    /// The ranks whose bricks touch this one's (`Bricks::peers`), and each rank's place among
    /// them (`usize::MAX` for the others): every exchange but the gather is with these.
    peers: Vec<usize>,
    peer_at: Vec<usize>,
    /// For each peer, the places in `owned` of the atoms it takes as ghosts.
    send: Vec<Vec<usize>>,
    /// The ghosts' numbers, in their places after the owned atoms.
    ghosts: Vec<usize>,
    /// The owned atoms then the ghosts (velocities of ghosts zero: no force reads them), and a
    /// thermostat chain's links (the same on every rank).
    local: State,
    /// The forces on `local`, owned first; between steps, the owned atoms' at the state reached.
    f: Vec<[f64; 3]>,
    inverse: Vec<f64>,
    /// The owned atoms' positions when the ghosts were last chosen.
    since: Vec<[f64; 3]>,
    graph: LagrangianGraph,
    step: u64,
    tally: Tally,
    /// Whether the owned atoms are those the graph was made with, in its order.
    owned_kept: bool,
    /// Whether rank 0's share, dropped, sends the others home: once every rank has one.
    leads: bool,
}

/// What holds the run at a temperature, stepped over the ranks' atoms as in one process.
enum Bath {
    None,
    /// A Nosé–Hoover chain: its links on every rank, moved by the kinetic energy of every
    /// rank's atoms summed in rank order.
    Chain(lagra_checker::thermostat::Chain),
    /// A Langevin bath (BAOAB): each atom's noise drawn for its number, as in one process.
    Langevin {
        kt: f64,
        gamma: f64,
        seed: u64,
    },
}

impl Bath {
    /// What `--explain` says of it.
    fn said(&self) -> &'static str {
        match self {
            Bath::None => "",
            Bath::Chain(_) => "; a Nosé–Hoover chain, the kinetic energy gathered from every rank twice a step",
            Bath::Langevin { .. } => "; a Langevin bath, each atom's noise drawn for its number",
        }
    }
}

/// What the plan reports.
#[derive(Default)]
struct Tally {
    regroups: u64,
    ghosts: u64,
    owned: u64,
    talking: f64,
    /// Seconds in migrating and choosing ghosts (exchanges included), in the forces, and in
    /// enclosing this rank's parts of the energy and momentum (their gathers included).
    regrouping: f64,
    forcing: f64,
    enclosing: f64,
    started: Option<Instant>,
}

impl<E: Exchange> Domain<E> {
    /// This rank's share of the scene at state `s` (every rank passes the same), the box cut
    /// by `grid` ("2x2x1") or by the ranks and the box. A collective. `threads` for this rank's
    /// forces.
    pub fn new(ex: E, scene: &Scene, s: &State, grid: Option<&str>, threads: usize) -> Result<Self, String> {
        fits(scene)?;
        // the pair terms are every rank's; the bonded ones each rank's own (`Bonded::local`)
        let pairs = scene.model.terms.iter().filter(|t| t.sites.is_empty()).cloned().collect();
        // (the rest of the scene's model field by field: its bodies are not copied to be dropped)
        let m = &scene.model;
        let model = Model {
            units: m.units,
            cell: m.cell,
            bodies: vec![],
            terms: pairs,
            constraints: m.constraints.clone(),
            thermostat: m.thermostat.clone(),
            floor: m.floor,
            pins: m.pins.clone(),
        };
        let bonded = Bonded::of(&scene.model, &s.x);
        let bath = match (&scene.thermostat, &scene.model.thermostat) {
            (Some(Thermostat::NoseHoover { .. }), Some(chain)) => Bath::Chain(chain.clone()),
            (Some(Thermostat::Langevin { kt, gamma, seed }), _) => {
                Bath::Langevin { kt: *kt, gamma: *gamma, seed: *seed }
            }
            _ => Bath::None,
        };
        let cell = model.cell.expect("fits: a periodic box");
        let reach = model.terms.iter().map(|t| t.kind.reach(&t.params)).fold(bonded.span, f64::max);
        let halo = reach * (1.0 + SKIN);
        let bricks = match grid {
            Some(g) => Bricks::given(g, ex.size(), cell.size, halo)?,
            None => Bricks::chosen(ex.size(), cell.size, halo)?,
        };
        let pool = lagra_kernel::graph::threads_of(threads)?;
        let me = ex.rank();
        let owned: Vec<usize> = (0..s.x.len()).filter(|&i| bricks.owner(s.x[i]) == me).collect();
        let local = State {
            step: s.step,
            t: s.t,
            x: owned.iter().map(|&i| s.x[i]).collect(),
            v: owned.iter().map(|&i| s.v[i]).collect(),
            chain: s.chain.clone(),
            spin: vec![],
        };
        let graph = LagrangianGraph::with_pool(&model, None);
        let mut d = Domain {
            ex,
            bricks,
            reach,
            halo,
            dt: scene.solver.dt,
            pool,
            local_model: model.clone(),
            model,
            whole: scene.model.clone(),
            instances: vec![],
            threads,
            bonded,
            bath,
            owned,
            peers: vec![],
            peer_at: vec![],
            send: vec![],
            ghosts: vec![],
            local,
            f: vec![],
            inverse: vec![],
            since: vec![],
            graph,
            step: s.step,
            tally: Tally { started: Some(Instant::now()), ..Tally::default() },
            leads: false,
            owned_kept: false,
        };
        d.peers = d.bricks.peers(me);
        d.peer_at = vec![usize::MAX; d.ex.size()];
        d.peers.iter().enumerate().for_each(|(k, &r)| d.peer_at[r] = k);
        d.regroup()?;
        d.forces()?;
        d.leads = d.ex.rank() == 0;
        Ok(d)
    }

    /// Chooses the ghosts again: each rank's atoms near another's brick are sent there, and the
    /// local graph is made of the owned atoms and the ghosts received, with the pair terms and
    /// the bonded instances of the owned atoms. Fails on every rank if an instance's atom is not
    /// among a rank's (it stretched beyond the halo).
    fn regroup(&mut self) -> Result<(), String> {
        let (me, n) = (self.ex.rank(), self.owned.len());
        let mut send = vec![vec![]; self.peers.len()];
        for (k, &x) in self.local.x[..n].iter().enumerate() {
            self.bricks.near(x, self.halo, |r| {
                if r != me {
                    send[self.peer_at[r]].push(k)
                }
            });
        }
        let out = send
            .iter()
            .map(|s| s.iter().flat_map(|&k| with_number(self.owned[k], self.local.x[k])).collect())
            .collect();
        let got = self.talk(|ex, peers| ex.swap(peers, out));
        let ghosts: Vec<usize> = got.iter().flat_map(|g| g.chunks_exact(4)).map(|g| g[0] as usize).collect();
        self.local.x.truncate(n);
        self.local.x.extend(got.iter().flat_map(|g| g.chunks_exact(4)).map(|g| [g[1], g[2], g[3]]));
        self.local.v.resize(n, [0.0; 3]);
        self.local.v.resize(n + ghosts.len(), [0.0; 3]);
        self.f = vec![[0.0; 3]; n + ghosts.len()];
        self.inverse = self.owned.iter().map(|&i| 1.0 / self.whole.bodies[i].mass).collect();
        self.since = self.local.x[..n].to_vec();
        // the same bodies in the same places keep their graph, and its neighbour list, which
        // rebuilds itself as the bodies move: on one rank, the one-process run's bits
        let rebuild = ghosts != self.ghosts || !self.owned_kept;
        let place: std::collections::HashMap<usize, usize> =
            self.owned.iter().chain(&ghosts).enumerate().map(|(k, &i)| (i, k)).collect();
        let bonded = self.bonded.local(&self.owned, &place);
        let mut apart = [bonded.as_ref().map_or(1.0, |_| 0.0)];
        self.talk(|ex, _| ex.max(&mut apart));
        let (instances, bonded): (Vec<usize>, Vec<TermInstance>) = match (bonded, apart[0]) {
            (Ok(b), 0.0) => b.into_iter().unzip(),
            (Err([i, j]), _) => {
                return Err(format!(
                    "atoms {i} and {j} of a bonded term lie beyond the domains' halo ({:.4}) at step {}: it \
                     stretched further than the domains allow (1.5 × its span at the start, or a FENE bond's R0)",
                    self.halo, self.step
                ))
            }
            (Ok(_), _) => {
                return Err(format!(
                    "another rank's bonded term stretched beyond the domains' halo ({:.4}) at step {} (it says which on its stderr)",
                    self.halo, self.step
                ))
            }
        };
        if rebuild {
            let bodies = self.owned.iter().chain(&ghosts).map(|&i| self.whole.bodies[i].clone()).collect();
            let terms = self.model.terms.iter().cloned().chain(bonded).collect();
            self.local_model = Model { bodies, terms, ..self.model.clone() };
            self.instances = instances;
            self.graph = LagrangianGraph::with_pool(&self.local_model, self.pool.clone());
            // pairs between ghosts give no owned atom a force
            self.graph.leave_out_pairs_among(n);
        }
        self.owned_kept = true;
        self.send = send;
        self.ghosts = ghosts;
        self.tally.regroups += 1;
        self.tally.ghosts += self.ghosts.len() as u64;
        self.tally.owned += n as u64;
        Ok(())
    }

    /// Moves each atom that left this rank's brick to its owner; keeps the owned in number order.
    fn migrate(&mut self) {
        let (me, n) = (self.ex.rank(), self.owned.len());
        let mut out = vec![vec![]; self.peers.len()];
        let mut kept = vec![];
        for k in 0..n {
            match self.bricks.owner(self.local.x[k]) {
                r if r == me => kept.push(k),
                // an atom moves less than half the skin between two moves: to a peer
                r => out[self.peer_at[r]]
                    .extend(with_number(self.owned[k], self.local.x[k]).into_iter().chain(self.local.v[k])),
            }
        }
        let got = self.talk(|ex, peers| ex.swap(peers, out));
        let mut atoms: Vec<(usize, [f64; 3], [f64; 3])> =
            kept.iter().map(|&k| (self.owned[k], self.local.x[k], self.local.v[k])).collect();
        atoms.extend(
            got.iter().flat_map(|g| g.chunks_exact(7)).map(|a| (a[0] as usize, [a[1], a[2], a[3]], [a[4], a[5], a[6]])),
        );
        atoms.sort_unstable_by_key(|a| a.0);
        let owned: Vec<usize> = atoms.iter().map(|a| a.0).collect();
        self.owned_kept = owned == self.owned;
        self.owned = owned;
        self.local.x = atoms.iter().map(|a| a.1).collect();
        self.local.v = atoms.iter().map(|a| a.2).collect();
    }

    /// The ghosts' positions, from their owners, in the order chosen at the last regroup.
    fn share_positions(&mut self) {
        let n = self.owned.len();
        let out = self.send.iter().map(|s| s.iter().flat_map(|&k| self.local.x[k]).collect()).collect();
        let got = self.talk(|ex, peers| ex.swap(peers, out));
        for (slot, x) in self.local.x[n..].iter_mut().zip(got.iter().flat_map(|g| g.chunks_exact(3))) {
            *slot = [x[0], x[1], x[2]];
        }
    }

    /// The forces on the local system; every rank learns whether any rank's failed (the lowest
    /// such rank, which says why on its stderr).
    fn forces(&mut self) -> Result<(), String> {
        let mine = self.graph.forces_only(&self.local, &mut self.f);
        if let Err(e) = &mine {
            eprintln!("lagra (rank {}): at step {}: {e}", self.ex.rank(), self.step + 1);
        }
        // the lowest failing rank, as the largest −rank
        let mut failed = [mine.as_ref().map_or(-(self.ex.rank() as f64), |_| f64::NEG_INFINITY)];
        self.talk(|ex, _| ex.max(&mut failed));
        match (mine, failed[0]) {
            (_, f64::NEG_INFINITY) => Ok(()),
            (Err(e), _) => Err(e.to_string()),
            (Ok(()), r) => Err(format!("the forces on rank {} could not be evaluated (it says why on its stderr)", -r)),
        }
    }

    /// One velocity Verlet step of the owned atoms, as the one-process solver takes it (the same
    /// arithmetic per atom, `kick_drift` then `kick`), inside a thermostat's half-steps or with a
    /// Langevin bath between its drifts.
    fn step(&mut self) -> Result<(), String> {
        let (n, h, dt) = (self.owned.len(), 0.5 * self.dt, self.dt);
        self.chain_half(h);
        let spread = self.graph.spread();
        let l = &mut self.local;
        match self.bath {
            Bath::Langevin { kt, gamma, seed } => {
                kick(&mut l.v[..n], &self.f[..n], &self.inverse, h);
                drift(&mut l.x[..n], &l.v[..n], h);
                langevin_bath(&mut l.v[..n], &self.inverse, |k| self.owned[k], (kt, gamma, seed), self.step, dt);
                drift(&mut l.x[..n], &l.v[..n], h);
            }
            _ => kick_drift(&mut l.x[..n], &mut l.v[..n], &mut self.f[..n], &self.inverse, (h, dt), false, spread),
        }
        let moved = l.x[..n].iter().zip(&self.since).map(|(x, s)| dist2(x, s)).fold(0.0, f64::max);
        let mut far = [moved];
        self.talk(|ex, _| ex.max(&mut far));
        let skin = self.halo - self.reach;
        if far[0] > 0.25 * skin * skin {
            let t = Instant::now();
            self.migrate();
            self.regroup()?;
            self.tally.regrouping += t.elapsed().as_secs_f64();
        } else {
            self.share_positions();
        }
        let t = Instant::now();
        self.forces()?;
        self.tally.forcing += t.elapsed().as_secs_f64();
        let n = self.owned.len();
        kick(&mut self.local.v[..n], &self.f[..n], &self.inverse, h);
        self.chain_half(h);
        self.step += 1;
        Ok(())
    }

    /// A Nosé–Hoover chain's half-step: the owned atoms' kinetic energy summed (compensated, in
    /// number order, as one process sums it), the ranks' sums added in rank order on every rank
    /// (so every rank moves the links alike, and one rank gives the one-process bits), the
    /// owned atoms' velocities scaled.
    fn chain_half(&mut self, h: f64) {
        if !matches!(self.bath, Bath::Chain(_)) {
            return;
        }
        let n = self.owned.len();
        let mine: Sum = (self.local.v[..n].iter().zip(&self.owned))
            .map(|(v, &i)| 0.5 * self.whole.bodies[i].mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
            .collect();
        let all = self.talk(|ex, _| ex.all_gather(&mine.parts()));
        let mut kinetic = Sum::default();
        all.chunks_exact(2).for_each(|p| kinetic.merge(Sum::of_parts([p[0], p[1]])));
        if let Bath::Chain(chain) = &self.bath {
            let scale = chain_half(chain, &mut self.local.chain, kinetic.value(), h);
            self.local.v[..n].iter_mut().flatten().for_each(|c| *c *= scale);
        }
    }

    fn steps_to(&mut self, until: u64) -> Result<(), String> {
        while self.step < until {
            self.step()?;
        }
        Ok(())
    }

    fn talk<T>(&mut self, say: impl FnOnce(&E, &[usize]) -> T) -> T {
        let t = Instant::now();
        let r = say(&self.ex, &self.peers);
        self.tally.talking += t.elapsed().as_secs_f64();
        r
    }
}

impl<E: Exchange> Drop for Domain<E> {
    /// Rank 0's share, dropped when its run ends (or fails), sends the others home.
    fn drop(&mut self) {
        if self.leads {
            let mut stop = STOP;
            self.ex.broadcast(&mut stop);
        }
    }
}

/// An atom's number (exact in an f64 below 2^53) and its position.
fn with_number(i: usize, x: [f64; 3]) -> [f64; 4] {
    [i as f64, x[0], x[1], x[2]]
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]) * (a[c] - b[c])).sum()
}

#[cfg(test)]
mod tests;
