//! Joints between solids: `joint ball [i, j] { at }` holds a point of each body together,
//! `joint hinge [i, j] { at, axis }` holds two points on its axis, so that the bodies turn about
//! it alone; `[i]` alone joins body i to the world. Each joint becomes the pins of the model
//! (`lagra_checker::model::Pin`), its points fixed in the bodies' frames where the scene places
//! them: the checker's `joint_satisfied` certifies the same pins the solver holds.

use super::{err, indices_of, Compiler};
use crate::block::{value_span, Block};
use crate::diagnostic::{Diagnostic, Span};
use crate::Pair;
use lagra_checker::model::Pin;
use lagra_checker::units::Dim;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

type V = Vector3<f64>;

/// A joint as written: its bodies (one: joined to the world), its anchor, a hinge's axis.
pub(super) struct JointDecl {
    bodies: Vec<(usize, Span)>,
    at: ([f64; 3], Span),
    axis: Option<[f64; 3]>,
    pub(super) span: Span,
}

/// How far past a body's reach (its bounding ball) an anchor may stand, as a share of it.
const SLACK: f64 = 0.1;

impl<'a> Compiler<'a> {
    /// `joint KIND [i, j] { at, axis }`, read where it stands; its bodies are checked once all
    /// are known (`pins`).
    pub(super) fn joint(
        &mut self,
        kind: &Pair,
        idx: &Pair,
        block: Option<Pair<'a>>,
        span: Span,
    ) -> Result<(), Diagnostic> {
        let hinge = match kind.as_str() {
            "ball" => false,
            "hinge" => true,
            other => return err(kind.as_span(), format!("unknown joint `{other}`; known joints: ball, hinge")),
        };
        let owner = format!("joint {}", kind.as_str());
        let bodies = indices_of(idx)?;
        if !(1..=2).contains(&bodies.len()) {
            return err(
                idx.as_span(),
                format!("{owner} joins two solids `[i, j]`, or one and the world `[i]`; got {} indices", bodies.len()),
            );
        }
        if bodies.len() == 2 && bodies[0].0 == bodies[1].0 {
            return err(idx.as_span(), format!("{owner} joins body {} to itself", bodies[0].0));
        }
        let mut b = Block::read(block, span)?;
        let at_field = b
            .take("at")
            .ok_or_else(|| Diagnostic::new(span, format!("{owner} needs `at`, the joint's point (a length vector)")))?;
        let at = self.rd.numbers(&at_field, &owner, Dim::LENGTH, 3)?;
        let axis = match (b.take("axis"), hinge) {
            (Some(f), true) => {
                let a = self.rd.numbers(&f, &owner, Dim::NONE, 3)?;
                if a.iter().all(|c| *c == 0.0) {
                    return err(value_span(&f), "a hinge's axis must not be zero");
                }
                Some([a[0], a[1], a[2]])
            }
            (None, true) => return err(span, "joint hinge needs `axis`, the direction it turns about"),
            (Some(f), false) => return err(f.span, "`axis` belongs to a hinge; a ball joint turns every way"),
            (None, false) => None,
        };
        b.check_names(&owner, if hinge { &["at", "axis"] } else { &["at"] })?;
        self.joints.push(JointDecl { bodies, at: ([at[0], at[1], at[2]], value_span(&at_field)), axis, span });
        Ok(())
    }

    /// Every joint's pins, its points in its bodies' frames at the initial state: each body
    /// must exist, be a solid, and start with the anchor within its reach (so that the scene
    /// starts joined where it says).
    pub(super) fn pins(&self) -> Result<Vec<Pin>, Diagnostic> {
        // (a scene of many bodies and no joint walks none of them)
        if self.joints.is_empty() {
            return Ok(vec![]);
        }
        let mut spin_of = vec![None; self.bodies.len()];
        let mut rigid = 0;
        for (i, b) in self.bodies.iter().enumerate() {
            if b.moments.is_some() {
                spin_of[i] = Some(rigid);
                rigid += 1;
            }
        }
        let mut pins = vec![];
        for j in &self.joints {
            for &(i, at) in &j.bodies {
                let Some(body) = self.bodies.get(i) else {
                    return err(at, format!("joint: body {i} does not exist ({} bodies)", self.bodies.len()));
                };
                let Some(solid) = body.solid else {
                    return err(
                        at,
                        format!("joint: body {i} is a point mass; a joint joins solids (entities with a `shape`)"),
                    );
                };
                let reach = solid.extent.reach();
                let away = (V::from(j.at.0) - V::from(self.x0[i])).norm();
                if away > (1.0 + SLACK) * reach {
                    return err(
                        j.at.1,
                        format!("joint: its point is {away:.4} from body {i}'s centre, beyond the body's reach {reach:.4}: the bodies must start joined at `at`"),
                    );
                }
            }
            // in body i's frame: Rᵀ (p − x)
            let local = |i: usize, p: V| -> [f64; 3] {
                let s = self.spin0[spin_of[i].expect("a solid is a rigid body")];
                let q = UnitQuaternion::from_quaternion(Quaternion::new(s[0], s[1], s[2], s[3]));
                (q.inverse() * (p - V::from(self.x0[i]))).into()
            };
            let (a, b) = match j.bodies[..] {
                [(b, _)] => (None, b),
                [(a, _), (b, _)] => (Some(a), b),
                _ => unreachable!("a joint has one or two bodies (joint)"),
            };
            let anchor = V::from(j.at.0);
            let mut points = vec![anchor];
            if let Some(axis) = j.axis {
                // the second pin one reach along the axis: a turn off the axis by θ opens it by
                // about reach·θ, a gap measured on the scale of the bodies themselves
                let reach = j
                    .bodies
                    .iter()
                    .map(|&(i, _)| self.bodies[i].solid.map_or(0.0, |s| s.extent.reach()))
                    .fold(f64::INFINITY, f64::min);
                points.push(anchor + V::from(axis).normalize() * reach);
            }
            for p in points {
                let on_a = a.map_or(p.into(), |a| local(a, p));
                pins.push(Pin { a, b, on_a, on_b: local(b, p) });
            }
        }
        Ok(pins)
    }
}
