//! Sequential impulses (Catto, GDC 2005–2014; the contact solver of Box2D and Bullet). A step
//! finds the contacts once, then in each of its substeps kicks with the forces, finds the
//! contact impulses by projected Gauss–Seidel on the velocity-level complementarity problem —
//! each contact's normal impulse clamped to push only, its friction to Coulomb's cone μλₙ —
//! warm-started from the substep before (the first from the last step's impulses), rows from
//! the highest contact down, and only then drifts and turns the bodies with the velocities the
//! contacts allow. A contact's depth is followed through the substeps by its anchors on the two
//! bodies; depth beyond a slop is fed back as a velocity (Baumgarte), and a gap closes at most in
//! one substep (speculative contacts), so resting bodies neither sink nor bounce. Restitution
//! is 0.
//!
//! Symplectic Euler in free flight (first order), with each rigid body turned exactly by the
//! free-body splitting (`rigid::free_step`): its spin enters the solve as ω = R π/I and leaves as
//! π = I Rᵀω. It is not AVBD (Chen et al. 2024), the primal block descent the design names:
//! that is the next step; this dual solver is the one users of Box2D, Bullet and PhysX know.

use super::{Carried, Evaluated, Failure, Iterations, Solver};
use crate::contact::{Pose, Solids, Touch};
use crate::graph::LagrangianGraph;
use crate::rigid;
use crate::state::State;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

type V = Vector3<f64>;

/// Depth fed back per step (Baumgarte's β).
const FEEDBACK: f64 = 0.2;
/// Depth left alone, as a share of the contact margin, so resting contacts persist.
const SLOP: f64 = 0.05;

pub struct Impulses {
    pub at: Evaluated,
    pub solids: Solids,
    pub substeps: u32,
    pub sweeps: u32,
    /// Last step's impulses (normal, two tangents) by pair and place, to start from.
    warm: HashMap<(usize, usize), Vec<(V, [f64; 3])>>,
    iterations: Iterations,
}

impl Impulses {
    pub fn new(at: Evaluated, solids: Solids, substeps: u32, sweeps: u32) -> Impulses {
        let iterations = Iterations { what: "contact sweeps (residual: a normal speed)", ..Default::default() };
        Impulses { at, solids, substeps, sweeps, warm: HashMap::new(), iterations }
    }
}

/// A body's share in the solve: 1/m, the world inverse inertia, its velocity and spin rate.
struct Mobile {
    inverse_mass: f64,
    inverse_inertia: Matrix3<f64>,
    v: V,
    omega: V,
}

impl Mobile {
    /// The speed along direction d at a point whose lever arm crossed with d is `arm` (r × d).
    fn speed(&self, d: &V, arm: &V) -> f64 {
        d.dot(&self.v) + arm.dot(&self.omega)
    }
    /// An impulse `amount`·d whose angular part, I⁻¹(r × d), is `turn`.
    fn nudge(&mut self, d: &V, turn: &V, amount: f64) {
        self.v += d * (amount * self.inverse_mass);
        self.omega += turn * amount;
    }
}

/// One contact as found at the step's start: its bodies (the floor is none), its point, normal,
/// depth and friction, and where it holds on each body (in the body's frame). Only `prepare`
/// and the warm start read it; the sweeps read its `Row`.
struct Found {
    touch: Touch,
    anchors: [V; 2],
}

impl Found {
    fn new(touch: Touch, poses: &[Pose]) -> Found {
        let local = |i: Option<usize>| {
            i.map_or(touch.point, |i| poses[i].rotation.transpose() * (touch.point - poses[i].centre))
        };
        Found { anchors: [local(touch.a), local(Some(touch.b))], touch }
    }
}

/// One contact in the solve, what every sweep reads and nothing else (kept apart from `Found`,
/// so the sweeps stream less memory): its bodies, its directions (normal, two tangents), at the
/// current substep its lever arms, effective masses and target normal speed; its impulses carry
/// over the substeps.
struct Row {
    a: Option<usize>,
    b: usize,
    friction: f64,
    dirs: [V; 3],
    /// Per body (a, b) and direction: r × d, and I⁻¹(r × d), the turn an impulse along d makes.
    arms: [[V; 3]; 2],
    turns: [[V; 3]; 2],
    mass: [f64; 3],
    target: f64,
    lambda: [f64; 3],
}

impl Row {
    fn new(f: &Found) -> Row {
        let n = f.touch.normal;
        let t1 = if n.x.abs() < 0.9 { n.cross(&V::x()) } else { n.cross(&V::y()) }.normalize();
        Row {
            a: f.touch.a,
            b: f.touch.b,
            friction: f.touch.friction,
            dirs: [n, t1, n.cross(&t1)],
            arms: [[V::zeros(); 3]; 2],
            turns: [[V::zeros(); 3]; 2],
            mass: [0.0; 3],
            target: 0.0,
            lambda: [0.0; 3],
        }
    }

