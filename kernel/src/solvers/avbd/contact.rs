//! A contact, or a pin of a joint, as AVBD holds it: three rows (a contact's normal and two
//! tangents, a pin's x, y, z), linear in the two bodies' moves, each with its target, its λ and
//! its stiffness k; the forces they put on a body in its descent, and the dual step after a
//! sweep. The constants are the augmented Lagrangian's, each with what the stack and the hinged
//! chain measured for it.

use super::{Body, Move, V};
use crate::contact::{Pose, Touch};
use lagra_checker::model::Pin;

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

/// One contact, or one pin of a joint: its bodies (a: none is the floor, or the world), its rows'
/// directions and each body's arm to the point (row k's Jacobian on b is (d_k, r_b × d_k), on a
/// the negative of a's), each row's target, what bounds the rows, each row's λ and k, and where it
/// was found (for the next step's warm start).
pub(super) struct Contact {
    pub(super) a: Option<usize>,
    pub(super) b: usize,
    /// A contact's normal and two tangents; a pin's x, y, z.
    pub(super) dirs: [V; 3],
    /// From a's centre and from b's to the point, as each was found; nothing for a body that does
    /// not turn (a point mass, the floor, the world).
    pub(super) arms: [V; 2],
    /// What each row's error is measured from: the normal's stabilised overlap (the tangents'
    /// nothing), or a pin's gap along x, y, z.
    offset: [f64; 3],
    pub(super) bound: Bound,
    pub(super) lambda: [f64; 3],
    pub(super) stiffness: [f64; 3],
    /// The starting stiffness, the ramp and the cap (in this contact's m/dt²).
    start: f64,
    ramp: f64,
    most: f64,
    pub(super) point: V,
}

/// What bounds a row's force: a contact's normal pushes only and its friction stays inside
/// Coulomb's disc; a pin's three rows are equalities (the pin's index, for its warm start).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Bound {
    Coulomb(f64),
    Pin(usize),
}

impl Contact {
    /// A contact found at poses `start`: its rows' Jacobians there.
    pub(super) fn new(t: &Touch, start: &[Pose], bodies: &[Body], margin: f64) -> Contact {
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
    pub(super) fn pin(j: usize, p: &Pin, start: &[Pose], bodies: &[Body], margin: f64) -> Contact {
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
    pub(super) fn soften(&mut self) {
        self.start *= FREE_STIFFNESS_START / STIFFNESS_START;
        self.stiffness = [self.start; 3];
    }

    /// Starts from last step's λ and k: a contact's λ scaled by its carry, a pin's decayed by
    /// αγ; k decayed by γ (within its start and cap).
    pub(super) fn warm_from(&mut self, lambda: &[f64; 3], stiffness: &[f64; 3]) {
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
    pub(super) fn errors(&self, bodies: &[Body]) -> [f64; 3] {
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
    pub(super) fn forces(&self, c: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
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
    pub(super) fn update(&mut self, bodies: &[Body]) -> f64 {
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

/// How far a point at `arm` from a body's centre moves as the body moves by m: Δx + Δθ × r.
#[inline]
fn point_move(m: &Move, r: &V) -> [f64; 3] {
    [
        m[0] + m[4].mul_add(r.z, -m[5] * r.y),
        m[1] + m[5].mul_add(r.x, -m[3] * r.z),
        m[2] + m[3].mul_add(r.y, -m[4] * r.x),
    ]
}
