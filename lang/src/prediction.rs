//! The predictions a scene declares (`@predict`), and their closed forms derived from the
//! scene's own Lagrangian and initial state: the damped oscillator's period, Kepler's third
//! law, the cyclotron orbit. They are theory, worked out before any step; measuring them along
//! a run is the run's (`lagra_run::predict`). Agreements measure the integrator's error; they
//! are not certified claims.

use crate::thermostat::Bath;
use lagra_checker::model::Model;
use lagra_checker::terms::{Kind, Shape};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PredictionKind {
    /// A single damped harmonic bond: T = 2π/ω_d, ω_d = √(k/μ − (γ/2μ)²), μ the reduced mass.
    OscillatorPeriod,
    /// Two bodies under Newtonian gravity: T = 2π√(a³/G(m₀+m₁)), a from the vis-viva equation.
    KeplerPeriod,
    /// Equilibrium: over the second half of the run each axis carries the same kinetic energy
    /// on average; the ratio of the largest to the smallest, predicted 1. Under a thermostat:
    /// the kinetic temperature 2⟨T⟩/N_f over the second half, predicted the bath's kT.
    Equipartition,
    /// Bounded motion: 2⟨T⟩ = −⟨Σ x·F⟩ over the run (the virial theorem); predicted ratio 1.
    /// Exact for time averages over whole periods, or long enough.
    Virial,
    /// A charge in a uniform magnetic field alone: T = 2π m / (|q| |B|), the cyclotron period.
    CyclotronPeriod,
    /// The same: the gyration radius m v⊥ / (|q| |B|), measured as half the extent of the orbit
    /// across the field once it has turned fully.
    CyclotronRadius,
    /// Statistical: at the end of the run the velocity components, relative to the centre of
    /// mass and scaled by √(m/T) at the measured kinetic temperature T (the bath's, under a
    /// thermostat), pass a Kolmogorov–Smirnov test against the standard normal distribution
    /// (p ≥ tol, 0.01 if not given).
    MaxwellBoltzmann,
    /// A dam break: the surge front z/a against Martin & Moyce (1952), at the times T = t√(2g/a)
    /// they measured (`MARTIN_MOYCE`); the measured value is the ratio simulated/measured
    /// farthest from 1, predicted 1. The column's scales are read from the bodies (`Column`).
    DamBreakFront,
}

/// Martin & Moyce (1952), "An experimental study of the collapse of liquid columns on a rigid
/// horizontal plane", Phil. Trans. R. Soc. A 244, 312–324, Table 2 (square column, n² = 2,
/// a = 2¼ in): the times T = t√(2g/a) at which the surge front reached Z = z/a, as tabulated in
/// the validation literature (the primary could not be consulted here).
pub const MARTIN_MOYCE: [(f64, f64); 15] = [
    (0.41, 1.11),
    (0.84, 1.22),
    (1.19, 1.44),
    (1.43, 1.67),
    (1.63, 1.89),
    (1.83, 2.11),
    (1.98, 2.33),
    (2.20, 2.56),
    (2.32, 2.78),
    (2.51, 3.00),
    (2.65, 3.22),
    (2.83, 3.44),
    (2.98, 3.67),
    (3.11, 3.89),
    (3.33, 4.11),
];

/// A dam break's scales, from the bodies' initial lattice: each body stands for a cube of the
/// lattice's spacing, so the column's back face is half a spacing behind the first body
/// (`back`), its width a is the bodies' extent plus one spacing, and the front is the farthest
/// body plus half a spacing (`reach`); g from the gravity term.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Column {
    pub back: f64,
    pub a: f64,
    pub g: f64,
    pub reach: f64,
}

impl Column {
    pub fn of(model: &Model, x0: &[[f64; 3]]) -> Result<Column, String> {
        if !model.terms.iter().any(|t| t.kind.spec().shape == Shape::Density) {
            return Err("needs a fluid (`sph`)".into());
        }
        let back = |t: &&lagra_checker::model::TermInstance| {
            t.kind == Kind::Wall && t.params[0] > 0.0 && t.params[1] == 0.0 && t.params[2] == 0.0
        };
        if !model.terms.iter().any(|t| back(&t)) {
            return Err("needs a back wall, a `wall` with normal +x".into());
        }
        let gravity: Vec<_> = model.terms.iter().filter(|t| t.kind == Kind::UniformAcceleration).collect();
        let g = match gravity.as_slice() {
            [t] if t.params[0] == 0.0 && t.params[2] == 0.0 && t.params[1] < 0.0 => -t.params[1],
            _ => return Err("needs one gravity term along −y".into()),
        };
        let mut xs: Vec<f64> = x0.iter().map(|x| x[0]).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        let spacing = xs.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
        if !spacing.is_finite() {
            return Err("needs a column of bodies at least two wide".into());
        }
        let (lo, hi) = (xs[0], xs[xs.len() - 1]);
        Ok(Column { back: lo - spacing / 2.0, a: hi - lo + spacing, g, reach: spacing / 2.0 })
    }

