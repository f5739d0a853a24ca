//! The thermostat a scene declares, and what it means before any step: the temperature it
//! holds over which degrees of freedom, and a Nosé–Hoover chain's links. Its propagation is the
//! kernel's (`lagra_kernel::thermostat`).

use lagra_checker::model::Model;
use lagra_checker::terms::Shape;
use lagra_checker::thermostat::Chain;

/// The thermostat a scene declares.
#[derive(Clone, Debug, PartialEq)]
pub enum Thermostat {
    /// A Nosé–Hoover chain relaxing over `tau`; the chain itself (kT, the degrees of freedom,
    /// the links' masses) is the model's (`Model::thermostat`).
    NoseHoover { tau: f64 },
    /// Langevin dynamics at k_B·T = `kt` with friction `gamma` (per time), noise from `seed`.
    Langevin { kt: f64, gamma: f64, seed: u64 },
}

impl Thermostat {
    pub fn name(&self) -> &'static str {
        match self {
            Thermostat::NoseHoover { .. } => "nose_hoover",
            Thermostat::Langevin { .. } => "langevin",
        }
    }
}

/// The temperature a thermostat holds, over the degrees of freedom it thermalizes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bath {
    pub kt: f64,
    pub dof: f64,
}

impl Bath {
    pub fn of(t: &Thermostat, model: &Model) -> Bath {
        match (t, &model.thermostat) {
            (Thermostat::NoseHoover { .. }, Some(c)) => Bath { kt: c.kt, dof: c.dof },
            (Thermostat::Langevin { kt, .. }, _) => Bath { kt: *kt, dof: 3.0 * model.bodies.len() as f64 },
            (Thermostat::NoseHoover { .. }, None) => unreachable!("a Nosé–Hoover scene's model holds its chain"),
        }
    }
}

/// The kinetic degrees of freedom a chain thermalizes: 3N, less the three of the centre of mass
/// when every term is internal (bonds and pairs: the total momentum is then conserved, and the
/// chain, which scales every velocity alike, keeps it at zero).
pub fn degrees_of_freedom(model: &Model) -> f64 {
    let n = 3.0 * model.bodies.len() as f64;
    let internal = model.terms.iter().all(|t| t.kind.spec().shape != Shape::External);
    if internal {
        n - 3.0
    } else {
        n
    }
}

/// A chain of `links` for `tau`: Q₁ = N_f·kT·τ², Q_j = kT·τ² (Martyna, Tuckerman & Klein 1996).
pub fn chain(kt: f64, tau: f64, links: usize, dof: f64) -> Chain {
    let q = kt * tau * tau;
    Chain { kt, dof, masses: (0..links).map(|j| if j == 0 { dof * q } else { q }).collect() }
}
