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
use crate::contact::{Pose, Solids, Touch};
use crate::graph::LagrangianGraph;
use crate::state::State;
use block::Block;
use colours::Rows;
use islands::Island;
use lagra_checker::model::Pin;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3, Vector6};
use rayon::prelude::*;
use std::collections::HashMap;

type V = Vector3<f64>;
/// A body's move over the step: displacement, then rotation vector.
type Move = Vector6<f64>;

/// α: the share of a step's starting overlap left for later steps.
const STABILISE: f64 = 0.95;
/// α_pin: the share of a joint's starting gap left for later steps. A gap closed in one step
/// becomes a velocity (v = Δx/dt): closing all of it pumped energy into
/// `scenes/hinged_chain.lagra` (|ΔH|/|H₀| 0.2 within 0.12 s); at 40 sweeps 0.8 left the energy
/// within 6.2e-4 over 2 s and the widest gap at 2.2e-4, 0.95 at 5.9e-4 and 8.1e-4.
const PIN_STABILISE: f64 = 0.8;
/// γ: how much of last step's k a persisting contact starts from, and of a pin's λ (with α).
/// The authors use 0.99; on `scenes/bench/stack_1000.lagra` 0.9 left its fastest point at
/// 4.5e-3 / 4.7e-3 (dt 0.005 / 0.01) against 4.8e-3 / 9.9e-3 with 0.99: a stiffness that stays
/// high makes the sweeps carry load down a ten-block tower more slowly.
const DECAY: f64 = 0.9;
/// The share of last step's λ a persisting contact starts from. The authors carry αγ (0.855
/// here); on the stack (with `STIFFNESS_START` at 10, bottom-up sweeps, 20 sweeps a step) the
/// fastest point at 3.5–4 s was 1.8e-4 / 1.8e-4 / 4.6e-4 at dt 0.005 / 0.01 / 0.02 with 0.5,
/// against 2.1e-2 and 8.8e-2 (dt 0.005, 0.02: `resting` FAILs) with 0.95: a λ carried whole
/// keeps the push that stopped a block last step, and the sweeps do not undo it in time. 0.3
/// and 0.7 rested less quietly at some dt (up to 1.9e-3 and 1.8e-3).
const CARRY: f64 = 0.5;
/// The stiffness a new contact row starts at (and never falls below), and its cap, in units of
/// its lighter body's m/dt². The ramp hardly moves it (the sweeps leave overlaps of ~1e-5
/// against a margin of 1e-2), so the start is the stiffness: at 1, the stack's dual steps
/// (λ += kC) rebuilt a tower's load so slowly that it rested at 2.1e-3 (dt 0.005) and FAILed
/// `resting` at dt 0.01 and 0.02 (9.5e-3, 1.6e-2); 6–25 rested (6.8e-4 to 2.9e-3 with the old
/// carry); 40 and 100 overshot (λ rings: 2.5e-2 and 5.3e-2, FAIL).
const STIFFNESS_START: f64 = 10.0;
const STIFFNESS_MOST: f64 = 1e3;
/// The starting stiffness of a contact between two bodies that touch nothing fixed (bodies
/// colliding in the air). Its bodies' moves are taken one after the other, so the first takes
/// most of a stiff contact's push and the pair's momentum is not kept: at 10, the box, brick and
/// ball colliding in `tests/end_to_end/contact.rs` ended 0.30 off in momentum, at 1 (as before
/// the stack's measurements) 4.8e-3. The stack needs 10 (at 1 or 3 between its blocks it rested
/// at 1.2e-3 / 3.5e-3 or 5.0e-4 / 1.8e-3 at dt 0.005 / 0.01), and it stands on the floor.
const FREE_STIFFNESS_START: f64 = 1.0;
/// A pin's starting stiffness (its λ is carried by αγ): with a contact's start and carry (10,
/// 0.5) `scenes/hinged_chain.lagra` lost 5.5e-3 of its energy in 0.2 s (its claim is 5e-3);
/// with 1 and αγ it keeps within 6.1e-4 over 2 s.
const PIN_STIFFNESS_START: f64 = 1.0;
/// β: the ramp, in units of m/dt² per contact margin of error.
const RAMP: f64 = 1.0;

