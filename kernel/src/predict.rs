//! Closed-form predictions derived from a scene's own Lagrangian and initial state, measured
//! along the run: the damped oscillator's period and Kepler's third law. These are measured
//! agreements (the integrator's error), not certified claims.

use lagra_checker::model::Model;
use lagra_checker::terms::Kind;
use nalgebra::Vector3;
use serde::Serialize;
use std::f64::consts::TAU;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PredictionKind {
    /// A single damped harmonic bond: T = 2π/ω_d, ω_d = √(k/μ − (γ/2μ)²), μ the reduced mass.
    OscillatorPeriod,
    /// Two bodies under Newtonian gravity: T = 2π√(a³/G(m₀+m₁)), a from the vis-viva equation.
    KeplerPeriod,
}

#[derive(Clone, Debug)]
pub struct Prediction {
    pub kind: PredictionKind,
    /// The relative difference allowed between measured and predicted; reported only if absent.
    pub tol: Option<f64>,
    pub predicted: f64,
}

impl PredictionKind {
    pub const ALL: [PredictionKind; 2] = [PredictionKind::OscillatorPeriod, PredictionKind::KeplerPeriod];

    pub fn name(self) -> &'static str {
        match self {
            PredictionKind::OscillatorPeriod => "oscillator_period",
            PredictionKind::KeplerPeriod => "kepler_period",
        }
    }

    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// The predicted period, or why the closed form does not apply to this scene.
    pub fn predict(self, model: &Model, x0: &[[f64; 3]], v0: &[[f64; 3]]) -> Result<f64, String> {
        let kinds: Vec<Kind> = model.terms.iter().map(|t| t.kind).collect();
        let rel = |i: usize, j: usize| {
            (Vector3::from(x0[j]) - Vector3::from(x0[i]), Vector3::from(v0[j]) - Vector3::from(v0[i]))
        };
        match self {
            PredictionKind::OscillatorPeriod => {
                let bond = match kinds.as_slice() {
                    [Kind::HarmonicBond] => &model.terms[0],
                    _ => return Err("needs exactly one harmonic bond and no other term".into()),
                };
                let (i, j) = (bond.sites[0], bond.sites[1]);
                let (m1, m2) = (model.bodies[i].mass, model.bodies[j].mass);
                let mu = m1 * m2 / (m1 + m2);
                let (k, gamma) = (bond.params[0], bond.params[2]);
                let (r, v) = rel(i, j);
                if r.cross(&v).norm() > 1e-12 * r.norm() * v.norm().max(f64::MIN_POSITIVE) {
                    return Err("the closed form assumes motion along the bond, but the bond starts rotating".into());
                }
                let w2 = k / mu - (gamma / (2.0 * mu)).powi(2);
                if w2 > 0.0 {
                    Ok(TAU / w2.sqrt())
                } else {
                    Err("the bond is critically or over-damped: it has no period".into())
                }
            }
            PredictionKind::KeplerPeriod => {
                if kinds != [Kind::Gravity] || model.bodies.len() != 2 {
                    return Err("needs exactly two bodies and one gravity interaction".into());
                }
                let mu = model.terms[0].params[0] * (model.bodies[0].mass + model.bodies[1].mass);
                let (r, v) = rel(0, 1);
                let inv_a = 2.0 / r.norm() - v.norm_squared() / mu;
                if inv_a > 0.0 {
                    Ok(TAU * (inv_a.powi(-3) / mu).sqrt())
                } else {
                    Err("the orbit is unbound: it has no period".into())
                }
            }
        }
    }
}

/// Measures a period along the trajectory.
pub enum Meter {
    /// Upward zero crossings of the bond extension |r| − r₀.
    Crossings { i: usize, j: usize, r0: f64, last: Option<(f64, f64)>, first: Option<f64>, latest: f64, count: u64 },
    /// Completed revolutions of the relative position in the orbital plane.
    Revolutions { basis: Option<(Vector3<f64>, Vector3<f64>)>, angle: f64, last: (f64, f64), turns: u64, at: f64 },
}

impl Meter {
    pub fn new(p: &Prediction, model: &Model) -> Meter {
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
            PredictionKind::KeplerPeriod => {
                Meter::Revolutions { basis: None, angle: 0.0, last: (0.0, 0.0), turns: 0, at: 0.0 }
            }
        }
    }

    pub fn observe(&mut self, t: f64, x: &[[f64; 3]], v: &[[f64; 3]]) {
        match self {
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
            Meter::Revolutions { basis, angle, last, turns, at } => {
                let r = Vector3::from(x[1]) - Vector3::from(x[0]);
                let (e1, e2) = *basis.get_or_insert_with(|| {
                    let n = r.cross(&(Vector3::from(v[1]) - Vector3::from(v[0])));
                    let e1 = r.normalize();
                    (e1, n.normalize().cross(&e1))
                });
                // Unwrapped angle in the orbital plane, counted from the initial direction.
                let (t0, raw0) = *last;
                let raw = r.dot(&e2).atan2(r.dot(&e1));
                let mut d = raw - raw0;
                d -= TAU * (d / TAU).round();
                let before = *angle;
                *angle += d;
                *last = (t, raw);
                let target = TAU * (*turns + 1) as f64;
                if before < target && *angle >= target {
                    *turns += 1;
                    *at = t0 + (t - t0) * (target - before) / d;
                }
            }
        }
    }

    /// The measured period, once enough of the trajectory has been seen.
    pub fn measured(&self) -> Option<f64> {
        match self {
            Meter::Crossings { first, latest, count, .. } if *count >= 2 => {
                Some((latest - first.unwrap_or(0.0)) / (*count - 1) as f64)
            }
            Meter::Revolutions { turns, at, .. } if *turns >= 1 => Some(at / *turns as f64),
            _ => None,
        }
    }
}
