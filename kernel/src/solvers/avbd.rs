//! Augmented Vertex Block Descent (Giles, Diaz and Yuksel, SIGGRAPH 2025; after Vertex Block
//! Descent, Chen, Macklin and Yuksel 2024): a step of implicit Euler written as a minimisation,
//!
//!   x = argmin ½‖x − y‖²_M / dt² + Σ_j E_j(x),   y = x₀ + dt v₀ + dt² M⁻¹F(x₀),
//!
//! solved body by body: each body's six degrees of freedom take one Newton step against the
//! inertial term and its contacts with the others held still, bodies of one colour (no contact
//! between them) at once, the colours from the ground up (a body's level is its distance in
//! contacts from the floor, so a sweep carries support up a tower in one pass); on a pool of
//! threads, where the bodies fall into islands (joined by contacts and pins, not by the floor)
//! enough to share out, an island at a time on each thread (`islands.rs`), with the same bits.
//! A contact is
//! three rows (normal, two tangents), each a hard constraint C ≥ 0 (or C = 0 for sticking
//! friction) held by an augmented Lagrangian: the force F = k C + λ, clamped (push only;
//! friction inside Coulomb's disc μ|Fₙ|); after each sweep λ takes the force and, where the
//! bound does not bind, the stiffness k ramps by β|C|, so the constraint stiffens only as far as
//! it is violated. λ and k start from last step's contact of the same pair nearest the point
//! (λ at half, k decayed by γ), so a resting stack starts each step with part of its weight
//! already carried.
//!
//! A body's unknown is its move over the step, Δ = (Δx, Δθ): its centre's displacement and its
//! turn as a rotation vector (the pose at the end is x₀ + Δx, exp(Δθ) q₀). A contact row is
//! linear in the moves, as in the authors' reference solvers: C = J_a·Δ_a + J_b·Δ_b − d, its
//! Jacobians J = ±(d, r × d) taken where the contact was found, so each body's share of the
//! energy is a quadratic with clamps and its Newton step is exact on it (the nonlinear row,
//! evaluated at the turned anchors, let a stiff contact overshoot and a tall stack blow up).
//! The normal row's d is the overlap d₀ found at the step's start, of which only a share
//! 1 − α is corrected in a step (stabilisation, so a deep start does not explode apart), or
//! the gap of a speculative contact; the friction rows measure the slip since the step began.
//! Velocities are the move over dt (v = Δx/dt, ω = Δθ/dt in the world, π = I Rᵀω), so the
//! method dissipates as implicit Euler does, which is what lets a stack settle.
//!
//! A joint is pins (`lagra_checker::model::Pin`), each three equality rows along x, y, z of
//! the gap between a point of b and one of a (or of the world), linear in the moves like a
//! contact's, unclamped, warm-started as a contact's are, with a share 1 − α_pin of the step's
//! starting gap closed in the step.
//!
//! Nothing here is trusted: `resting` and `no_penetration` are decided by the checker's own
//! geometry on the states this produces, and `joint_satisfied` by the pins' gaps.

use super::{Carried, Evaluated, Failure, Iterations, Solver};
use crate::contact::{Pose, Solids};
use crate::graph::LagrangianGraph;
use crate::spread;
use crate::state::State;
use block::Block;
use colours::Rows;
use contact::{Bound, Contact};
use islands::{Island, Islands, Whole};
use lagra_checker::model::Pin;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3, Vector6};
use rayon::prelude::*;
use rayon::ThreadPool;
use warm::{Kept, Key, Warm};

type V = Vector3<f64>;
/// A body's move over the step: displacement, then rotation vector.
type Move = Vector6<f64>;

pub struct Avbd {
    pub at: Evaluated,
    pub solids: Solids,
    /// Sweeps over the bodies per step.
    pub sweeps: u32,
    /// Last step's contacts: place, λ and k of the three rows.
    warm: Warm,
    iterations: Iterations,
    paths: Paths,
}

/// How the steps were swept, for `--explain`: island by island on the pool, the whole with
/// each colour spread over the pool, or island by island on one thread; and the last step's
/// islands.
#[derive(Default)]
struct Paths {
    islands: u64,
    colours: u64,
    /// Colour passes that spread over the pool (`SPREAD_FROM` bodies or more).
    spread: u64,
    /// Steps swept island by island without a pool.
    alone: u64,
    last: Option<(usize, usize)>,
}

