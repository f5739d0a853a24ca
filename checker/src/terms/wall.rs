//! A wall, the plane n̂·x = d with n̂ = n/|n| pointing into the room, as a frictionless penalty:
//! at depth δ = d − n̂·x > 0 behind it a spring V = ½kδ², nothing in front. A fluid's tank is
//! walls and a floor; a wall does no work but its spring's, so the energy stays a sum.

use super::{Definition, Param, Shape, Site, Spec};
use crate::real::{dot3, norm2, select, Real};
use crate::units::Dim;

pub struct Wall;

impl Definition for Wall {
    const SPEC: Spec = Spec {
        name: "Wall",
        keyword: "wall",
        shape: Shape::External,
        params: &[
            Param::vector("normal", Dim::NONE),
            Param::scalar("offset", Dim::LENGTH).or(0.0),
            Param::scalar("k", Dim::STIFFNESS).positive(),
        ],
    };

    fn accepts(p: &[f64]) -> Result<(), (&'static str, &'static str)> {
        if p[..3].iter().any(|&c| c != 0.0) {
            Ok(())
        } else {
            Err(("normal", "must not be zero: it says which side of the wall is the room"))
        }
    }

    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R {
        let n = [p[0].clone(), p[1].clone(), p[2].clone()];
        let depth = p[3].clone() - dot3(&n, &s[0].x) / norm2(&n).sqrt();
        let in_front = p[3].lt(&(dot3(&n, &s[0].x) / norm2(&n).sqrt()));
        let spring = p[4].clone() * depth.powi(2);
        // on the plane the spring is zero either way
        select(in_front, || spring.lift(0.0) * spring.clone(), || spring.lift(0.5) * spring.clone())
    }
}
