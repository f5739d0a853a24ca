//! Holonomic distance constraints kept by SHAKE (positions: Ryckaert, Ciccotti & Berendsen 1977)
//! and RATTLE (velocities: Andersen 1983).
//!
//! SHAKE's equations for the multipliers λ of the constraint forces along the rods as they were
//! at the start of the step (rᵃ) are solved by Newton's method: the residual gₐ = (ℓ² − |sₐ|²)/2
//! of every rod sₐ = xⱼ − xᵢ, then A·δλ = g with Aₐᵦ = Σₖ wₖ σₐₖ σᵦₖ rₐ·rᵦ (w = 1/m, σ = ±1 for
//! a rod's two ends: the rods' coupling through their shared bodies), moving each body by
//! wₖ Σᵦ δλᵦ σᵦₖ rᵦ, until every rod has its length to `tol`. A is symmetric positive definite
//! for independent rods, and solved by conjugate gradients, matrix-free, in a fixed order (so
//! the bits never depend on the thread count). This is M-SHAKE's matrix form: the classic
//! constraint-by-constraint sweeps (Gauss–Seidel) took ~500 sweeps a step on an eight-rod chain
//! at tol 10⁻¹⁰ (measured), this takes a few rounds. RATTLE's velocity equations are linear,
//! with A built on the new rods, and solved the same way. A round that does not bring every rod
//! within `tol` in `sweeps` rounds is an error naming the worst constraint, never a state that
//! silently breaks it.

use lagra_checker::model::{Constraint, Images, Model};
use std::fmt;

/// The constraints of a model.
#[derive(Clone, Debug)]
pub struct Constraints {
    rods: Vec<Rod>,
    images: Images,
    /// The bodies some rod touches, in the order first met (a rod's ends index into it).
    bodies: Vec<usize>,
}

/// How far the iteration goes: to a relative tolerance — | |xⱼ − xᵢ| − ℓ | ≤ tol·ℓ, and a
/// speed along the rod |(vⱼ − vᵢ)·r̂| ≤ tol·ℓ/dt — in at most `sweeps` rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub tol: f64,
    pub sweeps: u32,
}

#[derive(Clone, Copy, Debug)]
struct Rod {
    i: usize,
    j: usize,
    /// `i` and `j` among the constrained bodies.
    ends: [usize; 2],
    length: f64,
}

/// A converged iteration: the rounds that corrected something, and the worst relative error
/// left (at most tol/2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Swept {
    pub sweeps: u32,
    pub error: f64,
}

/// An iteration that did not converge: which constraint is worst, by how much, after how many
/// rounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Unconverged {
    pub constraint: usize,
    pub bodies: [usize; 2],
    pub what: &'static str,
    pub error: f64,
    pub tol: f64,
    pub sweeps: u32,
}

impl fmt::Display for Unconverged {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "constraint {} (bodies {}, {}): {} did not converge in {} rounds: relative error {:.3e} > tol {:.1e}",
            self.constraint, self.bodies[0], self.bodies[1], self.what, self.sweeps, self.error, self.tol
        )
    }
}

type V3 = [f64; 3];

fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: &V3, b: &V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The rods' coupling A = J M⁻¹ Jᵀ for rod directions `dirs` (J's row a: ∓dirsₐ at its two
/// ends), applied without forming it.
struct Coupling<'a> {
    rods: &'a [Rod],
    dirs: &'a [V3],
    /// 1/m of each constrained body.
    w: &'a [f64],
}

