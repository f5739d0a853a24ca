//! Rigid bodies in SE(3), first layer (issue 26): a body's pose (centre of mass and orientation,
//! a unit quaternion from the body frame to the world), its principal moments from its shape
//! and mass, and the free rigid body's symplectic step. Not yet a vertex kind of the graph: the
//! language, the contact solver and the checker's claims build on this.
//!
//! The body frame is the principal frame (a box's edges, any frame for a sphere), so the inertia
//! is the diagonal `moments` and the body-frame angular momentum π gives ω = π / I per axis.

use nalgebra::{UnitQuaternion, Vector3};

/// What a rigid body is shaped as; its mass is uniform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// Edge lengths a, b, c along the body axes.
    Cuboid([f64; 3]),
    Sphere(f64),
}

impl Shape {
    /// The principal moments about the centre of mass: m(b² + c²)/12 and its turns for a box,
    /// 2mr²/5 for a sphere. A size or mass that is not positive and finite is an error.
    pub fn moments(&self, mass: f64) -> Result<Vector3<f64>, String> {
        let positive = |what: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(v)
            } else {
                Err(format!("{what} must be positive and finite, not {v}"))
            }
        };
        let m = positive("a rigid body's mass", mass)?;
        Ok(match *self {
            Shape::Cuboid(size) => {
                let [a, b, c] = [0, 1, 2].map(|k| positive("a box's edge length", size[k]));
                let [a, b, c] = [a?, b?, c?];
                Vector3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (m / 12.0)
            }
            Shape::Sphere(r) => Vector3::repeat(0.4 * m * positive("a sphere's radius", r)?.powi(2)),
        })
    }
}

/// One rigid body's state: where it is and how it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Rigid {
    pub mass: f64,
    /// Principal moments (body frame).
    pub moments: Vector3<f64>,
    /// Centre of mass and its velocity (world frame).
    pub x: Vector3<f64>,
    pub v: Vector3<f64>,
    /// Body frame to world frame.
    pub q: UnitQuaternion<f64>,
    /// Angular momentum in the body frame, π = I ω.
    pub pi: Vector3<f64>,
}

impl Rigid {
    /// ω in the body frame.
    pub fn omega(&self) -> Vector3<f64> {
        self.pi.component_div(&self.moments)
    }

    /// Angular momentum about the centre of mass, in the world frame: q π.
    pub fn angular_momentum(&self) -> Vector3<f64> {
        self.q * self.pi
    }

    /// ½ m |v|² + ½ Σ π_k² / I_k.
    pub fn kinetic(&self) -> f64 {
        0.5 * self.mass * self.v.norm_squared() + 0.5 * self.pi.dot(&self.omega())
    }

    /// Free motion over `h`: the centre drifts, the body turns by the splitting of Dullweber,
    /// Leimkuhler and McLachlan (J. Chem. Phys. 107, 5840, 1997) — the kinetic energy split by
    /// axis, T = T₁ + T₂ + T₃, each part's flow an exact rotation about its body axis, composed
    /// symmetrically: R₁(h/2) R₂(h/2) R₃(h) R₂(h/2) R₁(h/2). Each rotation keeps the world
    /// angular momentum and |π| exactly (in exact arithmetic), the composition is symplectic
    /// and time-reversible, and its energy error is O(h²) and bounded.
    pub fn free_step(&mut self, h: f64) {
        self.x += self.v * h;
        for (axis, share) in [(0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5)] {
            self.turn(axis, share * h);
        }
    }

    /// The flow of T_k = π_k² / 2I_k over `h`: the body turns by θ = h π_k / I_k about its axis
    /// k, so π, seen from the turned body, turns by −θ, and q π stays.
    fn turn(&mut self, k: usize, h: f64) {
        let theta = h * self.pi[k] / self.moments[k];
        let axis = Vector3::ith_axis(k);
        self.pi = UnitQuaternion::from_axis_angle(&axis, -theta) * self.pi;
        self.q *= UnitQuaternion::from_axis_angle(&axis, theta);
    }
}