    /// Lever arms, effective masses and target at the current poses: the depth is the step's
    /// minus how far the anchors have parted along the normal since; depth beyond the slop is
    /// fed back, a gap may close within the substep.
    fn prepare(&mut self, f: &Found, poses: &[Pose], mobile: &[Mobile], h: f64, slop: f64) {
        let world = |i: Option<usize>, l: &V| i.map_or(*l, |i| poses[i].centre + poses[i].rotation * l);
        let (wa, wb) = (world(self.a, &f.anchors[0]), world(Some(self.b), &f.anchors[1]));
        // both bodies are pushed at one point, midway between their anchors, so the pair of
        // impulses exerts no net torque: the angular momentum is kept, not only the momentum
        let at = 0.5 * (wa + wb);
        let bodies = [self.a, Some(self.b)];
        for (side, body) in bodies.into_iter().enumerate() {
            let Some(i) = body else { continue };
            let r = at - poses[i].centre;
            self.arms[side] = self.dirs.map(|d| r.cross(&d));
            self.turns[side] = self.arms[side].map(|arm| mobile[i].inverse_inertia * arm);
        }
        let mass = |k: usize| {
            let share = |side: usize| {
                bodies[side].map_or(0.0, |i| mobile[i].inverse_mass + self.arms[side][k].dot(&self.turns[side][k]))
            };
            let resistance = share(0) + share(1);
            if resistance > 0.0 {
                1.0 / resistance
            } else {
                0.0
            }
        };
        self.mass = [mass(0), mass(1), mass(2)];
        let depth = f.touch.depth - self.dirs[0].dot(&(wb - wa));
        self.target = if depth > slop { FEEDBACK * (depth - slop) / h } else { depth.min(0.0) / h };
    }
}

impl Solver for Impulses {
    fn step(&mut self, g: &LagrangianGraph, s: &mut State, dt: f64) -> Result<(), Failure> {
        let h = dt / self.substeps as f64;
        let slop = SLOP * self.solids.margin;
        let mut poses = self.solids.poses(&s.x, &s.spin);
        let mut found: Vec<Found> =
            self.solids.touching(&poses, g.pool()).into_iter().map(|t| Found::new(t, &poses)).collect();
        // from the highest contact down: a stack's weight reaches the floor within one sweep
        found.sort_by(|a, b| b.touch.point.y.total_cmp(&a.touch.point.y));
        let mut rows: Vec<Row> = found.iter().map(Row::new).collect();
        self.start_warm(&found, &mut rows);
        // the residual: the largest normal speed the last sweep still had to correct
        let mut residual = 0.0f64;
        for substep in 0..self.substeps {
            g.kick(&mut s.v, &self.at.f, h);
            // a kick moves no body: the first substep's poses are the step's
            if substep > 0 {
                poses = self.solids.poses(&s.x, &s.spin);
            }
            let mut mobile = mobiles(g, s, &poses);
            for (r, f) in rows.iter_mut().zip(&found) {
                r.prepare(f, &poses, &mobile, h, slop);
                for k in 0..3 {
                    apply(r, &mut mobile, k, r.lambda[k]);
                }
            }
            for _ in 0..self.sweeps {
                residual = rows.iter_mut().map(|r| solve(r, &mut mobile)).fold(0.0, f64::max);
            }
            for (i, m) in mobile.iter().enumerate() {
                s.v[i] = m.v.into();
            }
            g.drift(s, h);
            // each rigid body leaves the solve with π = I Rᵀω and turns freely over the substep
            let rigid = mobile.iter().zip(&poses).enumerate().filter(|(i, _)| g.is_rigid(*i)).map(|p| p.1);
            for ((m, p), (spin, moments)) in rigid.zip(s.spin.iter_mut().zip(g.moments())) {
                let pi = (p.rotation.transpose() * m.omega).component_mul(moments);
                spin[4..].copy_from_slice(pi.as_slice());
                rigid::free_step(spin, *moments, h);
            }
            self.at.potential = g.forces(s, &mut self.at.f)?;
        }
        self.iterations.record(self.sweeps * self.substeps, residual);
        self.keep_warm(&found, &rows);
        Ok(())
    }

    /// Its contact search spreads over the pool at any size.
    fn spreads(&self, g: &LagrangianGraph) -> bool {
        g.pool().is_some()
    }

    fn evaluated(&self) -> &Evaluated {
        &self.at
    }