impl Avbd {
    pub fn new(at: Evaluated, solids: Solids, sweeps: u32) -> Avbd {
        let iterations = Iterations {
            what: "AVBD sweeps (residual: the largest overlap beyond the stabilised target, or joint gap)",
            ..Default::default()
        };
        Avbd { at, solids, sweeps, warm: Warm::default(), iterations, paths: Paths::default() }
    }
}

/// A body in the solve: its move so far, the move inertia alone would make, and what resists a
/// move (m/dt² and the world inertia over dt²: none for a point mass, which does not turn).
#[derive(Clone, Copy)]
struct Body {
    moved: Move,
    target: Move,
    /// m/dt².
    mass: f64,
    inertia: Option<Matrix3<f64>>,
}

impl Solver for Avbd {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let start = self.solids.poses(&s.x, &s.spin);
        // the islands a task each where they share out over the pool's threads (nothing to
        // wait for between colours), or one after another without a pool; else the whole at
        // once, each colour spread over the pool. (On one thread the whole was swept at once
        // until the islands' split got cheap: island by island, a colour pass is clocked only
        // as part of its island's, and `hinged_chain`, whose 4 bodies' passes took a clock
        // reading each, runs in 0.05 s instead of 0.075 s.)
        let search = || {
            let found = self.solids.touching(&start, g.pool());
            let islands = Islands::of(&found, &self.solids.pins, start.len());
            (found, islands)
        };
        let ((found, islands), mut bodies) = beside(g.pool(), search, || self.bodies(g, s, &start, dt));
        self.paths.last = Some((islands.len(), islands.sizes().max().unwrap_or(0)));
        let solved: Vec<Solved> = match g.pool() {
            Some(pool) if !shares(&islands, pool.current_num_threads()) => {
                self.paths.colours += 1;
                let whole = Whole::of(bodies.len(), found.len(), self.pins());
                vec![pool.install(|| self.solve(whole.island(&found), &bodies, &start, Some(pool)))]
            }
            pool => {
                match pool {
                    Some(_) => self.paths.islands += 1,
                    None => self.paths.alone += 1,
                }
                spread::share(pool, islands.len(), 1, |k| self.solve(islands.get(k, &found), &bodies, &start, None))
            }
        };
        // a body in no contact makes its inertial move: exact in one Newton step, not swept
        for b in &mut bodies {
            b.moved = b.target;
        }
        for (i, m) in solved.iter().flat_map(|s| &s.moves) {
            bodies[*i].moved = *m;
        }
        let residual = solved.iter().fold(0.0, |r: f64, s| r.max(s.residual));
        self.paths.spread += solved.iter().map(|s| s.spread).sum::<u64>();
        self.iterations.record(self.sweeps, residual);
        let turn = |spin: &mut [f64; 7], b: &Body, moments: &V| {
            let turn: V = b.moved.fixed_rows::<3>(3).into_owned();
            let before = UnitQuaternion::from_quaternion(Quaternion::new(spin[0], spin[1], spin[2], spin[3]));
            let after = UnitQuaternion::new_normalize((UnitQuaternion::from_scaled_axis(turn) * before).into_inner());
            let pi = (after.to_rotation_matrix().into_inner().transpose() * (turn / dt)).component_mul(moments);
            let q = after.quaternion();
            *spin = [q.w, q.i, q.j, q.k, pi.x, pi.y, pi.z];
        };
        let place = || {
            for ((b, p), (x, v)) in bodies.iter().zip(&start).zip(s.x.iter_mut().zip(s.v.iter_mut())) {
                let shift = b.moved.fixed_rows::<3>(0).into_owned();
                *x = (p.centre + shift).into();
                *v = (shift / dt).into();
            }
            let rigid = bodies.iter().enumerate().filter(|(i, _)| g.is_rigid(*i)).map(|p| p.1);
            s.spin.iter_mut().zip(rigid).zip(g.moments()).for_each(|((spin, b), m)| turn(spin, b, m));
        };
        let warm = &mut self.warm;
        let file = || {
            warm.clear();
            for (key, kept) in solved.iter().flat_map(|s| &s.kept) {
                match *key {
                    Key::Pin(j) => warm.keep_pin(j, *kept),
                    Key::Pair(a, b) => warm.keep(a, b, *kept),
                }
            }
        };
        beside(g.pool(), place, file);
        self.at.potential = g.forces(s, &mut self.at.f)?;
        Ok(())
    }

    /// Its contact search spreads over the pool at any size.
    fn spreads(&self, g: &LagrangianGraph) -> bool {
        g.pool().is_some()
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    /// The forces and each contact's λ and k, pairs in order.
    fn carried(&self) -> Result<Carried, String> {
        let warm = self.warm.pairs();
        let stiffness = warm.iter().map(|(_, w)| w.iter().map(|c| c.2).collect()).collect();
        let warm =
            warm.into_iter().map(|(pair, w)| (pair, w.iter().map(|(p, l, _)| ((*p).into(), *l)).collect())).collect();
        Ok(Carried { warm, stiffness, ..Carried::forces(&self.at) })
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
        let pairs: warm::Pairs = c
            .warm
            .iter()
            .zip(&c.stiffness)
            .map(|((pair, w), k)| (*pair, w.iter().zip(k).map(|((p, l), k)| (V::from(*p), *l, *k)).collect()))
            .collect();
        self.warm = Warm::from_pairs(&pairs);
    }

    fn rotates(&self) -> bool {
        true
    }

    fn iterations(&self) -> Option<&Iterations> {
        Some(&self.iterations)
    }

    fn plan(&self) -> Option<String> {
        let p = &self.paths;
        let ways = [
            (p.islands, "island by island, a task each on the pool"),
            (p.colours, "the whole, colour by colour (too few islands, or one too large, to share out)"),
            (p.alone, "island by island on one thread"),
        ];
        let said: Vec<String> =
            ways.iter().filter(|w| w.0 > 0).map(|(n, how)| format!("{how} in {n} step(s)")).collect();
        let last = p
            .last
            .map_or(String::new(), |(n, most)| format!("; the last step {n} island(s), the largest of {most} bodies"));
        let spread = match p.colours {
            0 => String::new(),
            _ => format!(
                "; {} of its colour passes spread over the pool (those of {SPREAD_FROM} bodies or more)",
                p.spread
            ),
        };
        (!said.is_empty()).then(|| format!("AVBD swept {}{spread}{last}", said.join(", ")))
    }
}