    /// The front z/a of bodies at `x`.
    pub fn front(&self, x: &[[f64; 3]]) -> f64 {
        (x.iter().fold(f64::NEG_INFINITY, |z, x| z.max(x[0])) + self.reach - self.back) / self.a
    }
}

#[derive(Clone, Debug)]
pub struct Prediction {
    pub kind: PredictionKind,
    /// The relative difference allowed between measured and predicted (for a statistical test,
    /// the least p-value); reported only if absent.
    pub tol: Option<f64>,
    /// The closed-form value; `None` for a statistical test.
    pub predicted: Option<f64>,
}

impl PredictionKind {
    pub const ALL: [PredictionKind; 8] = [
        PredictionKind::CyclotronRadius,
        PredictionKind::OscillatorPeriod,
        PredictionKind::KeplerPeriod,
        PredictionKind::Virial,
        PredictionKind::Equipartition,
        PredictionKind::CyclotronPeriod,
        PredictionKind::MaxwellBoltzmann,
        PredictionKind::DamBreakFront,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PredictionKind::OscillatorPeriod => "oscillator_period",
            PredictionKind::KeplerPeriod => "kepler_period",
            PredictionKind::Virial => "virial",
            PredictionKind::Equipartition => "equipartition",
            PredictionKind::CyclotronPeriod => "cyclotron_period",
            PredictionKind::CyclotronRadius => "cyclotron_radius",
            PredictionKind::MaxwellBoltzmann => "maxwell_boltzmann",
            PredictionKind::DamBreakFront => "dam_break_front",
        }
    }

    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// The predicted value (`None` for a statistical test), or why the prediction does not apply.
    pub fn predict(
        self,
        model: &Model,
        x0: &[[f64; 3]],
        v0: &[[f64; 3]],
        bath: Option<Bath>,
    ) -> Result<Option<f64>, String> {
        match (self, bath) {
            (PredictionKind::Equipartition, Some(b)) if model.bodies.len() >= 10 => Ok(Some(b.kt)),
            _ => self.closed_form(model, x0, v0),
        }
    }

    fn closed_form(self, model: &Model, x0: &[[f64; 3]], v0: &[[f64; 3]]) -> Result<Option<f64>, String> {
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
                    Ok(Some(TAU / w2.sqrt()))
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
                    Ok(Some(TAU * (inv_a.powi(-3) / mu).sqrt()))
                } else {
                    Err("the orbit is unbound: it has no period".into())
                }
            }
            PredictionKind::Virial if model.terms.iter().any(|t| t.dissipates() || t.kind == Kind::MagneticField) => {
                Err("needs conservative, position-dependent forces".into())
            }
            PredictionKind::Virial => Ok(Some(1.0)),
            PredictionKind::Equipartition if model.bodies.len() < 10 => Err("needs at least 10 bodies".into()),
            PredictionKind::Equipartition => Ok(Some(1.0)),
            PredictionKind::CyclotronPeriod | PredictionKind::CyclotronRadius => {
                let (b, body) = match (model.terms.as_slice(), model.bodies.as_slice()) {
                    ([t], [body]) if t.kind == Kind::MagneticField => {
                        (Vector3::new(t.params[0], t.params[1], t.params[2]), body)
                    }
                    _ => return Err("needs exactly one charged body and one magnetic field, nothing else".into()),
                };
                if body.charge == 0.0 || b.norm() == 0.0 {
                    return Err("the body is neutral or the field is zero: it does not gyrate".into());
                }
                let omega = body.charge.abs() * b.norm() / body.mass;
                let v = Vector3::from(v0[0]);
                let across = (v - b * (v.dot(&b) / b.norm_squared())).norm();
                Ok(Some(if self == PredictionKind::CyclotronPeriod { TAU / omega } else { across / omega }))
            }
            PredictionKind::MaxwellBoltzmann if model.bodies.len() < 10 => {
                Err("needs at least 10 bodies for a distribution to test".into())
            }
            PredictionKind::MaxwellBoltzmann => Ok(None),
            PredictionKind::DamBreakFront => Column::of(model, x0).map(|_| Some(1.0)),
        }
    }
}
