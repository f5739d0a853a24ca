//! The invariants a scene may declare with `@expect`.

use crate::units::Dim;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClaimKind {
    /// |H − H₀| ≤ tol·|H₀| (relative); with dissipative terms, |H + Q − H₀| ≤ tol·|H₀|.
    EnergyConservation,
    /// Every component of Σmv stays at its initial value within tol, or within a round-off
    /// budget when no tol is given.
    MomentumConservation,
    /// Every component of Σm x×v, likewise.
    AngularMomentumConservation,
    /// Every term definition in the model is homogeneous and energy-valued.
    DimensionalConsistency,
}

impl ClaimKind {
    pub const ALL: [ClaimKind; 4] = [
        ClaimKind::EnergyConservation,
        ClaimKind::MomentumConservation,
        ClaimKind::AngularMomentumConservation,
        ClaimKind::DimensionalConsistency,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ClaimKind::EnergyConservation => "energy_conservation",
            ClaimKind::MomentumConservation => "momentum_conservation",
            ClaimKind::AngularMomentumConservation => "angular_momentum_conservation",
            ClaimKind::DimensionalConsistency => "dimensional_consistency",
        }
    }

    pub fn from_name(name: &str) -> Option<ClaimKind> {
        ClaimKind::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether the claim is about the trajectory (checked at checkpoints) or the model alone.
    pub fn is_dynamic(self) -> bool {
        self != ClaimKind::DimensionalConsistency
    }

    /// The dimension of `tol`: energy's is relative, momentum's absolute.
    pub fn tol_dim(self) -> Option<Dim> {
        match self {
            ClaimKind::EnergyConservation => Some(Dim::NONE),
            ClaimKind::MomentumConservation => Some(Dim([1, 1, -1, 0])),
            ClaimKind::AngularMomentumConservation => Some(Dim([1, 2, -1, 0])),
            ClaimKind::DimensionalConsistency => None,
        }
    }

    /// Whether `tol` must be given (a relative energy tolerance has no natural default).
    pub fn needs_tol(self) -> bool {
        self == ClaimKind::EnergyConservation
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    pub kind: ClaimKind,
    pub tol: Option<f64>,
    /// Check every `every`-th step (and always the first and the last).
    pub every: u64,
}