/// An island swept: its bodies' moves (by their index in the state), what its contacts leave
/// for the next step's warm start (their pairs numbered as in the state), and what its last
/// sweep left.
struct Solved {
    moves: Vec<(usize, Move)>,
    kept: Vec<(Key, Kept)>,
    residual: f64,
    /// Its colour passes that spread over the pool.
    spread: u64,
}

/// `first()` and `second()`, on a pool at once: `first` on this thread (its passes clocked
/// here, its serial work still counted serial), `second` for another thread to take if one is
/// free, or after `first` on this one. Nothing is shared between them: the same values either
/// way. (The stack's serial parts between passes, each 30–120 µs a step on this thread, were
/// about 9% of its time at two threads.)
fn beside<A: Send, B: Send>(
    pool: Option<&ThreadPool>,
    first: impl FnOnce() -> A + Send,
    second: impl FnOnce() -> B + Send,
) -> (A, B) {
    match pool {
        Some(pool) => pool.join(first, second),
        None => (first(), second()),
    }
}

/// Whether `threads` threads have islands enough to take one at a time: at least one each, and
/// the largest no more than a thread's share of the bodies in islands.
fn shares(islands: &Islands, threads: usize) -> bool {
    let largest = islands.sizes().max().unwrap_or(0);
    let held: usize = islands.sizes().sum();
    islands.len() >= threads && largest * threads <= held
}