impl Coupling<'_> {
    /// Each constrained body's displacement w·Jᵀλ for multipliers λ.
    fn spread(&self, lambda: &[f64], u: &mut [V3]) {
        u.iter_mut().for_each(|u| *u = [0.0; 3]);
        for ((r, d), l) in self.rods.iter().zip(self.dirs).zip(lambda) {
            let [a, b] = r.ends;
            for c in 0..3 {
                u[a][c] -= self.w[a] * l * d[c];
                u[b][c] += self.w[b] * l * d[c];
            }
        }
    }

    /// y = A·p.
    fn apply(&self, p: &[f64], y: &mut [f64], u: &mut [V3]) {
        self.spread(p, u);
        for ((y, r), d) in y.iter_mut().zip(self.rods).zip(self.dirs) {
            *y = dot(d, &sub(&u[r.ends[1]], &u[r.ends[0]]));
        }
    }

    /// λ with A·λ = b, by conjugate gradients (to a relative residual far below any tolerance
    /// the outer rounds ask; those check the result in the constraints' own terms).
    fn solve(&self, b: &[f64], u: &mut [V3]) -> Vec<f64> {
        let n = b.len();
        let (mut x, mut r, mut p, mut q) = (vec![0.0; n], b.to_vec(), b.to_vec(), vec![0.0; n]);
        let norm = |v: &[f64]| v.iter().map(|c| c * c).sum::<f64>();
        let (goal, mut rr) = (1e-30 * norm(b), norm(b));
        for _ in 0..2 * n + 8 {
            if rr <= goal {
                break;
            }
            self.apply(&p, &mut q, u);
            let alpha = rr / p.iter().zip(&q).map(|(p, q)| p * q).sum::<f64>();
            if !alpha.is_finite() {
                break;
            }
            x.iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
            r.iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
            let next = norm(&r);
            let beta = next / rr;
            p.iter_mut().zip(&r).for_each(|(p, r)| *p = r + beta * *p);
            rr = next;
        }
        x
    }
}

impl Constraints {
    /// The model's constraints (`None` if it has none).
    pub fn of(model: &Model) -> Option<Constraints> {
        if model.constraints.is_empty() {
            return None;
        }
        let mut bodies: Vec<usize> = vec![];
        let mut index = |b: usize| match bodies.iter().position(|&k| k == b) {
            Some(k) => k,
            None => {
                bodies.push(b);
                bodies.len() - 1
            }
        };
        let rods = model
            .constraints
            .iter()
            .map(|&Constraint { bodies: [i, j], length }| Rod { i, j, ends: [index(i), index(j)], length })
            .collect();
        Some(Constraints { rods, images: Images::of(&model.cell), bodies })
    }

    /// The rod from body i to body j (its nearest image in a periodic box).
    fn rod(&self, x: &[V3], r: &Rod) -> V3 {
        self.images.image(sub(&x[r.j], &x[r.i]))
    }