    /// The forces and the warm starts, pairs in order (the map's own order is arbitrary).
    fn carried(&self) -> Result<Carried, String> {
        let mut warm: Vec<_> = self
            .warm
            .iter()
            .map(|(&pair, w)| (pair, w.iter().map(|(place, j)| ((*place).into(), *j)).collect()))
            .collect();
        warm.sort_by_key(|w: &((usize, usize), Vec<_>)| w.0);
        Ok(Carried { warm, ..Carried::forces(&self.at) })
    }

    fn take_up(&mut self, c: &Carried) {
        self.at = c.evaluated();
        let place = |w: &[([f64; 3], [f64; 3])]| w.iter().map(|(p, j)| (V::from(*p), *j)).collect();
        self.warm = c.warm.iter().map(|(pair, w)| (*pair, place(w))).collect();
    }

    fn rotates(&self) -> bool {
        true
    }

    fn iterations(&self) -> Option<&Iterations> {
        Some(&self.iterations)
    }
}

/// Every body's mobile share at the substep's start (a point mass turns not: zero inverse inertia).
fn mobiles(g: &LagrangianGraph, s: &State, poses: &[Pose]) -> Vec<Mobile> {
    let mut spins = s.spin.iter().zip(g.moments());
    (0..s.x.len())
        .map(|i| {
            let (inverse_inertia, omega) = match g.is_rigid(i).then(|| spins.next()).flatten() {
                Some((spin, moments)) => {
                    let r = poses[i].rotation;
                    let inverse = r * Matrix3::from_diagonal(&moments.map(|c| 1.0 / c)) * r.transpose();
                    (inverse, r * rigid::omega(spin, *moments))
                }
                None => (Matrix3::zeros(), V::zeros()),
            };
            Mobile { inverse_mass: g.inverse_masses[i], inverse_inertia, v: V::from(s.v[i]), omega }
        })
        .collect()
}

/// One contact's Gauss–Seidel update: the normal impulse clamped to push only, then friction
/// held inside μλₙ's disc. Returns the normal speed it changed.
fn solve(r: &mut Row, mobile: &mut [Mobile]) -> f64 {
    let total = (r.lambda[0] + r.mass[0] * (r.target - relative(r, mobile, 0))).max(0.0);
    let change = total - r.lambda[0];
    apply(r, mobile, 0, change);
    r.lambda[0] = total;
    let wanted = [1, 2].map(|k| r.lambda[k] - r.mass[k] * relative(r, mobile, k));
    let (size, most) = ((wanted[0].powi(2) + wanted[1].powi(2)).sqrt(), r.friction * r.lambda[0]);
    let scale = if size > most && size > 0.0 { most / size } else { 1.0 };
    for k in [1, 2] {
        let total = wanted[k - 1] * scale;
        apply(r, mobile, k, total - r.lambda[k]);
        r.lambda[k] = total;
    }
    if r.mass[0] > 0.0 {
        (change / r.mass[0]).abs()
    } else {
        0.0
    }
}

/// How fast b moves away from a along direction k at the contact.
fn relative(r: &Row, mobile: &[Mobile], k: usize) -> f64 {
    let d = &r.dirs[k];
    mobile[r.b].speed(d, &r.arms[1][k]) - r.a.map_or(0.0, |a| mobile[a].speed(d, &r.arms[0][k]))
}

/// An impulse `amount` along direction k: on b, and its opposite on a, at the contact.
fn apply(r: &Row, mobile: &mut [Mobile], k: usize, amount: f64) {
    mobile[r.b].nudge(&r.dirs[k], &r.turns[1][k], amount);
    if let Some(a) = r.a {
        mobile[a].nudge(&r.dirs[k], &r.turns[0][k], -amount);
    }
}

impl Impulses {
    /// Each row starts from the impulses of last step's nearest contact of the same pair (within
    /// twice the margin).
    fn start_warm(&self, found: &[Found], rows: &mut [Row]) {
        let reach = self.solids.margin * self.solids.margin * 4.0;
        for (r, f) in rows.iter_mut().zip(found) {
            let key = (r.a.map_or(usize::MAX, |a| a), r.b);
            let Some(old) = self.warm.get(&key) else { continue };
            let near =
                old.iter().map(|(p, l)| ((p - f.touch.point).norm_squared(), l)).min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((_, lambda)) = near.filter(|n| n.0 <= reach) {
                r.lambda = *lambda;
            }
        }
    }

    fn keep_warm(&mut self, found: &[Found], rows: &[Row]) {
        self.warm.clear();
        for (r, f) in rows.iter().zip(found) {
            let key = (r.a.map_or(usize::MAX, |a| a), r.b);
            self.warm.entry(key).or_default().push((f.touch.point, r.lambda));
        }
    }
}