impl Avbd {
    /// One island's step: its contacts' rows at the step's start (warm-started from last step's
    /// by their pair in the state), its colours, its sweeps (each colour large enough to pay
    /// spread over `pool`). An island's levels and greedy colours are decided within it, so its
    /// bodies descend in the order they take in a sweep over all: the same bits whether the
    /// bodies are swept island by island or all at once.
    fn solve(&self, island: Island, all: &[Body], start: &[Pose], pool: Option<&ThreadPool>) -> Solved {
        let margin = self.solids.margin.max(f64::MIN_POSITIVE);
        let poses: Vec<Pose> = island.bodies.iter().map(|&i| start[i]).collect();
        let mut bodies: Vec<Body> = island.bodies.iter().map(|&i| all[i]).collect();
        let mut contacts: Vec<Contact> = island.touches().map(|t| Contact::new(&t, &poses, &bodies, margin)).collect();
        for (j, p) in island.pins {
            let mut c = Contact::pin(*j, p, &poses, &bodies, margin);
            if let Some((_, lambda, stiffness)) = self.warm.pin(*j) {
                c.warm_from(lambda, stiffness);
            }
            contacts.push(c);
        }
        let rows = Rows::of(&contacts, bodies.len());
        for c in contacts.iter_mut().filter(|c| matches!(c.bound, Bound::Coulomb(_))) {
            if c.a.is_some_and(|a| !rows.grounded[a] && !rows.grounded[c.b]) {
                c.soften();
            }
            self.start_warm(c, c.a.map(|a| island.bodies[a]), island.bodies[c.b]);
        }
        for (b, of) in bodies.iter_mut().zip(&rows.of) {
            if of.is_empty() {
                b.moved = b.target;
            }
        }
        let (residual, spread) = sweep(&mut bodies, &mut contacts, &rows, self.sweeps, pool);
        // computed here, on the island's thread, so the step's serial part only files them
        let kept = contacts.iter().map(|c| keep(c, &bodies, &poses, island.bodies)).collect();
        let moves = island.bodies.iter().zip(&bodies).map(|(&i, b)| (i, b.moved)).collect();
        Solved { moves, kept, residual, spread }
    }

    /// The pins with their indices, for a sweep over all bodies at once.
    fn pins(&self) -> Vec<(usize, Pin)> {
        self.solids.pins.iter().copied().enumerate().collect()
    }

    /// Each body's inertial move, y − x₀ = dt v₀ + dt² F/m (a rigid body's turn dt ω₀), and
    /// where the sweeps start it: dt v₀, dt ω₀ (a resting body's move is nothing).
    fn bodies(&self, g: &LagrangianGraph, s: &State, start: &[Pose], dt: f64) -> Vec<Body> {
        let scale = 1.0 / (dt * dt);
        let mut spins = s.spin.iter().zip(g.moments());
        start
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let drift = V::from(s.v[i]) * dt;
                let fall = V::from(self.at.f[i]) * (dt * dt * g.inverse_masses[i]);
                let (turn, inertia) = match g.is_rigid(i).then(|| spins.next()).flatten() {
                    Some((spin, moments)) => {
                        let omega = p.rotation * crate::rigid::omega(spin, *moments);
                        let inertia = p.rotation * Matrix3::from_diagonal(moments) * p.rotation.transpose() * scale;
                        (omega * dt, Some(inertia))
                    }
                    None => (V::zeros(), None),
                };
                let moved = Move::new(drift.x, drift.y, drift.z, turn.x, turn.y, turn.z);
                let target = moved + Move::new(fall.x, fall.y, fall.z, 0.0, 0.0, 0.0);
                Body { moved, target, mass: g.masses[i] * scale, inertia }
            })
            .collect()
    }

    /// A new contact starts from last step's contact of the same pair (a, b in the state's
    /// numbering, a none: the floor) nearest its point (within twice the margin), its λ and k
    /// carried as `warm_from` says.
    fn start_warm(&self, c: &mut Contact, a: Option<usize>, b: usize) {
        let reach = 4.0 * self.solids.margin * self.solids.margin;
        let near =
            self.warm.between(a, b).map(|w| ((w.0 - c.point).norm_squared(), w)).min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, (_, lambda, stiffness))) = near.filter(|n| n.0 <= reach) {
            c.warm_from(lambda, stiffness);
        }
    }
}