    fn coupling<'a>(&'a self, dirs: &'a [V3], w: &'a [f64]) -> Coupling<'a> {
        Coupling { rods: &self.rods, dirs, w }
    }

    /// SHAKE: moves the bodies along their rods as they were at `before` until every rod has its
    /// length, and changes the velocities by the same displacements over `dt` (so x = x₀ + dt·v
    /// still holds: the constraint force acted through the step).
    pub fn positions(
        &self,
        before: &[V3],
        x: &mut [V3],
        v: &mut [V3],
        inverse: &[f64],
        dt: f64,
        tol: Tolerance,
    ) -> Result<Swept, Unconverged> {
        let old: Vec<V3> = self.rods.iter().map(|r| self.rod(before, r)).collect();
        let w: Vec<f64> = self.bodies.iter().map(|&b| inverse[b]).collect();
        let a = self.coupling(&old, &w);
        let mut u = vec![[0.0; 3]; self.bodies.len()];
        self.rounds("the positions (SHAKE)", tol, |k: &Self| {
            let mut g = vec![0.0; k.rods.len()];
            let mut worst = (0.0f64, 0);
            for (n, (r, o)) in k.rods.iter().zip(&old).enumerate() {
                let s = k.rod(x, r);
                let (l2, s2) = (r.length * r.length, dot(&s, &s));
                g[n] = 0.5 * (l2 - s2);
                let error = if dot(&s, o) > 0.0 { (s2 - l2).abs() / (2.0 * l2) } else { f64::INFINITY };
                if !(error <= worst.0) {
                    worst = (error, n);
                }
            }
            if worst.0 <= 0.5 * tol.tol || !worst.0.is_finite() {
                return worst;
            }
            a.spread(&a.solve(&g, &mut u), &mut u);
            for (&b, d) in k.bodies.iter().zip(&u) {
                for c in 0..3 {
                    x[b][c] += d[c];
                    v[b][c] += d[c] / dt;
                }
            }
            worst
        })
    }

    /// RATTLE's second half: removes from the velocities each rod's rate of stretching, until
    /// the relative speed along every rod is at most tol·ℓ/dt.
    pub fn velocities(
        &self,
        x: &[V3],
        v: &mut [V3],
        inverse: &[f64],
        dt: f64,
        tol: Tolerance,
    ) -> Result<Swept, Unconverged> {
        let now: Vec<V3> = self.rods.iter().map(|r| self.rod(x, r)).collect();
        let w: Vec<f64> = self.bodies.iter().map(|&b| inverse[b]).collect();
        let a = self.coupling(&now, &w);
        let mut u = vec![[0.0; 3]; self.bodies.len()];
        self.rounds("the velocities (RATTLE)", tol, |k: &Self| {
            let mut rates = vec![0.0; k.rods.len()];
            let mut worst = (0.0f64, 0);
            for (n, (r, s)) in k.rods.iter().zip(&now).enumerate() {
                rates[n] = -dot(s, &sub(&v[r.j], &v[r.i]));
                // the stretching speed along the rod, against a length per step
                let error = (rates[n].abs() / dot(s, s).sqrt()) * dt / r.length;
                if !(error <= worst.0) {
                    worst = (error, n);
                }
            }
            if worst.0 <= 0.5 * tol.tol || !worst.0.is_finite() {
                return worst;
            }
            a.spread(&a.solve(&rates, &mut u), &mut u);
            for (&b, d) in k.bodies.iter().zip(&u) {
                for c in 0..3 {
                    v[b][c] += d[c];
                }
            }
            worst
        })
    }

    /// Rounds until the worst error a round *starts* with is within tol (a round that starts
    /// converged changes nothing). Returns the rounds that corrected something and the worst
    /// error left.
    fn rounds(
        &self,
        what: &'static str,
        tol: Tolerance,
        mut once: impl FnMut(&Self) -> (f64, usize),
    ) -> Result<Swept, Unconverged> {
        let mut sweeps = 0;
        loop {
            let (error, n) = once(self);
            if error <= 0.5 * tol.tol {
                return Ok(Swept { sweeps, error });
            }
            sweeps += 1;
            if sweeps > tol.sweeps || !error.is_finite() {
                let r = &self.rods[n];
                return Err(Unconverged {
                    constraint: n,
                    bodies: [r.i, r.j],
                    what,
                    error,
                    tol: tol.tol,
                    sweeps: sweeps - 1,
                });
            }
        }
    }

    /// Each rod's relative length error (for tests and the initial state's check).
    pub fn errors(&self, x: &[V3]) -> Vec<f64> {
        self.rods.iter().map(|r| (dot(&self.rod(x, r), &self.rod(x, r)).sqrt() - r.length).abs() / r.length).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, UnitSystem};

    fn chain(n: usize) -> Model {
        Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: (0..n)
                .map(|i| Body { mass: 1.0 + i as f64, charge: 0.0, colour: [0.0; 2], moments: None, solid: None })
                .collect(),
            terms: vec![],
            constraints: (1..n).map(|i| Constraint { bodies: [i - 1, i], length: 1.0 }).collect(),
            thermostat: None,
            floor: None,
            pins: vec![],
        }
    }

    #[test]
    fn shake_restores_every_length_and_rattle_every_rate() {
        let model = chain(4);
        let k = Constraints::of(&model).unwrap();
        let tol = Tolerance { tol: 1e-12, sweeps: 100 };
        let before: Vec<V3> = (0..4).map(|i| [i as f64, 0.0, 0.0]).collect();
        let mut x: Vec<V3> = before.iter().map(|p| [p[0] * 1.01, 0.02 * p[0], -0.01]).collect();
        let v0 = vec![[0.3, -0.2, 0.1], [0.0, 0.4, 0.0], [-0.1, 0.0, 0.2], [0.5, 0.5, 0.5]];
        let mut v = v0.clone();
        let inverse: Vec<f64> = model.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let shaken = k.positions(&before, &mut x, &mut v, &inverse, 0.01, tol).unwrap();
        assert!(k.errors(&x).iter().all(|e| *e <= 1e-12), "{:?}", k.errors(&x));
        assert!(shaken.sweeps <= 6, "{shaken:?}");
        k.velocities(&x, &mut v, &inverse, 0.01, tol).unwrap();
        for r in &k.rods {
            let (s, u) = (k.rod(&x, r), sub(&v[r.j], &v[r.i]));
            assert!(dot(&s, &u).abs() <= 1e-12 * 1.0 / 0.01, "{}", dot(&s, &u));
        }
        // the corrections are internal forces: momentum is unchanged
        let p =
            |v: &[V3]| -> V3 { std::array::from_fn(|c| v.iter().zip(&model.bodies).map(|(v, b)| b.mass * v[c]).sum()) };
        assert!(p(&v).iter().zip(p(&v0)).all(|(a, b)| (a - b).abs() < 1e-12));
    }

    #[test]
    fn a_rod_turned_past_a_right_angle_is_an_error_naming_it() {
        let model = chain(2);
        let k = Constraints::of(&model).unwrap();
        let before = vec![[0.0; 3], [1.0, 0.0, 0.0]];
        let mut x = vec![[0.0; 3], [-0.2, 1.5, 0.0]];
        let mut v = vec![[0.0; 3]; 2];
        let e =
            k.positions(&before, &mut x, &mut v, &[1.0, 1.0], 0.1, Tolerance { tol: 1e-10, sweeps: 50 }).unwrap_err();
        assert_eq!((e.constraint, e.bodies), (0, [0, 1]));
        assert!(e.to_string().contains("did not converge"), "{e}");
    }

    #[test]
    fn too_few_rounds_is_an_error_not_a_wrong_state() {
        let model = chain(6);
        let k = Constraints::of(&model).unwrap();
        let before: Vec<V3> = (0..6).map(|i| [i as f64, 0.0, 0.0]).collect();
        let mut x: Vec<V3> = before.iter().map(|p| [p[0] * 1.1, 0.1 * p[0] * p[0], 0.0]).collect();
        let mut v = vec![[0.0; 3]; 6];
        let e = k.positions(&before, &mut x, &mut v, &[1.0; 6], 0.1, Tolerance { tol: 1e-14, sweeps: 1 }).unwrap_err();
        assert_eq!(e.sweeps, 1);
        assert!(e.error > 1e-14);
    }

    /// A long chain converges in a few rounds (Gauss–Seidel sweeps needed hundreds).
    #[test]
    fn a_long_chain_takes_few_rounds() {
        let model = chain(40);
        let k = Constraints::of(&model).unwrap();
        let before: Vec<V3> = (0..40).map(|i| [i as f64, 0.0, 0.0]).collect();
        let mut x: Vec<V3> = before.iter().map(|p| [p[0] * 1.001, 0.003 * (p[0] * 0.7).sin(), 0.0]).collect();
        let mut v = vec![[0.0; 3]; 40];
        let inverse: Vec<f64> = model.bodies.iter().map(|b| 1.0 / b.mass).collect();
        let tol = Tolerance { tol: 1e-12, sweeps: 10 };
        let shaken = k.positions(&before, &mut x, &mut v, &inverse, 0.01, tol).unwrap();
        assert!(shaken.sweeps <= 5 && k.errors(&x).iter().all(|e| *e <= 1e-12), "{shaken:?}");
    }
}
