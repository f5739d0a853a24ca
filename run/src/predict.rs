//! The scene's predictions (`lagra_lang::prediction`: their closed forms) measured along a run:
//! a period by its crossings or windings, equipartition and the virial by averages, the
//! Maxwell–Boltzmann distribution by a Kolmogorov–Smirnov test. These are measured agreements
//! (the integrator's error), not certified claims.

use lagra_checker::model::Model;
use lagra_lang::prediction::{Column, Prediction, PredictionKind, MARTIN_MOYCE};
use lagra_lang::thermostat::Bath;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Measures a period along the trajectory (a restart file carries what it measured so far).
#[derive(Clone, Serialize, Deserialize)]
pub enum Meter {
    /// Upward zero crossings of the bond extension |r| − r₀.
    Crossings { i: usize, j: usize, r0: f64, last: Option<(f64, f64)>, first: Option<f64>, latest: f64, count: u64 },
    /// Completed revolutions of the relative position in the orbital plane.
    Revolutions(Winding),
    /// Completed turns of body 0's velocity about the magnetic field, and the extent of its
    /// orbit across the field (the positions' least and greatest along a fixed in-plane axis).
    Gyrations { normal: Vector3<f64>, winding: Winding, extent: (f64, f64), radius: bool },
    /// Kinetic energy along each axis, at every state of the run (and the bath, if any).
    Axes { masses: Vec<f64>, per_state: Vec<[f64; 3]>, bath: Option<Bath> },
    /// Running sums of 2T and of −Σ x·F over the states of the run.
    Virial { masses: Vec<f64>, kinetic: f64, virial: f64, states: u64 },
    /// The first and the last velocities, the masses, and the bath's kT if any.
    Velocities { first: Option<Vec<[f64; 3]>>, last: Vec<[f64; 3]>, masses: Vec<f64>, kt: Option<f64> },
    /// A dam break's front z/a at each state (T = t√(2g/a), Z), thinned to the times between.
    Front { column: Column, last: Option<(f64, f64)>, at: Vec<(f64, f64)> },
}

impl Meter {
    pub fn new(p: &Prediction, model: &Model, x0: &[[f64; 3]], bath: Option<Bath>) -> Meter {
        match p.kind {
            PredictionKind::OscillatorPeriod => {
                let b = &model.terms[0];
                Meter::Crossings {
                    i: b.sites[0],
                    j: b.sites[1],
                    r0: b.params[1],
                    last: None,
                    first: None,
                    latest: 0.0,
                    count: 0,
                }
            }
            PredictionKind::KeplerPeriod => Meter::Revolutions(Winding::default()),
            PredictionKind::Equipartition => {
                Meter::Axes { masses: model.bodies.iter().map(|b| b.mass).collect(), per_state: vec![], bath }
            }
            PredictionKind::Virial => Meter::Virial {
                masses: model.bodies.iter().map(|b| b.mass).collect(),
                kinetic: 0.0,
                virial: 0.0,
                states: 0,
            },
            PredictionKind::CyclotronPeriod | PredictionKind::CyclotronRadius => {
                let (t, q) = (&model.terms[0], model.bodies[0].charge);
                // a positive charge turns clockwise about B
                let normal = -Vector3::new(t.params[0], t.params[1], t.params[2]) * q.signum();
                let radius = p.kind == PredictionKind::CyclotronRadius;
                Meter::Gyrations {
                    normal,
                    winding: Winding::default(),
                    extent: (f64::INFINITY, f64::NEG_INFINITY),
                    radius,
                }
            }
            PredictionKind::DamBreakFront => {
                let column = Column::of(model, x0).expect("the prediction was accepted at compile time");
                Meter::Front { column, last: None, at: vec![] }
            }
            PredictionKind::MaxwellBoltzmann => {
                let masses = model.bodies.iter().map(|b| b.mass).collect();
                Meter::Velocities { first: None, last: vec![], masses, kt: bath.map(|b| b.kt) }
            }
        }
    }

