//! Dual numbers: the generic definitions differentiated exactly, to hold the fast forces to
//! F = −∂V/∂x − ∂F_R/∂v.

use super::{group, Frame};
use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
use lagra_checker::mpfi::Mpfi;
use lagra_checker::real::Real;
use lagra_checker::terms::{Kind, Shape, Site};
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug)]
pub struct Dual {
    v: f64,
    d: f64,
}

impl Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        Dual { v: self.v + o.v, d: self.d + o.d }
    }
}
impl Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        Dual { v: self.v - o.v, d: self.d - o.d }
    }
}
impl Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        Dual { v: self.v * o.v, d: self.d * o.v + self.v * o.d }
    }
}
impl Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        Dual { v: self.v / o.v, d: (self.d * o.v - self.v * o.d) / (o.v * o.v) }
    }
}
impl Neg for Dual {
    type Output = Dual;
    fn neg(self) -> Dual {
        Dual { v: -self.v, d: -self.d }
    }
}
impl Real for Dual {
    fn lift(&self, c: f64) -> Self {
        Dual { v: c, d: 0.0 }
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        Dual { v: s, d: self.d / (2.0 * s) }
    }
    fn powi(self, n: i32) -> Self {
        Dual { v: self.v.powi(n), d: n as f64 * self.v.powi(n - 1) * self.d }
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        Dual { v: e, d: e * self.d }
    }
    fn ln(self) -> Self {
        Dual { v: self.v.ln(), d: self.d / self.v }
    }
    fn acos(self) -> Self {
        let c = self.v.clamp(-1.0, 1.0);
        Dual { v: c.acos(), d: -self.d / (1.0 - c * c).sqrt() }
    }
    fn cos(self) -> Self {
        Dual { v: self.v.cos(), d: -self.v.sin() * self.d }
    }
    fn sin(self) -> Self {
        Dual { v: self.v.sin(), d: self.v.cos() * self.d }
    }
    fn atan2(self, x: Self) -> Self {
        let r2 = x.v * x.v + self.v * self.v;
        Dual { v: self.v.atan2(x.v), d: (x.v * self.d - self.v * x.d) / r2 }
    }
    fn lt(&self, bound: &Self) -> Option<bool> {
        Some(self.v < bound.v)
    }
    fn hull(self, _: Self) -> Self {
        self
    }
}