/// What a contact leaves for the next step's warm start, keyed by pin, or by its pair in the
/// state's numbering (`index`: the island's bodies): its λ and k, at its point carried by b's
/// move (where the next step's search will find it).
fn keep(c: &Contact, bodies: &[Body], start: &[Pose], index: &[usize]) -> (Key, Kept) {
    if let Bound::Pin(j) = c.bound {
        return (Key::Pin(j), (c.point, c.lambda, c.stiffness));
    }
    let m = &bodies[c.b].moved;
    let turn: V = m.fixed_rows::<3>(3).into_owned();
    let place = c.point + m.fixed_rows::<3>(0) + turn.cross(&(c.point - start[c.b].centre));
    (Key::Pair(c.a.map(|a| index[a]), index[c.b]), (place, c.lambda, c.stiffness))
}

/// Bodies in a colour (or contacts in an island) from which a sweep's pass over them spreads
/// over the pool. A body's descent takes ~0.4 µs (the stack's sweeps, one thread), so a smaller
/// colour is under ~25 µs of work, where a pass's hand-over costs a few (a pyramid's colours
/// are a few bricks each). (A large colour shared by a counter, `spread::share`, was no faster
/// than rayon's split: docs/bench.)
const SPREAD_FROM: usize = 64;

/// `sweeps` rounds of block descent, colour by colour, each followed by the dual step, each
/// pass large enough spread over `pool`; returns the overlap left beyond the target after the
/// last, and the colour passes that spread.
fn sweep(
    bodies: &mut [Body],
    contacts: &mut [Contact],
    rows: &Rows,
    sweeps: u32,
    pool: Option<&ThreadPool>,
) -> (f64, u64) {
    let (mut residual, mut spread) = (0.0, 0);
    for _ in 0..sweeps {
        for colour in &rows.colours {
            // a colour's bodies share no row, so each one's move is the same taken in place
            // or from the moves as the colour began
            match pool.filter(|_| colour.len() >= SPREAD_FROM) {
                Some(pool) => {
                    spread += 1;
                    let frozen = &*bodies;
                    let moved: Vec<Move> = spread::pass(|| {
                        pool.install(|| {
                            colour.par_iter().map(|&i| descend(&frozen[i], frozen, contacts, &rows.of[i])).collect()
                        })
                    });
                    for (&i, m) in colour.iter().zip(moved) {
                        bodies[i].moved = m;
                    }
                }
                // not a pass of its own: on a pool, a colour too small to spread at any thread
                // count (serial); without one, part of an island's task, its pass already
                None => {
                    for &i in colour {
                        bodies[i].moved = descend(&bodies[i], bodies, contacts, &rows.of[i]);
                    }
                }
            }
        }
        // the largest overlap is the same taken in any order
        let frozen = &*bodies;
        residual = match pool.filter(|_| contacts.len() >= SPREAD_FROM) {
            Some(pool) => spread::pass(|| {
                pool.install(|| contacts.par_iter_mut().map(|c| c.update(frozen)).reduce(|| 0.0, f64::max))
            }),
            None => contacts.iter_mut().map(|c| c.update(frozen)).fold(0.0, f64::max),
        };
    }
    (residual, spread)
}

/// A body's Newton step on its share of the energy, the others' moves held: the inertial term
/// ½‖Δ − Δ̃‖²_M/dt² plus each of its contacts' rows, F J into the force and k J Jᵀ into the
/// Hessian (a point mass keeps its turn at nothing).
fn descend(b: &Body, bodies: &[Body], contacts: &[Contact], rows: &[(usize, bool)]) -> Move {
    let mut block = Block::inertial(b.mass, b.inertia.as_ref(), &(b.target - b.moved));
    // row n's Jacobian on b is (d_n, r × d_n), on a its negative: the sign goes into the force
    // only, k J Jᵀ being the same either way
    for &(j, as_b) in rows {
        let c = &contacts[j];
        let (f, k) = c.forces(&c.errors(bodies));
        let sign = if as_b { 1.0 } else { -1.0 };
        block.add_rows(&c.dirs, &c.arms[as_b as usize], k, f.map(|f| sign * f));
    }
    match block.solve() {
        Some(step) => b.moved + step,
        None => b.moved,
    }
}

mod block;
mod colours;
mod contact;
mod islands;
#[cfg(test)]
mod tests;
mod warm;