    /// One state of the run: time, positions, velocities, and the forces there.
    pub fn observe(&mut self, t: f64, x: &[[f64; 3]], v: &[[f64; 3]], f: &[[f64; 3]]) {
        match self {
            Meter::Axes { masses, per_state, .. } => {
                let along = |a: usize| v.iter().zip(masses.iter()).map(|(v, m)| 0.5 * m * v[a] * v[a]).sum::<f64>();
                per_state.push([along(0), along(1), along(2)]);
            }
            Meter::Virial { masses, kinetic, virial, states } => {
                *kinetic += x
                    .iter()
                    .zip(v)
                    .zip(masses.iter())
                    .map(|((_, v), m)| m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
                    .sum::<f64>();
                *virial -= x.iter().zip(f).map(|(x, f)| x[0] * f[0] + x[1] * f[1] + x[2] * f[2]).sum::<f64>();
                *states += 1;
            }
            Meter::Velocities { first, last, .. } => {
                first.get_or_insert_with(|| v.to_vec());
                last.clear();
                last.extend_from_slice(v);
            }
            Meter::Crossings { i, j, r0, last, first, latest, count } => {
                let s = (Vector3::from(x[*j]) - Vector3::from(x[*i])).norm() - *r0;
                if let Some((t0, s0)) = *last {
                    if s0 < 0.0 && s >= 0.0 {
                        let tc = t0 + (t - t0) * (-s0) / (s - s0);
                        first.get_or_insert(tc);
                        *latest = tc;
                        *count += 1;
                    }
                }
                *last = Some((t, s));
            }
            Meter::Front { column: c, last, at } => {
                let now = (t * (2.0 * c.g / c.a).sqrt(), c.front(x));
                // the front between the last state and this one at each of the table's times
                if let Some((t0, z0)) = *last {
                    for &(tm, _) in MARTIN_MOYCE.iter().filter(|(tm, _)| t0 < *tm && *tm <= now.0) {
                        at.push((tm, z0 + (now.1 - z0) * (tm - t0) / (now.0 - t0)));
                    }
                }
                *last = Some(now);
            }
            Meter::Revolutions(w) => {
                let r = Vector3::from(x[1]) - Vector3::from(x[0]);
                let n = r.cross(&(Vector3::from(v[1]) - Vector3::from(v[0])));
                w.push(t, r, n);
            }
            Meter::Gyrations { normal, winding, extent, .. } => {
                winding.push(t, Vector3::from(v[0]), *normal);
                if let Some((e1, _)) = winding.basis {
                    let along = Vector3::from(x[0]).dot(&e1);
                    *extent = (extent.0.min(along), extent.1.max(along));
                }
            }
        }
    }

    /// The measured value (a period, or a statistical test's p-value) and, for a test, what it
    /// saw; `None` if the run saw too little.
    pub fn measured(&self) -> Option<(f64, Option<String>)> {
        if let Meter::Velocities { first: Some(first), last, masses, kt } = self {
            let (d, p, t) = ks_maxwell_boltzmann(last, masses, *kt);
            let (_, p0, _) = ks_maxwell_boltzmann(first, masses, *kt);
            let n = 3 * last.len();
            return Some((
                p,
                Some(format!(
                    "KS along each axis, {n} velocity components at T = {t:.4}: D ≤ {d:.4}, p = {p:.3} (initially p = {p0:.1e})"
                )),
            ));
        }
        if let Meter::Front { at, .. } = self {
            // the ratio farthest from 1, and every point
            let ratios: Vec<(f64, f64, f64)> =
                at.iter().zip(MARTIN_MOYCE).map(|(&(t, z), (_, zm))| (t, z, zm)).collect();
            let worst =
                ratios.iter().map(|(_, z, zm)| z / zm).max_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))?;
            let points: Vec<String> = ratios.iter().map(|(t, z, zm)| format!("T {t}: z/a {z:.3} (M&M {zm})")).collect();
            return Some((worst, Some(format!("front against Martin & Moyce 1952: {}", points.join(", ")))));
        }
        self.period().map(|t| (t, None))
    }

    fn period(&self) -> Option<f64> {
        match self {
            Meter::Crossings { first, latest, count, .. } if *count >= 2 => {
                Some((latest - first.unwrap_or(0.0)) / (*count - 1) as f64)
            }
            Meter::Gyrations { winding, extent, radius: true, .. } => {
                winding.period().map(|_| (extent.1 - extent.0) / 2.0)
            }
            Meter::Revolutions(w) | Meter::Gyrations { winding: w, .. } => w.period(),
            Meter::Virial { kinetic, virial, states, .. } if *states > 1 => Some(kinetic / virial),
            Meter::Axes { per_state, bath, .. } if per_state.len() >= 20 => {
                let second_half = &per_state[per_state.len() / 2..];
                let n = second_half.len() as f64;
                let mean: [f64; 3] = std::array::from_fn(|a| second_half.iter().map(|k| k[a]).sum::<f64>() / n);
                if let Some(b) = bath {
                    return Some(2.0 * mean.iter().sum::<f64>() / b.dof);
                }
                let (lo, hi) = mean.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &k| (lo.min(k), hi.max(k)));
                Some(hi / lo)
            }
            _ => None,
        }
    }
}

/// Counts the turns of a vector about a fixed normal, interpolating the time of each.
#[derive(Clone, Default, Serialize, Deserialize)]
pub struct Winding {
    basis: Option<(Vector3<f64>, Vector3<f64>)>,
    angle: f64,
    last: (f64, f64),
    turns: u64,
    at: f64,
}