/// A small deterministic generator (SplitMix64), so a failing case reproduces from its seed.
pub struct Rng(u64);
impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// At a random configuration from `seed` (bodies 0 and 1 `sep` apart when `sep` < 1), the fast
/// force of one instance of `kind` equals −∂V/∂x − ∂F_R/∂v of its definition, and the fast
/// energy equals V, to round-off.
pub fn assert_matches_definition(kind: Kind, params: &[f64], seed: u64, sep: f64) {
    let mut rng = Rng::new(seed);
    let n = kind.spec().shape.arity();
    let mut x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-3.0, 3.0))).collect();
    let v: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-2.0, 2.0))).collect();
    let m: Vec<f64> = (0..n).map(|_| rng.uniform(0.5, 3.0)).collect();
    if sep < 1.0 && n == 2 {
        let dir: [f64; 3] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        x[1] = std::array::from_fn(|c| x[0][c] + sep * dir[c]);
    }
    let sites = if matches!(kind.spec().shape, Shape::Bond(_)) { (0..n).collect() } else { vec![] };
    let term = TermInstance { kind, sites, params: params.to_vec() };
    let q: Vec<f64> = (0..n).map(|_| rng.uniform(-2.0, 2.0)).collect();
    let colour: Vec<[f64; 2]> = (0..n).map(|_| [rng.uniform(-0.5, 0.5), rng.uniform(-0.6, 0.6)]).collect();
    let bodies = m
        .iter()
        .zip(&q)
        .zip(&colour)
        .map(|((&mass, &charge), &colour)| Body { mass, charge, colour, moments: None, solid: None })
        .collect();
    let model = Model {
        units: UnitSystem::Reduced,
        cell: None,
        bodies,
        terms: vec![term.clone()],
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    };

    let mut fast = vec![[0.0; 3]; n];
    let energy = group(kind, &[(0, &term)], &model, &None)
        .accumulate(&Frame { x: &x, v: &v, m: &m, q: &q, c: &colour }, &mut fast, true)
        .expect("no singularity");

    // The definition at positions x, where coordinate (b, c) of x (or v) carries the derivative.
    let eval = |x: &[[f64; 3]], b: usize, c: usize, of_velocity: bool| -> (Dual, Option<Dual>) {
        let sites: Vec<Site<Dual>> = (0..n)
            .map(|i| {
                let seed = |k: usize, vel: bool| {
                    if i == b && k == c && vel == of_velocity {
                        1.0
                    } else {
                        0.0
                    }
                };
                Site {
                    x: std::array::from_fn(|k| Dual { v: x[i][k], d: seed(k, false) }),
                    v: std::array::from_fn(|k| Dual { v: v[i][k], d: seed(k, true) }),
                    m: Dual { v: m[i], d: 0.0 },
                    q: Dual { v: q[i], d: 0.0 },
                    colour: colour[i].map(|c| Dual { v: c, d: 0.0 }),
                }
            })
            .collect();
        let p: Vec<Dual> = params.iter().map(|&c| Dual { v: c, d: 0.0 }).collect();
        let s: Vec<&Site<Dual>> = sites.iter().collect();
        (kind.potential(&p, &s), kind.rayleigh(&p, &s))
    };
    // The velocity-linear part of L, at positions x + ε·xd and velocities vel.
    let gyro = |x: &[[f64; 3]], xd: &dyn Fn(usize, usize) -> f64, vel: &dyn Fn(usize, usize) -> f64| {
        let sites: Vec<Site<Dual>> = (0..n)
            .map(|i| Site {
                x: std::array::from_fn(|k| Dual { v: x[i][k], d: xd(i, k) }),
                v: std::array::from_fn(|k| Dual { v: vel(i, k), d: 0.0 }),
                m: Dual { v: m[i], d: 0.0 },
                q: Dual { v: q[i], d: 0.0 },
                colour: colour[i].map(|c| Dual { v: c, d: 0.0 }),
            })
            .collect();
        let p: Vec<Dual> = params.iter().map(|&c| Dual { v: c, d: 0.0 }).collect();
        kind.gyroscopic(&p, &sites.iter().collect::<Vec<_>>())
    };
    // Its Euler–Lagrange force ∂L/∂x_bc − (v·∇)∂L/∂v_bc; ∂L/∂v_bc is L at the unit velocity e_bc.
    let lorentz = |x: &[[f64; 3]], b: usize, c: usize| -> f64 {
        let at_v = |i: usize, k: usize| v[i][k];
        let unit = |i: usize, k: usize| if (i, k) == (b, c) { 1.0 } else { 0.0 };
        let dl_dx = gyro(x, &unit, &at_v).map_or(0.0, |g| g.d);
        let transport = gyro(x, &at_v, &unit).map_or(0.0, |g| g.d);
        dl_dx - transport
    };
    let force_at = |x: &[[f64; 3]]| -> Vec<[f64; 3]> {
        (0..n)
            .map(|b| {
                std::array::from_fn(|c| {
                    -eval(x, b, c, false).0.d - eval(x, b, c, true).1.map_or(0.0, |f| f.d) + lorentz(x, b, c)
                })
            })
            .collect()
    };
    let exact = force_at(&x);
    let coordinates = || (0..n).flat_map(|b| (0..3).map(move |c| (b, c)));
    // The round-off the inputs carry into V: |V| + Σ |∂V/∂x|·(|x| + 1).
    let v_def = eval(&x, 0, 0, false).0.v;
    let carried: f64 = coordinates().map(|(b, c)| eval(&x, b, c, false).0.d.abs() * (x[b][c].abs() + 1.0)).sum();
    // The round-off of V's own formula, which no derivative shows: V's width in binary64
    // interval arithmetic, over ε. A force-shifted potential near its cut-off is
    // V(r) − V(r_c) + (r − r_c)F(r_c), terms of size V(r_c) that nearly cancel.
    let cancelled = {
        let at = |c: f64| Mpfi::point(53, c);
        let sites: Vec<Site<Mpfi>> = (0..n)
            .map(|i| Site { x: x[i].map(at), v: v[i].map(at), m: at(m[i]), q: at(q[i]), colour: colour[i].map(at) })
            .collect();
        let p: Vec<Mpfi> = params.iter().map(|&c| at(c)).collect();
        let (lo, hi) = kind.potential(&p, &sites.iter().collect::<Vec<_>>()).bounds();
        ((hi - lo) / f64::EPSILON).max(0.0) // NaN (the interval is empty): no allowance
    };
    // And into F: Σ |∂F/∂x|·(|x| + 1), by differences of the exact force. It is large where the
    // force is ill-conditioned — an angle near straight (acos), a shifted force near its cut-off
    // (F(r) − F(r_c)) — and there two correct evaluations differ by more than |F|·ε. The lesser
    // of the step forward and the step back: within h of a truncated cut-off one of them jumps
    // with the force, which would loosen the check there.
    let sensitivity: f64 = coordinates()
        .map(|(b, c)| {
            let h = 1e-7 * (x[b][c].abs() + 1.0);
            let slope = |step: f64| {
                let mut moved = x.clone();
                moved[b][c] += step;
                let moved = force_at(&moved);
                let df = moved.iter().flatten().zip(exact.iter().flatten()).map(|(g, f)| (g - f).abs());
                df.fold(0.0f64, f64::max) / h
            };
            slope(h).min(slope(-h)) * (x[b][c].abs() + 1.0)
        })
        .sum();
    let scale = v_def.abs() + carried + sensitivity + exact.iter().flatten().fold(0.0f64, |a, f| a.max(f.abs()));
    for (b, (fa, fe)) in fast.iter().zip(&exact).enumerate() {
        for c in 0..3 {
            assert!(fa[c].is_finite(), "force on body {b} is not finite");
            assert!(
                (fa[c] - fe[c]).abs() <= 1e-11 * scale + 1e-300,
                "{kind:?} body {b} axis {c}: fast {} vs exact {}",
                fa[c],
                fe[c]
            );
        }
    }
    assert!(
        (energy - v_def).abs() <= 1e-11 * (v_def.abs() + carried + cancelled) + 1e-300,
        "{kind:?} energy: fast {energy} vs definition {v_def}"
    );
    // a dissipative term's power is v·∂F/∂v
    let sites: Vec<Site<f64>> =
        (0..n).map(|i| Site { x: x[i], v: v[i], m: m[i], q: q[i], colour: colour[i] }).collect();
    let refs: Vec<&Site<f64>> = sites.iter().collect();
    if let Some(power) = kind.power(params, &refs) {
        let terms: Vec<f64> =
            coordinates().map(|(b, c)| v[b][c] * eval(&x, b, c, true).1.map_or(0.0, |f| f.d)).collect();
        let euler: f64 = terms.iter().sum();
        // The sum cancels where the bodies move mostly across the bond (ṙ small against |v|);
        // its condition is Σ |terms|, not |power|.
        let condition: f64 = terms.iter().map(|t| t.abs()).sum();
        assert!(
            (power - euler).abs() <= 1e-11 * (power.abs() + condition) + 1e-300,
            "{kind:?} power {power} vs v·∂F/∂v {euler}"
        );
    }
}