/// The period of the body-frame angular momentum of a torque-free body (Landau and Lifshitz,
/// Mechanics §37), from its moments (distinct, any order), |L|² and 2T: π returns after
/// T = 4K(k) √(I₁I₂I₃ / ((I₃ − I₂)(L² − 2E I₁))), k² = (I₂ − I₁)(2E I₃ − L²) / ((I₃ − I₂)(L² − 2E I₁)),
/// with I₁ < I₂ < I₃ ordered so that L² > 2E I₂ (else I₁ and I₃ swap roles). Near the
/// intermediate axis this is the time between two of its flips and back.
pub fn free_period(moments: Vector3<f64>, l2: f64, two_e: f64) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn spinning(moments: [f64; 3], pi: [f64; 3]) -> Rigid {
        Rigid {
            mass: 2.0,
            moments: Vector3::from(moments),
            x: Vector3::zeros(),
            v: Vector3::new(0.5, 0.0, -1.0),
            q: UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.3),
            pi: Vector3::from(pi),
        }
    }

    #[test]
    fn a_box_and_a_sphere_have_their_moments() {
        let m = Shape::Cuboid([1.0, 2.0, 3.0]).moments(12.0).unwrap();
        assert_eq!(m, Vector3::new(13.0, 10.0, 5.0));
        assert_eq!(Shape::Sphere(0.5).moments(10.0).unwrap(), Vector3::repeat(1.0));
    }

    #[test]
    fn sizes_and_masses_must_be_positive() {
        assert!(Shape::Cuboid([1.0, 0.0, 1.0]).moments(1.0).unwrap_err().contains("edge length"));
        assert!(Shape::Sphere(-1.0).moments(1.0).unwrap_err().contains("radius"));
        assert!(Shape::Sphere(1.0).moments(f64::NAN).unwrap_err().contains("mass"));
    }

    /// The world angular momentum is the same to round-off after 100,000 steps: every sub-flow
    /// is a rotation that keeps it.
    #[test]
    fn angular_momentum_stays() {
        let mut b = spinning([1.0, 2.0, 3.0], [0.3, 2.0, -0.7]);
        let l0 = b.angular_momentum();
        for _ in 0..100_000 {
            b.free_step(0.01);
        }
        assert!((b.angular_momentum() - l0).norm() < 1e-11 * l0.norm(), "{:e}", (b.angular_momentum() - l0).norm());
        // and the centre drifts with its velocity
        assert!((b.x - Vector3::new(0.5, 0.0, -1.0) * 1000.0).norm() < 1e-9, "{}", b.x);
    }

    /// The energy error is second order: a quarter when the step halves (the error's maximum
    /// over the same span of time), and it does not drift.
    #[test]
    fn energy_error_is_second_order_and_bounded() {
        let worst = |h: f64, steps: usize| {
            let mut b = spinning([1.0, 2.0, 3.0], [0.3, 2.0, -0.7]);
            let e0 = b.kinetic();
            (0..steps).fold(0.0f64, |w, _| {
                b.free_step(h);
                w.max((b.kinetic() - e0).abs() / e0)
            })
        };
        let (coarse, fine) = (worst(0.02, 5_000), worst(0.01, 10_000));
        let ratio = coarse / fine;
        assert!((3.6..4.4).contains(&ratio), "ratio {ratio}, {coarse:e} {fine:e}");
        // no drift: the worst error over ten times as long is no worse than a few times
        assert!(worst(0.02, 50_000) < 1.5 * coarse);
    }

    /// The intermediate-axis (Dzhanibekov) flip: spun mostly about its middle axis, the body
    /// turns its ω₂ over and back with the period Landau and Lifshitz give.
    #[test]
    fn the_intermediate_axis_flips_at_its_period() {
        let mut b = spinning([1.0, 2.0, 3.0], [0.02, 2.0, 0.01]);
        let period = free_period(b.moments, b.pi.norm_squared(), 2.0 * (b.kinetic() - 0.5 * 2.0 * b.v.norm_squared()));
        let h = 1e-3;
        // the times ω₂ changes sign, up to a step
        let (mut flips, mut last, mut t) = (vec![], b.omega()[1], 0.0);
        while flips.len() < 5 {
            b.free_step(h);
            t += h;
            let w = b.omega()[1];
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
            moments in prop::array::uniform3(0.1f64..5.0), pi in prop::array::uniform3(-3.0f64..3.0), h in 1e-4f64..0.05,
        ) {
            let mut b = spinning(moments, pi);
            let (l0, p0) = (b.angular_momentum(), b.pi.norm());
            for _ in 0..200 {
                b.free_step(h);
            }
            let scale = 1e-13 * (1.0 + p0) * 200.0;
            prop_assert!((b.angular_momentum() - l0).norm() < scale);
            prop_assert!((b.pi.norm() - p0).abs() < scale);
            prop_assert!((b.q.quaternion().norm() - 1.0).abs() < 1e-12);
        }
    }
}
