//! Rigid bodies in SE(3): a body's pose (centre of mass and orientation, a unit quaternion from
//! the body frame to the world) and the free rigid body's symplectic step. Its shape, principal
//! moments and initial spin are the scene's (`lagra_lang::shape`).
//!
//! The body frame is the principal frame (a box's edges, any frame for a sphere), so the inertia
//! is the diagonal `moments` and the body-frame angular momentum π gives ω = π / I per axis. No
//! term of the vocabulary exerts a torque yet (fields act through the centre of mass), so a
//! body's rotation is free and commutes with everything else a step does: the stepper turns the
//! rigid bodies after the translational step (`LagrangianGraph::turn`).

pub use lagra_lang::shape::Spin;
use nalgebra::{UnitQuaternion, Vector3};

fn orientation(s: &Spin) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(s[0], s[1], s[2], s[3]))
}

fn pi(s: &Spin) -> Vector3<f64> {
    Vector3::new(s[4], s[5], s[6])
}

/// ½ Σ π_k² / I_k.
pub fn rotational_energy(s: &Spin, moments: Vector3<f64>) -> f64 {
    0.5 * pi(s).dot(&pi(s).component_div(&moments))
}

/// The angular momentum about the centre of mass in the world frame, q π.
pub fn angular_momentum(s: &Spin) -> Vector3<f64> {
    orientation(s) * pi(s)
}

/// ω in the body frame, π / I.
pub fn omega(s: &Spin, moments: Vector3<f64>) -> Vector3<f64> {
    pi(s).component_div(&moments)
}

