//! The invariants a scene may declare with `@expect`.

use crate::model::Model;
use crate::units::Dim;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClaimKind {
    /// |H − H₀| ≤ tol·|H₀| (relative); with dissipative terms, |H + Q − H₀| ≤ tol·|H₀|.
    EnergyConservation,
    /// Each claimed component of Σmv stays at its initial value within tol, or within a
    /// round-off budget when no tol is given.
    MomentumConservation,
    /// Each claimed component of Σm x×v, likewise.
    AngularMomentumConservation,
    /// Every term definition in the model is homogeneous and energy-valued.
    DimensionalConsistency,
    /// The distance between two bodies stays within [min, max] (at every checkpoint, step 0
    /// included).
    Distance,
    /// Every distance constraint holds: | |xⱼ − xᵢ| − length | ≤ tol·length (at every
    /// checkpoint, step 0 included).
    ConstraintSatisfied,
    /// From time `after` on, no point of any body moves faster than `tol` (a speed): |v| + |ω|ρ
    /// for a rigid body, ρ the reach of its solid.
    Resting,
    /// No two solids overlap, and nothing is below the floor, by more than `tol` (a length).
    NoPenetration,
    /// Every joint holds: each of its pins' two points are at most `tol` (a length) apart (at
    /// every checkpoint, step 0 included).
    JointSatisfied,
}

impl ClaimKind {
    pub const ALL: [ClaimKind; 9] = [
        ClaimKind::EnergyConservation,
        ClaimKind::MomentumConservation,
        ClaimKind::AngularMomentumConservation,
        ClaimKind::DimensionalConsistency,
        ClaimKind::Distance,
        ClaimKind::ConstraintSatisfied,
        ClaimKind::Resting,
        ClaimKind::NoPenetration,
        ClaimKind::JointSatisfied,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ClaimKind::EnergyConservation => "energy_conservation",
            ClaimKind::MomentumConservation => "momentum_conservation",
            ClaimKind::AngularMomentumConservation => "angular_momentum_conservation",
            ClaimKind::DimensionalConsistency => "dimensional_consistency",
            ClaimKind::Distance => "distance",
            ClaimKind::ConstraintSatisfied => "constraint_satisfied",
            ClaimKind::Resting => "resting",
            ClaimKind::NoPenetration => "no_penetration",
            ClaimKind::JointSatisfied => "joint_satisfied",
        }
    }

    pub fn from_name(name: &str) -> Option<ClaimKind> {
        ClaimKind::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether the claim is about the trajectory (checked at checkpoints) or the model alone.
    pub fn is_dynamic(self) -> bool {
        self != ClaimKind::DimensionalConsistency
    }

    /// Whether the claim compares each state with the first (a conservation law), rather than
    /// each state on its own.
    pub fn is_conservation(self) -> bool {
        matches!(
            self,
            ClaimKind::EnergyConservation | ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation
        )
    }

    /// The dimension of `tol`, for claims that take one: energy's and the constraints' are
    /// relative, the momenta's absolute.
    pub fn tol_dim(self) -> Option<Dim> {
        match self {
            ClaimKind::EnergyConservation | ClaimKind::ConstraintSatisfied => Some(Dim::NONE),
            ClaimKind::MomentumConservation => Some(Dim([1, 1, -1, 0])),
            ClaimKind::AngularMomentumConservation => Some(Dim([1, 2, -1, 0])),
            ClaimKind::Resting => Some(Dim::VELOCITY),
            ClaimKind::NoPenetration | ClaimKind::JointSatisfied => Some(Dim::LENGTH),
            ClaimKind::DimensionalConsistency | ClaimKind::Distance => None,
        }
    }

    /// Whether `tol` must be given (a relative tolerance has no natural default).
    pub fn needs_tol(self) -> bool {
        matches!(
            self,
            ClaimKind::EnergyConservation
                | ClaimKind::ConstraintSatisfied
                | ClaimKind::Resting
                | ClaimKind::NoPenetration
                | ClaimKind::JointSatisfied
        )
    }

    /// Whether the claim may be declared more than once (for different bodies).
    pub fn repeatable(self) -> bool {
        self == ClaimKind::Distance
    }
}

