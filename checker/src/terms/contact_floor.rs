//! A floor, the plane y = y₀ with normal +y, as a penalty contact. Inside it, at depth
//! δ = y₀ − y, a spring V = ½kδ² and a Rayleigh function ½c v_y² + μkδ(√(|v_t|² + s²) − s):
//! damping along the normal and Coulomb friction against the tangential velocity v_t,
//! regularised by the slip speed s so the force is defined at rest (−μkδ v_t/√(|v_t|² + s²),
//! nearly μkδ once |v_t| ≫ s). Outside the floor, nothing.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{select, Real};
use crate::units::Dim;

pub struct ContactFloor;

/// Depth δ = y₀ − y, v_y², |v_t|², and whether the body is inside the floor.
fn contact<R: Real>(p: &[R], s: &Site<R>) -> (R, R, R, Option<bool>) {
    let vt2 = s.v[0].clone().powi(2) + s.v[2].clone().powi(2);
    (p[0].clone() - s.x[1].clone(), s.v[1].clone().powi(2), vt2, s.x[1].lt(&p[0]))
}

impl Definition for ContactFloor {
    const SPEC: Spec = Spec {
        name: "ContactFloor",
        keyword: "floor",
        shape: Shape::External,
        params: &[
            Param::scalar("y", Dim::LENGTH).or(0.0),
            Param::scalar("k", Dim::STIFFNESS),
            Param::scalar("damping", Dim::DAMPING).or(0.0),
            Param::scalar("friction", Dim::NONE).or(0.0),
            Param::scalar("slip", Dim::VELOCITY).or(0.05),
        ],
    };

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let (depth, _, _, inside) = contact(p, s[0]);
        let spring = p[1].clone() * depth.powi(2);
        select(inside, || spring.lift(0.5) * spring.clone(), || spring.lift(0.0) * spring.clone())
    }

    fn rayleigh<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        let (depth, vy2, vt2, inside) = contact(p, s[0]);
        let (c, mu, slip) = (p[2].clone(), p[3].clone(), p[4].clone());
        let damping = c.clone() * vy2;
        let friction = mu * p[1].clone() * depth * ((vt2 + slip.clone().powi(2)).sqrt() - slip);
        Some(select(inside, || damping.lift(0.5) * damping.clone() + friction, || damping.lift(0.0) * damping.clone()))
    }

    /// v·∂F/∂v = c v_y² + μkδ |v_t|²/√(|v_t|² + s²).
    fn power<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        let (depth, vy2, vt2, inside) = contact(p, s[0]);
        let (c, mu, slip) = (p[2].clone(), p[3].clone(), p[4].clone());
        let damping = c * vy2;
        let friction = mu * p[1].clone() * depth * vt2.clone() / (vt2 + slip.powi(2)).sqrt();
        Some(select(inside, || damping.clone() + friction, || damping.lift(0.0) * damping.clone()))
    }

    fn dissipates(p: &[f64]) -> bool {
        p[2] != 0.0 || p[3] != 0.0
    }
}