pub struct Avbd {
    pub at: Evaluated,
    pub solids: Solids,
    /// Sweeps over the bodies per step.
    pub sweeps: u32,
    /// Last step's contacts by pair: place, λ and k of the three rows.
    warm: HashMap<(usize, usize), Vec<(V, [f64; 3], [f64; 3])>>,
    iterations: Iterations,
    paths: Paths,
}

/// How the steps were swept, for `--explain`: island by island on the pool, the whole with
/// each colour spread over the pool, or the whole on one thread; and the last step's islands
/// (where there was a pool to share them out over).
#[derive(Default)]
struct Paths {
    islands: u64,
    colours: u64,
    alone: u64,
    last: Option<(usize, usize)>,
}

impl Avbd {
    pub fn new(at: Evaluated, solids: Solids, sweeps: u32) -> Avbd {
        let iterations = Iterations {
            what: "AVBD sweeps (residual: the largest overlap beyond the stabilised target, or joint gap)",
            ..Default::default()
        };
        Avbd { at, solids, sweeps, warm: HashMap::new(), iterations, paths: Paths::default() }
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

/// One contact, or one pin of a joint: its bodies (a: none is the floor, or the world), its rows'
/// directions and each body's arm to the point (row k's Jacobian on b is (d_k, r_b × d_k), on a
/// the negative of a's), each row's target, what bounds the rows, each row's λ and k, and where it
/// was found (for the next step's warm start).
struct Contact {
    a: Option<usize>,
    b: usize,
    /// A contact's normal and two tangents; a pin's x, y, z.
    dirs: [V; 3],
    /// From a's centre and from b's to the point, as each was found; nothing for a body that does
    /// not turn (a point mass, the floor, the world).
    arms: [V; 2],
    /// What each row's error is measured from: the normal's stabilised overlap (the tangents'
    /// nothing), or a pin's gap along x, y, z.
    offset: [f64; 3],
    bound: Bound,
    lambda: [f64; 3],
    stiffness: [f64; 3],
    /// The starting stiffness, the ramp and the cap (in this contact's m/dt²).
    start: f64,
    ramp: f64,
    most: f64,
    point: V,
}

/// What bounds a row's force: a contact's normal pushes only and its friction stays inside
/// Coulomb's disc; a pin's three rows are equalities (the pin's index, for its warm start).
#[derive(Clone, Copy, PartialEq)]
enum Bound {
    Coulomb(f64),
    Pin(usize),
}

/// The warm-start key of pin j: (j, none), which no contact's (a, b) can be (b is a body).
fn pin_key(j: usize) -> (usize, usize) {
    (j, usize::MAX)
}

impl Contact {
    /// A contact found at poses `start`: its rows' Jacobians there.
    fn new(t: &Touch, start: &[Pose], bodies: &[Body], margin: f64) -> Contact {
        let n = t.normal;
        let t1 = if n.x.abs() < 0.9 { n.cross(&V::x()) } else { n.cross(&V::y()) }.normalize();
        let arm = |i: Option<usize>| match i.filter(|&i| bodies[i].inertia.is_some()) {
            Some(i) => t.point - start[i].centre,
            None => V::zeros(),
        };
        Contact {
            dirs: [n, t1, n.cross(&t1)],
            arms: [arm(t.a), arm(Some(t.b))],
            offset: [(1.0 - STABILISE) * t.depth.max(0.0) + t.depth.min(0.0), 0.0, 0.0],
            ..Contact::rows(t.a, t.b, Bound::Coulomb(t.friction), t.point, bodies, margin)
        }
    }

    /// Pin j at poses `start`: rows along x, y, z of p_b − p_a, each point moved as its body
    /// moves (Jacobians ±(d, r × d), r from the body's centre to its point); a share
    /// 1 − α_pin of the gap found at the start is closed in a step.
    fn pin(j: usize, p: &Pin, start: &[Pose], bodies: &[Body], margin: f64) -> Contact {
        let seen = |i: usize, on: &[f64; 3]| start[i].rotation * V::from(*on);
        let (arm_b, arm_a) = (seen(p.b, &p.on_b), p.a.map(|a| seen(a, &p.on_a)));
        let at_b = start[p.b].centre + arm_b;
        let at_a = p.a.zip(arm_a).map_or(V::from(p.on_a), |(a, arm)| start[a].centre + arm);
        let gap = at_b - at_a;
        Contact {
            dirs: [V::x(), V::y(), V::z()],
            arms: [arm_a.unwrap_or_default(), arm_b],
            offset: (-gap * (1.0 - PIN_STABILISE)).into(),
            ..Contact::rows(p.a, p.b, Bound::Pin(j), at_b, bodies, margin)
        }
    }

    /// Rows between a and b with no Jacobians yet, their λ at nothing and k at its start (in
    /// units of the lighter body's m/dt²).
    fn rows(a: Option<usize>, b: usize, bound: Bound, point: V, bodies: &[Body], margin: f64) -> Contact {
        let unit = a.map_or(bodies[b].mass, |a| bodies[a].mass.min(bodies[b].mass));
        let start = match bound {
            Bound::Coulomb(_) => STIFFNESS_START,
            Bound::Pin(_) => PIN_STIFFNESS_START,
        };
        Contact {
            a,
            b,
            dirs: [V::zeros(); 3],
            arms: [V::zeros(); 2],
            offset: [0.0; 3],
            bound,
            lambda: [0.0; 3],
            stiffness: [start * unit; 3],
            start: start * unit,
            ramp: RAMP * unit / margin,
            most: STIFFNESS_MOST * unit,
            point,
        }
    }

    /// A contact between bodies that touch nothing fixed: its stiffness starts (and stays at
    /// least) at `FREE_STIFFNESS_START`.
    fn soften(&mut self) {
        self.start *= FREE_STIFFNESS_START / STIFFNESS_START;
        self.stiffness = [self.start; 3];
    }

    /// Starts from last step's λ and k: a contact's λ scaled by its carry, a pin's decayed by
    /// αγ; k decayed by γ (within its start and cap).
    fn warm_from(&mut self, lambda: &[f64; 3], stiffness: &[f64; 3]) {
        let carry = match self.bound {
            Bound::Coulomb(_) => CARRY,
            Bound::Pin(_) => STABILISE * DECAY,
        };
        self.lambda = lambda.map(|l| l * carry);
        self.stiffness = stiffness.map(|k| (k * DECAY).clamp(self.start, self.most));
    }

    /// The three rows' errors at these moves: each direction's share of how far b's point moved
    /// from a's (J·Δ = d·(Δx + Δθ × r): the point's move, to first order). Written out in
    /// numbers: it is the sweeps' innermost work (a contact's errors are taken three times a
    /// sweep), and nalgebra's 3-vectors spent most of it shuffling pairs of lanes.
    #[inline(always)]
    fn errors(&self, bodies: &[Body]) -> [f64; 3] {
        let mut apart = point_move(&bodies[self.b].moved, &self.arms[1]);
        if let Some(a) = self.a {
            let back = point_move(&bodies[a].moved, &self.arms[0]);
            apart = [0, 1, 2].map(|i| apart[i] - back[i]);
        }
        [0, 1, 2].map(|k| {
            let d = &self.dirs[k];
            d.x.mul_add(apart[0], d.y.mul_add(apart[1], d.z * apart[2])) - self.offset[k]
        })
    }

    /// The rows' forces at errors `c` (k C + λ: the normal pushes only, friction stays inside
    /// μ|Fₙ|), and the stiffness each puts in the Hessian: a sliding row's scaled by the share
    /// of its force the disc lets through; the normal's whole k even where it lets go, as the
    /// authors do, so that a body does not leap from a contact it is leaving into it and back
    /// (without it one box on the floor swings between free fall and a lift, step after step).
    #[inline(always)]
    fn forces(&self, c: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
        let friction = match self.bound {
            Bound::Coulomb(mu) => mu,
            Bound::Pin(_) => return ([0, 1, 2].map(|k| self.stiffness[k] * c[k] + self.lambda[k]), self.stiffness),
        };
        let normal = (self.stiffness[0] * c[0] + self.lambda[0]).min(0.0);
        let t = [1, 2].map(|k| self.stiffness[k] * c[k] + self.lambda[k]);
        let (size, most) = (t[0] * t[0] + t[1] * t[1], friction * normal.abs());
        // squares compared, so that a sticking row (most of a resting stack's) takes no root
        let share = if size > most * most { most / size.sqrt() } else { 1.0 };
        let k = self.stiffness;
        ([normal, t[0] * share, t[1] * share], [k[0], k[1] * share, k[2] * share])
    }

    /// The dual step: λ takes the force; where no bound binds, k ramps by β|C|. Returns the
    /// overlap left beyond the target, or a pin's largest gap.
    fn update(&mut self, bodies: &[Body]) -> f64 {
        let c = self.errors(bodies);
        let (f, _) = self.forces(&c);
        let free = match self.bound {
            Bound::Coulomb(mu) => {
                let most = mu * f[0];
                let sticking = f[1] * f[1] + f[2] * f[2] < most * most;
                [f[0] < 0.0, sticking, sticking]
            }
            Bound::Pin(_) => [true; 3],
        };
        for (k, free) in free.into_iter().enumerate() {
            self.lambda[k] = f[k];
            if free {
                self.stiffness[k] = (self.stiffness[k] + self.ramp * c[k].abs()).min(self.most);
            }
        }
        match self.bound {
            Bound::Coulomb(_) => (-c[0]).max(0.0),
            Bound::Pin(_) => c.iter().fold(0.0, |m, c| m.max(c.abs())),
        }
    }
}

impl Solver for Avbd {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let start = self.solids.poses(&s.x, &s.spin);
        let mut bodies = self.bodies(g, s, &start, dt);
        let found = self.solids.touching(&start, g.pool());
        // on a pool, the islands a task each where they share out over its threads (nothing to
        // wait for between colours); else the whole at once, each colour spread over the pool
        // (on one thread the whole too: taking the islands apart cost 10% of the stack's step)
        let islands = g.pool().map(|pool| (pool, Island::all(&found, &self.solids.pins, bodies.len())));
        if let Some((_, islands)) = &islands {
            self.paths.last = Some((islands.len(), islands.iter().map(|i| i.bodies.len()).max().unwrap_or(0)));
        }
        let solved: Vec<Solved> = match islands {
            Some((pool, islands)) if shares(&islands, pool.current_num_threads()) => {
                self.paths.islands += 1;
                pool.install(|| islands.par_iter().map(|i| self.solve(i, &bodies, &start, false)).collect())
            }
            _ => {
                let whole = Island { bodies: (0..bodies.len()).collect(), touches: found, pins: self.pins() };
                match g.pool() {
                    Some(pool) => {
                        self.paths.colours += 1;
                        vec![pool.install(|| self.solve(&whole, &bodies, &start, true))]
                    }
                    None => {
                        self.paths.alone += 1;
                        vec![self.solve(&whole, &bodies, &start, false)]
                    }
                }
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
        self.iterations.record(self.sweeps, residual);
        for ((b, p), (x, v)) in bodies.iter().zip(&start).zip(s.x.iter_mut().zip(s.v.iter_mut())) {
            let shift = b.moved.fixed_rows::<3>(0).into_owned();
            *x = (p.centre + shift).into();
            *v = (shift / dt).into();
        }
        let rigid = bodies.iter().enumerate().filter(|(i, _)| g.is_rigid(*i)).map(|p| p.1);
        for ((spin, b), moments) in s.spin.iter_mut().zip(rigid).zip(g.moments()) {
            let turn: V = b.moved.fixed_rows::<3>(3).into_owned();
            let before = UnitQuaternion::from_quaternion(Quaternion::new(spin[0], spin[1], spin[2], spin[3]));
            let after = UnitQuaternion::new_normalize((UnitQuaternion::from_scaled_axis(turn) * before).into_inner());
            let pi = (after.to_rotation_matrix().into_inner().transpose() * (turn / dt)).component_mul(moments);
            let q = after.quaternion();
            *spin = [q.w, q.i, q.j, q.k, pi.x, pi.y, pi.z];
        }
        self.at.potential = g.forces(s, &mut self.at.f)?;
        self.keep_warm(solved.iter().flat_map(|s| &s.contacts), &bodies, &start);
        Ok(())
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    /// The forces and each contact's λ and k, pairs in order (the map's own order is arbitrary).
    fn carried(&self) -> Result<Carried, String> {
        let mut warm: Vec<_> = self.warm.iter().collect();
        warm.sort_by_key(|w| *w.0);
        let places = |w: &[(V, [f64; 3], [f64; 3])]| w.iter().map(|(p, l, _)| ((*p).into(), *l)).collect();
        let stiffness = warm.iter().map(|(_, w)| w.iter().map(|c| c.2).collect()).collect();
        let warm = warm.iter().map(|(pair, w)| (**pair, places(w))).collect();
        Ok(Carried { warm, stiffness, ..Carried::forces(&self.at) })
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
        self.warm = c
            .warm
            .iter()
            .zip(&c.stiffness)
            .map(|((pair, w), k)| (*pair, w.iter().zip(k).map(|((p, l), k)| (V::from(*p), *l, *k)).collect()))
            .collect();
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
            (
                p.colours,
                "the whole, each colour spread over the pool (too few islands, or one too large, to share out)",
            ),
            (p.alone, "the whole on one thread"),
        ];
        let said: Vec<String> =
            ways.iter().filter(|w| w.0 > 0).map(|(n, how)| format!("{how} in {n} step(s)")).collect();
        let last = p
            .last
            .map_or(String::new(), |(n, most)| format!("; the last step {n} island(s), the largest of {most} bodies"));
        (!said.is_empty()).then(|| format!("AVBD swept {}{last}", said.join(", ")))
    }
}

/// An island swept: its bodies' moves (by their index in the state), its contacts (their bodies
/// numbered as in the state) with the λ and k they ended at, and what its last sweep left.
struct Solved {
    moves: Vec<(usize, Move)>,
    contacts: Vec<Contact>,
    residual: f64,
}

/// Whether `threads` threads have islands enough to take one at a time: at least one each, and
/// the largest no more than a thread's share of the bodies in islands.
fn shares(islands: &[Island], threads: usize) -> bool {
    let largest = islands.iter().map(|i| i.bodies.len()).max().unwrap_or(0);
    let held: usize = islands.iter().map(|i| i.bodies.len()).sum();
    islands.len() >= threads && largest * threads <= held
}

impl Avbd {
    /// One island's step: its contacts' rows at the step's start (warm-started from last step's
    /// by their pair in the state), its colours, its sweeps (each colour spread over the current
    /// pool if `parallel`). An island's levels and greedy colours are decided within it, so its
    /// bodies descend in the order they take in a sweep over all: the same bits whether the
    /// bodies are swept island by island or all at once.
    fn solve(&self, island: &Island, all: &[Body], start: &[Pose], parallel: bool) -> Solved {
        let margin = self.solids.margin.max(f64::MIN_POSITIVE);
        let poses: Vec<Pose> = island.bodies.iter().map(|&i| start[i]).collect();
        let mut bodies: Vec<Body> = island.bodies.iter().map(|&i| all[i]).collect();
        let mut contacts: Vec<Contact> =
            island.touches.iter().map(|t| Contact::new(t, &poses, &bodies, margin)).collect();
        for (j, p) in &island.pins {
            let mut c = Contact::pin(*j, p, &poses, &bodies, margin);
            if let Some((_, lambda, stiffness)) = self.warm.get(&pin_key(*j)).and_then(|w| w.first()) {
                c.warm_from(lambda, stiffness);
            }
            contacts.push(c);
        }
        let rows = Rows::of(&contacts, bodies.len());
        for c in contacts.iter_mut().filter(|c| matches!(c.bound, Bound::Coulomb(_))) {
            if c.a.is_some_and(|a| !rows.grounded[a] && !rows.grounded[c.b]) {
                c.soften();
            }
            self.start_warm(c, (c.a.map_or(usize::MAX, |a| island.bodies[a]), island.bodies[c.b]));
        }
        for (b, of) in bodies.iter_mut().zip(&rows.of) {
            if of.is_empty() {
                b.moved = b.target;
            }
        }
        let residual = sweep(&mut bodies, &mut contacts, &rows, self.sweeps, parallel);
        for c in &mut contacts {
            (c.a, c.b) = (c.a.map(|a| island.bodies[a]), island.bodies[c.b]);
        }
        let moves = island.bodies.iter().zip(&bodies).map(|(&i, b)| (i, b.moved)).collect();
        Solved { moves, contacts, residual }
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
    fn start_warm(&self, c: &mut Contact, pair: (usize, usize)) {
        let reach = 4.0 * self.solids.margin * self.solids.margin;
        let Some(old) = self.warm.get(&pair) else { return };
        let near = old.iter().map(|w| ((w.0 - c.point).norm_squared(), w)).min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, (_, lambda, stiffness))) = near.filter(|n| n.0 <= reach) {
            c.warm_from(lambda, stiffness);
        }
    }

    /// Each contact's λ and k, at its point carried by b's move (where the next step's search
    /// will find it).
    fn keep_warm<'a>(&mut self, contacts: impl Iterator<Item = &'a Contact>, bodies: &[Body], start: &[Pose]) {
        self.warm.clear();
        for c in contacts {
            if let Bound::Pin(j) = c.bound {
                self.warm.insert(pin_key(j), vec![(c.point, c.lambda, c.stiffness)]);
                continue;
            }
            let m = &bodies[c.b].moved;
            let turn: V = m.fixed_rows::<3>(3).into_owned();
            let place = c.point + m.fixed_rows::<3>(0) + turn.cross(&(c.point - start[c.b].centre));
            self.warm.entry((c.a.unwrap_or(usize::MAX), c.b)).or_default().push((place, c.lambda, c.stiffness));
        }
    }
}
/// How far a point at `arm` from a body's centre moves as the body moves by m: Δx + Δθ × r.
#[inline]
fn point_move(m: &Move, r: &V) -> [f64; 3] {
    [
        m[0] + m[4].mul_add(r.z, -m[5] * r.y),
        m[1] + m[5].mul_add(r.x, -m[3] * r.z),
        m[2] + m[3].mul_add(r.y, -m[4] * r.x),
    ]
}

/// `sweeps` rounds of block descent, colour by colour, each followed by the dual step; returns
/// the overlap left beyond the target after the last.
fn sweep(bodies: &mut [Body], contacts: &mut [Contact], rows: &Rows, sweeps: u32, parallel: bool) -> f64 {
    let mut residual = 0.0;
    for _ in 0..sweeps {
        for colour in &rows.colours {
            // a colour's bodies share no row, so each one's move is the same taken in place
            // or from the moves as the colour began
            if parallel {
                let frozen = &*bodies;
                let moved: Vec<Move> =
                    colour.par_iter().map(|&i| descend(&frozen[i], frozen, contacts, &rows.of[i])).collect();
                for (&i, m) in colour.iter().zip(moved) {
                    bodies[i].moved = m;
                }
            } else {
                for &i in colour {
                    bodies[i].moved = descend(&bodies[i], bodies, contacts, &rows.of[i]);
                }
            }
        }
        let frozen = &*bodies;
        residual = match parallel {
            true => contacts.par_iter_mut().map(|c| c.update(frozen)).reduce(|| 0.0, f64::max),
            false => contacts.iter_mut().map(|c| c.update(frozen)).fold(0.0, f64::max),
        };
    }
    residual
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
mod islands;
#[cfg(test)]
mod tests;
