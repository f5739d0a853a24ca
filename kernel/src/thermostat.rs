//! Thermostats: what holds a scene at a temperature (declared in `lagra_lang::thermostat`). A
//! Nosé–Hoover chain is more Lagrangian — links with their own kinetic and potential energy, in
//! the model where the checker sees them (`lagra_checker::thermostat::Chain`) — and its
//! half-step propagation is here. A Langevin bath
//! is friction and noise; its noise is drawn per (seed, step, body, axis) by a counter-based
//! generator, so a run is the same bits for a seed on any number of threads.

use crate::state::State;
use lagra_checker::thermostat::Chain;
use lagra_lang::random::normal;

/// Suzuki–Yoshida fourth-order weights: three sub-steps per chain half-step.
const WEIGHTS: [f64; 3] = [1.351_207_191_959_657_8, -1.702_414_383_919_315_3, 1.351_207_191_959_657_8];

/// Advances the chain and scales the velocities by it for `h` (half a step), by the
/// Martyna–Tuckerman–Klein splitting: links' velocities from the last inwards, the bodies'
/// velocities scaled by exp(−ξ₁·δ), the links' positions, the links' velocities outwards. It
/// is time-reversible, and with velocity Verlet between two of them conserves H′ to O(dt²).
pub fn nose_hoover_half(chain: &Chain, s: &mut State, masses: &[f64], h: f64) {
    let kinetic = crate::state::kinetic(s, masses);
    let scale = chain_half(chain, &mut s.chain, kinetic, h);
    s.v.iter_mut().flatten().for_each(|c| *c *= scale);
}

/// The chain's half-step alone, given the bodies' kinetic energy: the links advanced, and the
/// factor the bodies' velocities are to be scaled by. A run cut into domains sums the kinetic
/// energy over the ranks and scales each rank's own atoms.
pub fn chain_half(chain: &Chain, links: &mut [[f64; 2]], kinetic: f64, h: f64) -> f64 {
    let (kt, q) = (chain.kt, &chain.masses);
    let last = q.len() - 1;
    let mut twice_kinetic = 2.0 * kinetic;
    let force = |j: usize, links: &[[f64; 2]], twice_kinetic: f64| {
        if j == 0 {
            (twice_kinetic - chain.dof * kt) / q[0]
        } else {
            (q[j - 1] * links[j - 1][1] * links[j - 1][1] - kt) / q[j]
        }
    };
    let mut scale = 1.0;
    for w in WEIGHTS {
        let d = w * h;
        // a link's velocity, damped by the next link's for a quarter on each side of its kick
        let kick = |links: &mut [[f64; 2]], j: usize, g: f64| {
            let damp = if j < last { libm::exp(-0.25 * d * links[j + 1][1]) } else { 1.0 };
            links[j][1] = (links[j][1] * damp + 0.5 * d * g) * damp;
        };
        for j in (0..=last).rev() {
            let g = force(j, links, twice_kinetic);
            kick(links, j, g);
        }
        let a = libm::exp(-d * links[0][1]);
        scale *= a;
        twice_kinetic *= a * a;
        links.iter_mut().for_each(|l| l[0] += d * l[1]);
        for j in 0..=last {
            let g = force(j, links, twice_kinetic);
            kick(links, j, g);
        }
    }
    scale
}

/// The O of BAOAB over `dt`: each body's velocity relaxed towards the bath's and kicked by its
/// noise, drawn for the body's number in the scene (`number` of its place in `v`: a rank of a run
/// cut into domains holds some bodies, and draws for each what one process would).
pub fn langevin_bath(
    v: &mut [[f64; 3]],
    inverse_masses: &[f64],
    number: impl Fn(usize) -> usize,
    (kt, gamma, seed): (f64, f64, u64),
    step: u64,
    dt: f64,
) {
    let c1 = libm::exp(-gamma * dt);
    let c2 = libm::sqrt(1.0 - c1 * c1);
    for (k, (v, w)) in v.iter_mut().zip(inverse_masses).enumerate() {
        let (sigma, i) = (c2 * libm::sqrt(kt * w), number(k));
        for (c, vc) in v.iter_mut().enumerate() {
            *vc = c1 * *vc + sigma * normal(seed, step, 3 * i as u64 + c as u64);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, Model, UnitSystem};
    use lagra_lang::thermostat::chain;

    fn gas(n: usize) -> (Model, State) {
        let model = Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![Body { mass: 1.5, charge: 0.0, colour: [0.0; 2], moments: None, solid: None }; n],
            terms: vec![],
            constraints: vec![],
            thermostat: Some(chain(0.8, 0.5, 3, 3.0 * n as f64 - 3.0)),
            floor: None,
            pins: vec![],
        };
        let v = (0..n as u64)
            .map(|i| std::array::from_fn(|c| lagra_lang::random::normal(1, 0, 3 * i + c as u64)))
            .collect();
        (model, State { step: 0, t: 0.0, x: vec![[0.0; 3]; n], v, chain: vec![[0.0; 2]; 3], spin: vec![] })
    }

    /// The half-step conserves the chain's extended energy to the splitting's order (there is no
    /// potential: T + the chain's share): the error falls sixteen-fold when h halves (Suzuki–
    /// Yoshida's fourth order); and undoing it (ξ → −ξ) comes back to round-off.
    #[test]
    fn the_half_step_keeps_h_prime_to_fourth_order_and_is_reversible() {
        let (model, start) = gas(50);
        let c = model.thermostat.clone().unwrap();
        let m = vec![1.5; 50];
        let h = |s: &State| crate::state::kinetic(s, &m) + c.energy(&s.chain, &0.0);
        let drift = |step: f64| {
            let mut s = start.clone();
            for _ in 0..(2.0 / step).round() as usize {
                nose_hoover_half(&c, &mut s, &m, step);
            }
            ((h(&s) - h(&start)) / h(&start)).abs()
        };
        let (coarse, fine) = (drift(0.04), drift(0.02));
        assert!(coarse < 1e-3 && coarse / fine > 12.0, "{coarse:e} then {fine:e}");
        let mut s = start.clone();
        for _ in 0..200 {
            nose_hoover_half(&c, &mut s, &m, 0.01);
        }
        assert_ne!(s.v, start.v, "the chain did something");
        s.chain.iter_mut().for_each(|l| l[1] = -l[1]);
        for _ in 0..200 {
            nose_hoover_half(&c, &mut s, &m, 0.01);
        }
        s.chain.iter_mut().for_each(|l| l[1] = -l[1]);
        for (a, b) in s.v.iter().flatten().zip(start.v.iter().flatten()) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        // η sums 600 increments: its round-off is that of the sum
        for (a, b) in s.chain.iter().flatten().zip(start.chain.iter().flatten()) {
            assert!((a - b).abs() < 1e-10, "{a} vs {b}");
        }
    }

    /// A gas that starts hot relaxes towards the bath: its kinetic temperature moves to kT.
    #[test]
    fn a_hot_gas_cools_towards_the_bath() {
        let (model, mut s) = gas(200);
        let c = model.thermostat.clone().unwrap();
        let m = vec![1.5; 200];
        s.v.iter_mut().flatten().for_each(|v| *v *= 3.0);
        let temperature = |s: &State| 2.0 * crate::state::kinetic(s, &m) / c.dof;
        assert!(temperature(&s) > 2.0);
        let mut low = f64::INFINITY;
        for _ in 0..4000 {
            nose_hoover_half(&c, &mut s, &m, 0.005);
            low = low.min(temperature(&s));
        }
        assert!(low < 0.8, "the kinetic temperature came down to {low}, not to the bath's 0.8");
    }
}