/// The two bodies of a distance claim and the interval their distance must stay in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Between {
    pub bodies: [usize; 2],
    pub min: f64,
    pub max: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    pub kind: ClaimKind,
    pub tol: Option<f64>,
    /// Check every `every`-th step (and always the first and the last).
    pub every: u64,
    /// For the momenta: which of the x, y, z components are claimed (all when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[bool; 3]>,
    /// For a distance claim: its bodies and bounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub between: Option<Between>,
    /// For a resting claim: the time from which it holds (0 when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after: Option<f64>,
}

impl Claim {
    pub fn new(kind: ClaimKind, tol: Option<f64>, every: u64) -> Claim {
        Claim { kind, tol, every, axes: None, between: None, after: None }
    }

    /// The claim as printed: `momentum_conservation`, `momentum_conservation(x, z)`,
    /// `distance(0, 1)`.
    pub fn label(&self) -> String {
        match (&self.axes, &self.between) {
            (_, Some(b)) => format!("{}({}, {})", self.kind.name(), b.bodies[0], b.bodies[1]),
            (Some(a), None) if a != &[true; 3] => {
                let names: Vec<&str> = ["x", "y", "z"].iter().zip(a).filter(|p| *p.1).map(|p| *p.0).collect();
                format!("{}({})", self.kind.name(), names.join(", "))
            }
            _ => self.kind.name().to_string(),
        }
    }

    /// The tolerance every checkpoint is held to when it does not depend on the states: the
    /// declared one, or 0 for a distance (whose deviation is how far it is outside its bounds).
    /// `None` means the round-off budget.
    pub fn fixed_tol(&self) -> Option<f64> {
        if self.kind == ClaimKind::Distance {
            Some(0.0)
        } else {
            self.tol
        }
    }

    /// Rejects a claim that does not fit its kind or the model.
    pub fn validate(&self, model: &Model) -> Result<(), String> {
        let bodies = model.bodies.len();
        let name = self.label();
        if self.kind == ClaimKind::ConstraintSatisfied && model.constraints.is_empty() {
            return Err(format!("{name}: the model has no constraint"));
        }
        if self.kind == ClaimKind::JointSatisfied && model.pins.is_empty() {
            return Err(format!("{name}: the model has no joint"));
        }
        if self.kind.needs_tol() && self.tol.is_none() {
            return Err(format!("{name} needs a tolerance"));
        }
        if self.every == 0 {
            return Err(format!("{name}: every must be at least 1"));
        }
        if self.kind == ClaimKind::NoPenetration
            && model.floor.is_none()
            && model.bodies.iter().filter(|b| b.solid.is_some()).count() < 2
        {
            return Err(format!("{name}: the model has no floor and fewer than two solids"));
        }
        if self.after.is_some_and(|t| !(t.is_finite() && t >= 0.0))
            || (self.after.is_some() && self.kind != ClaimKind::Resting)
        {
            return Err(format!("{name}: `after` is a time ≥ 0, and only a resting claim takes one"));
        }
        if self.tol.is_some_and(|t| !(t.is_finite() && t > 0.0))
            || (self.tol.is_some() && self.kind.tol_dim().is_none())
        {
            return Err(format!("{name}: a tolerance must be finite and positive, and only where the claim takes one"));
        }
        let momentum = matches!(self.kind, ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation);
        match &self.axes {
            Some(a) if !momentum || a == &[false; 3] => {
                return Err(format!("{name}: axes must name a component of a momentum"))
            }
            _ => {}
        }
        match (&self.between, self.kind == ClaimKind::Distance) {
            (Some(b), true) => {
                if b.bodies.iter().any(|&i| i >= bodies) || b.bodies[0] == b.bodies[1] {
                    return Err(format!("{name}: needs two different bodies of the {bodies}"));
                }
                if !(b.min.is_finite() && b.max.is_finite() && 0.0 <= b.min && b.min <= b.max) {
                    return Err(format!("{name}: needs 0 ≤ min ≤ max, finite"));
                }
            }
            (None, false) => {}
            _ => return Err(format!("{name}: `between` belongs to a distance claim, and a distance claim needs it")),
        }
        Ok(())
    }
}