/// Free rotation over `h`, by the splitting of Dullweber, Leimkuhler and McLachlan (J. Chem.
/// Phys. 107, 5840, 1997): the kinetic energy split by axis, T = T₁ + T₂ + T₃, each part's flow
/// an exact rotation about its body axis, composed symmetrically: R₁(h/2) R₂(h/2) R₃(h) R₂(h/2)
/// R₁(h/2). Each rotation keeps the world angular momentum and |π| exactly (in exact
/// arithmetic), the composition is symplectic and time-reversible, and its energy error is
/// O(h²) and bounded.
pub fn free_step(s: &mut Spin, moments: Vector3<f64>, h: f64) {
    let (mut q, mut p) = (orientation(s), pi(s));
    for (k, share) in [(0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)] {
        // the flow of T_k = π_k² / 2I_k: the body turns by θ = h π_k / I_k about its axis k, so
        // π, seen from the turned body, turns by −θ, and q π stays
        let theta = share * h * p[k] / moments[k];
        let axis = Vector3::ith_axis(k);
        p = UnitQuaternion::from_axis_angle(&axis, -theta) * p;
        q *= UnitQuaternion::from_axis_angle(&axis, theta);
    }
    // renormalised, so that rounding does not let |q| wander over a long run
    let q = q.quaternion().normalize();
    *s = [q.w, q.i, q.j, q.k, p[0], p[1], p[2]];
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_lang::shape::spin_of;
    use proptest::prelude::*;

    /// The period of the body-frame angular momentum of a torque-free body (Landau and Lifshitz,
    /// Mechanics §37), from its moments (distinct, any order), |L|² and 2T: π returns after
    /// T = 4K(k) √(I₁I₂I₃ / ((I₃ − I₂)(L² − 2E I₁))), k² = (I₂ − I₁)(2E I₃ − L²) / ((I₃ − I₂)(L² − 2E I₁)),
    /// with I₁ < I₂ < I₃ ordered so that L² > 2E I₂ (else I₁ and I₃ swap roles). Near the
    /// intermediate axis this is the time between two of its flips and back.
    fn free_period(moments: Vector3<f64>, l2: f64, two_e: f64) -> f64 {
        let mut i = [moments[0], moments[1], moments[2]];
        i.sort_by(f64::total_cmp);
        if l2 < two_e * i[1] {
            i.swap(0, 2);
        }
        let [i1, i2, i3] = i;
        let k2 = (i2 - i1) * (two_e * i3 - l2) / ((i3 - i2) * (l2 - two_e * i1));
        4.0 * elliptic_k(k2) * (i1 * i2 * i3 / ((i3 - i2) * (l2 - two_e * i1))).sqrt()
    }

    /// The complete elliptic integral of the first kind K(m), m = k² < 1, by the arithmetic-geometric
    /// mean: K = π / (2 AGM(1, √(1 − m))).
    fn elliptic_k(m: f64) -> f64 {
        let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
        while (a - b).abs() > 1e-15 * a {
            (a, b) = (0.5 * (a + b), (a * b).sqrt());
        }
        std::f64::consts::PI / (2.0 * a)
    }

    const MOMENTS: [f64; 3] = [1.0, 2.0, 3.0];

    fn spinning(pi: [f64; 3]) -> Spin {
        let q = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.3).into_inner();
        [q.w, q.i, q.j, q.k, pi[0], pi[1], pi[2]]
    }

    #[test]
    fn a_spin_holds_the_angular_velocity_it_was_given() {
        let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.7);
        let w = Vector3::new(0.1, -2.0, 0.5);
        let s = spin_of(q, w, Vector3::from(MOMENTS));
        assert!((q * omega(&s, Vector3::from(MOMENTS)) - w).norm() < 1e-15);
    }

    /// The world angular momentum is the same to round-off after 100,000 steps: every sub-flow
    /// is a rotation that keeps it.
    #[test]
    fn angular_momentum_stays() {
        let mut s = spinning([0.3, 2.0, -0.7]);
        let l0 = angular_momentum(&s);
        for _ in 0..100_000 {
            free_step(&mut s, Vector3::from(MOMENTS), 0.01);
        }
        assert!((angular_momentum(&s) - l0).norm() < 1e-11 * l0.norm(), "{:e}", (angular_momentum(&s) - l0).norm());
    }

    /// The energy error is second order: a quarter when the step halves (the error's maximum
    /// over the same span of time), and it does not drift.
    #[test]
    fn energy_error_is_second_order_and_bounded() {
        let worst = |h: f64, steps: usize| {
            let mut s = spinning([0.3, 2.0, -0.7]);
            let e0 = rotational_energy(&s, Vector3::from(MOMENTS));
            (0..steps).fold(0.0f64, |w, _| {
                free_step(&mut s, Vector3::from(MOMENTS), h);
                w.max((rotational_energy(&s, Vector3::from(MOMENTS)) - e0).abs() / e0)
            })
        };
        let (coarse, fine) = (worst(0.02, 5_000), worst(0.01, 10_000));
        let ratio = coarse / fine;
        assert!((3.6..4.4).contains(&ratio), "ratio {ratio}, {coarse:e} {fine:e}");
        // no drift: the worst error over ten times as long is no worse than a few times
        assert!(worst(0.02, 50_000) < 1.5 * coarse);
    }

    /// The intermediate-axis (Dzhanibekov) flip: spun mostly about its middle axis, the body
    /// turns its ω₂ over and back with the period Landau and Lifshitz give (measured 37.006
    /// against 37.00598).
    #[test]
    fn the_intermediate_axis_flips_at_its_period() {
        let moments = Vector3::from(MOMENTS);
        let mut s = spinning([0.02, 2.0, 0.01]);
        let period = free_period(moments, pi(&s).norm_squared(), 2.0 * rotational_energy(&s, moments));
        let h = 1e-3;
        // the times ω₂ changes sign, up to a step
        let (mut flips, mut last, mut t) = (vec![], omega(&s, moments)[1], 0.0);
        while flips.len() < 5 {
            free_step(&mut s, moments, h);
            t += h;
            let w = omega(&s, moments)[1];
            if w.signum() != last.signum() {
                flips.push(t);
            }
            last = w;
        }
        // two sign changes a period
        let measured = flips[4] - flips[2];
        assert!((measured - period).abs() < 1e-3 * period, "flip period {measured}, analytic {period}");
        assert!(period > 10.0, "a slow flip: {period}");
    }

    proptest! {
        /// Any body, any spin: the step keeps |π| and the world angular momentum to round-off,
        /// and q stays a unit quaternion.
        #[test]
        fn rotations_keep_what_they_must(
            moments in prop::array::uniform3(0.1f64..5.0), p in prop::array::uniform3(-3.0f64..3.0), h in 1e-4f64..0.05,
        ) {
            let mut s = spinning(p);
            let (l0, p0) = (angular_momentum(&s), pi(&s).norm());
            for _ in 0..200 {
                free_step(&mut s, Vector3::from(moments), h);
            }
            let scale = 1e-13 * (1.0 + p0) * 200.0;
            prop_assert!((angular_momentum(&s) - l0).norm() < scale);
            prop_assert!((pi(&s).norm() - p0).abs() < scale);
            prop_assert!((orientation(&s).quaternion().norm() - 1.0).abs() < 1e-15);
        }
    }
}
