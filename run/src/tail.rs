//! Long-range ("tail") corrections: the share of a cut-off pair term beyond its cutoff, taking
//! the bodies as evenly spread there (g(r) = 1), worked out from the term's own definition with
//! its cutoff removed:
//!
//!   U_tail/N = 2πρ ∫_rc^∞ r² V(r) dr,    P_tail = −(2π/3) ρ² ∫_rc^∞ r³ V′(r) dr.
//!
//! For Lennard-Jones these are the textbook closed forms (a test holds them together). A term
//! whose potential reads the bodies' masses, charges or colours has no single V(r) for every
//! pair and is refused, as is one whose integrals do not converge (a tail decaying like r⁻³ or
//! slower).

use lagra_checker::model::Model;
use lagra_checker::terms::{Kind, Shape};
use lagra_kernel::derivatives::exact::along;
use serde::Serialize;

/// Per body of energy, and of pressure, at the model's density.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Tail {
    pub energy_per_body: f64,
    pub pressure: f64,
}

impl Tail {
    /// The tail of every pair term of the model with a finite reach, in its periodic box.
    pub fn of(model: &Model) -> Result<Tail, String> {
        let cell = model
            .cell
            .filter(|c| c.periodic == [true; 3])
            .ok_or("tail corrections need a box periodic along every axis")?;
        let rho = model.bodies.len() as f64 / cell.size.iter().product::<f64>();
        let mut tail = Tail { energy_per_body: 0.0, pressure: 0.0 };
        for t in model.terms.iter().filter(|t| t.kind.spec().shape == Shape::Pairwise) {
            let rc = t.kind.reach(&t.params);
            if rc.is_infinite() {
                continue;
            }
            let reads = t.kind.reads();
            if reads.m || reads.q || reads.colour {
                return Err(format!(
                    "tail corrections: {} depends on the bodies' masses, charges or colours, so it has no one V(r) for every pair",
                    t.kind.name()
                ));
            }
            let (u, p) = integrals(t.kind, &uncut(t.kind, &t.params), rc)?;
            tail.energy_per_body += 2.0 * std::f64::consts::PI * rho * u;
            tail.pressure -= 2.0 / 3.0 * std::f64::consts::PI * rho * rho * p;
        }
        Ok(tail)
    }
}

/// The parameters with the cutoff, if the term has one, moved past any distance the quadrature
/// visits (not to infinity: a shift's derivative would then be 0·∞).
fn uncut(kind: Kind, params: &[f64]) -> Vec<f64> {
    let mut p = params.to_vec();
    let mut at = 0;
    for param in kind.spec().params {
        if param.name == "cutoff" {
            p[at] = 1e100;
        }
        at += param.len;
    }
    p
}

/// ∫_rc^∞ r² V dr and ∫_rc^∞ r³ V′ dr, by Gauss–Legendre on u = rc/r ∈ (0, 1] (the integrands
/// then vanish at u → 0 for any tail faster than r⁻³), checked converged by halving the panels.
fn integrals(kind: Kind, p: &[f64], rc: f64) -> Result<(f64, f64), String> {
    let at = |panels: usize| {
        let (mut u_sum, mut p_sum) = (0.0, 0.0);
        for k in 0..panels {
            let (a, b) = (k as f64 / panels as f64, (k + 1) as f64 / panels as f64);
            for (x, w) in GAUSS {
                let u = 0.5 * (a + b) + 0.5 * (b - a) * x;
                let r = rc / u;
                let (v, dv) = along(kind, p, [1.0, 1.0, 0.0, 0.0], [[0.0; 2]; 2], r);
                // dr = rc/u² du
                let jacobian = 0.5 * (b - a) * w * rc / (u * u);
                u_sum += jacobian * r * r * v;
                p_sum += jacobian * r * r * r * dv;
            }
        }
        (u_sum, p_sum)
    };
    let (coarse, fine) = (at(200), at(400));
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-300) && b.is_finite();
    if !(close(coarse.0, fine.0) && close(coarse.1, fine.1)) {
        return Err(format!(
            "tail corrections: the integral of {} beyond its cutoff does not converge (it decays like r⁻³ or slower)",
            kind.name()
        ));
    }
    Ok(fine)
}

/// Five-point Gauss–Legendre nodes and weights on [−1, 1].
const GAUSS: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile;
    use std::f64::consts::PI;

    fn liquid(term: &str) -> Result<Tail, String> {
        let s = compile(&format!(
            "scene t {{ entity atom {{ mass: 1 }}
               lattice {{ type: atom, density: 0.86, cells: [5, 5, 5] }}
               {term}
               solver {{ dt: 0.005, steps: 1 }} }}"
        ))
        .map_err(|d| d.message)?;
        Tail::of(&s.model)
    }

    /// Lennard-Jones: U_tail/N = (8/3)πρεσ³[(σ/rc)⁹/3 − (σ/rc)³],
    /// P_tail = (16/3)πρ²εσ³[(2/3)(σ/rc)⁹ − (σ/rc)³]; the same for the shifted forms (their
    /// tail is the plain potential's beyond the cutoff) and nothing for WCA.
    #[test]
    fn lennard_jones_has_its_closed_form() {
        let (rho, eps, sigma, rc): (f64, f64, f64, f64) = (0.86, 1.3, 1.1, 3.0);
        let s = sigma / rc;
        let u = 8.0 / 3.0 * PI * rho * eps * sigma.powi(3) * (s.powi(9) / 3.0 - s.powi(3));
        let p = 16.0 / 3.0 * PI * rho * rho * eps * sigma.powi(3) * (2.0 / 3.0 * s.powi(9) - s.powi(3));
        for kind in ["lj", "lj_shifted", "lj_force_shifted"] {
            let t = liquid(&format!("interaction {kind} {{ epsilon: {eps}, sigma: {sigma}, cutoff: {rc} }}")).unwrap();
            assert!((t.energy_per_body / u - 1.0).abs() < 1e-10, "{kind}: {} vs {u}", t.energy_per_body);
            assert!((t.pressure / p - 1.0).abs() < 1e-10, "{kind}: {} vs {p}", t.pressure);
        }
        let wca = liquid("interaction wca { epsilon: 1, sigma: 1 }").unwrap();
        assert_eq!((wca.energy_per_body, wca.pressure), (0.0, 0.0));
    }

    #[test]
    fn a_term_with_no_one_potential_is_refused() {
        let e = liquid("interaction coulomb_rf { k: 1, cutoff: 2.0 }").unwrap_err();
        assert!(e.contains("charges"), "{e}");
    }
}