impl Winding {
    /// The vector `r` at time `t`; `normal` (used at the first call) fixes the plane and the
    /// positive sense of rotation.
    fn push(&mut self, t: f64, r: Vector3<f64>, normal: Vector3<f64>) {
        let (e1, e2) = *self.basis.get_or_insert_with(|| {
            let n = normal.normalize();
            let e1 = (r - n * r.dot(&n)).normalize();
            (e1, n.cross(&e1))
        });
        // Unwrapped angle in the plane, counted from the initial direction.
        let (t0, raw0) = self.last;
        let raw = r.dot(&e2).atan2(r.dot(&e1));
        let mut d = raw - raw0;
        d -= TAU * (d / TAU).round();
        let before = self.angle;
        self.angle += d;
        self.last = (t, raw);
        let target = TAU * (self.turns + 1) as f64;
        if before < target && self.angle >= target {
            self.turns += 1;
            self.at = t0 + (t - t0) * (target - before) / d;
        }
    }

    fn period(&self) -> Option<f64> {
        (self.turns >= 1).then(|| self.at / self.turns as f64)
    }
}

/// Kolmogorov–Smirnov test of velocities against Maxwell–Boltzmann: each axis on its own (the
/// distribution is Gaussian along every axis at one temperature), the components relative to the
/// centre of mass and scaled by √(m/T), T = Σ m|v − v_cm|² / (3N − 3), against the standard
/// normal (or at `kt`, a bath's, if given). Returns the largest D, the p-value of the three
/// tests together (Bonferroni: three times the least, at most 1) and T; each p from the
/// asymptotic Kolmogorov distribution with Stephens' small-sample correction.
fn ks_maxwell_boltzmann(v: &[[f64; 3]], m: &[f64], kt: Option<f64>) -> (f64, f64, f64) {
    let total: f64 = m.iter().sum();
    let cm: [f64; 3] = std::array::from_fn(|c| v.iter().zip(m).map(|(v, m)| m * v[c]).sum::<f64>() / total);
    let twice_kinetic: f64 =
        v.iter().zip(m).map(|(v, m)| m * (0..3).map(|c| (v[c] - cm[c]).powi(2)).sum::<f64>()).sum();
    let t = kt.unwrap_or(twice_kinetic / (3.0 * v.len() as f64 - 3.0));
    let (mut worst_d, mut least_p) = (0.0f64, 1.0f64);
    for c in 0..3 {
        let mut z: Vec<f64> = v.iter().zip(m).map(|(v, m)| (v[c] - cm[c]) * (m / t).sqrt()).collect();
        z.sort_by(f64::total_cmp);
        let n = z.len() as f64;
        let d = z.iter().enumerate().fold(0.0f64, |d, (i, x)| {
            let f = 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2);
            d.max((i + 1) as f64 / n - f).max(f - i as f64 / n)
        });
        let lambda = (n.sqrt() + 0.12 + 0.11 / n.sqrt()) * d;
        let p: f64 = if lambda < 0.2 {
            1.0
        } else {
            (1..=100)
                .map(|k| (if k % 2 == 1 { 2.0 } else { -2.0 }) * (-2.0 * (k * k) as f64 * lambda * lambda).exp())
                .sum()
        };
        worst_d = worst_d.max(d);
        least_p = least_p.min(p.clamp(0.0, 1.0));
    }
    (worst_d, (3.0 * least_p).min(1.0), t)
}

#[cfg(test)]
mod tests {
    use super::ks_maxwell_boltzmann;

    /// Deterministic standard-normal samples (Box–Muller on a fixed sequence).
    fn gaussian(n: usize) -> Vec<f64> {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut u = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| (-2.0 * u().max(1e-300).ln()).sqrt() * (std::f64::consts::TAU * u()).cos()).collect()
    }

    #[test]
    fn gaussian_velocities_pass_and_uniform_ones_fail() {
        let g = gaussian(3 * 300);
        let v: Vec<[f64; 3]> = g.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let (_, p, _) = ks_maxwell_boltzmann(&v, &vec![1.0; 300], None);
        assert!(p > 0.05, "a Gaussian sample is rejected: p = {p}");
        // uniform components of unit variance differ from the normal by D ≈ 0.052: 9000 of them
        // make that unmistakable
        let uniform: Vec<[f64; 3]> = (0..3000)
            .map(|i| {
                let x = (i as f64 + 0.5) / 3000.0 * 2.0 - 1.0;
                [x, -x, x]
            })
            .collect();
        let (_, p, _) = ks_maxwell_boltzmann(&uniform, &vec![1.0; 3000], None);
        assert!(p < 1e-3, "a uniform sample passes: p = {p}");
    }
}
