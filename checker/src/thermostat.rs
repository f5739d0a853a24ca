//! The Nosé–Hoover chain: a thermostat that is itself a piece of Lagrangian. Its links are
//! degrees of freedom of the state (positions η_j, velocities ξ_j), and the extended energy
//!
//!   H' = T + V + Σ_j ½ Q_j ξ_j² + N_f kT η_1 + kT Σ_{j≥2} η_j
//!
//! is conserved by the chain's equations of motion (Martyna, Klein & Tuckerman 1992), so the
//! energy claim of a thermostatted run is a claim about H', certified like H.

use crate::real::Real;
use serde::{Deserialize, Serialize};

/// A chain of `masses.len()` links at temperature `kt` (k_B·T, an energy), coupled to `dof`
/// degrees of freedom of the bodies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Chain {
    pub kt: f64,
    pub dof: f64,
    /// Q_j, the links' inertias (energy × time²).
    pub masses: Vec<f64>,
}

impl Chain {
    /// The chain's share of H': its links' kinetic energy and the potential that couples the
    /// first link to the bodies' degrees of freedom and each later link to the one before.
    /// `links[j]` is (η_j, ξ_j).
    pub fn energy<R: Real>(&self, links: &[[R; 2]], zero: &R) -> R {
        let (half, kt) = (zero.lift(0.5), zero.lift(self.kt));
        links.iter().zip(&self.masses).enumerate().fold(zero.clone(), |acc, (j, ([eta, xi], &q))| {
            let coupled = if j == 0 { zero.lift(self.dof) * kt.clone() } else { kt.clone() };
            acc + half.clone() * zero.lift(q) * xi.clone() * xi.clone() + coupled * eta.clone()
        })
    }

    /// Rejects a chain its energy cannot be evaluated for.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.kt)
            || !positive(self.dof)
            || self.masses.is_empty()
            || !self.masses.iter().all(|&q| positive(q))
        {
            return Err(format!(
                "thermostat: kT, the degrees of freedom and every link's mass must be finite and positive, got kT {}, {} degrees of freedom, masses {:?}",
                self.kt, self.dof, self.masses
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosure::Enclosure;
    use crate::outward::Outward;
    use rug::Float;

    fn chain() -> Chain {
        Chain { kt: 0.85, dof: 1497.0, masses: vec![12.0, 0.03, 0.03] }
    }

    #[test]
    fn energy_is_the_extended_share() {
        let links = [[0.1, -0.2], [0.3, 0.5], [-0.7, 2.0]];
        let want =
            0.5 * 12.0 * 0.04 + 1497.0 * 0.85 * 0.1 + 0.5 * 0.03 * 0.25 + 0.85 * 0.3 + 0.5 * 0.03 * 4.0 - 0.85 * 0.7;
        let got = chain().energy(&links, &0.0);
        assert!((got - want).abs() < 1e-12 * want.abs(), "{got} vs {want}");
    }

    #[test]
    fn the_enclosure_holds_the_exact_value() {
        let links = [[0.1, -0.2], [0.3, 0.5], [-0.7, 2.0]];
        let iv = chain().energy(&links.map(|l| l.map(Outward::point)), &Outward::point(0.0));
        let exact = chain().energy(&links.map(|l| l.map(|c| Float::with_val(512, c))), &Float::new(512));
        let (lo, hi) = iv.bounds();
        assert!(lo <= exact && exact <= hi, "{lo} {exact} {hi}");
    }

    #[test]
    fn a_chain_at_no_temperature_is_refused() {
        assert!(Chain { kt: 0.0, ..chain() }.validate().is_err());
        assert!(Chain { masses: vec![], ..chain() }.validate().is_err());
        assert!(Chain { masses: vec![1.0, f64::NAN], ..chain() }.validate().is_err());
        assert!(chain().validate().is_ok());
    }
}
