//! An entity with a `shape` is a rigid body: `shape: box, size: [a, b, c]` (edge lengths) or
//! `shape: sphere, size: r`, with `orientation: { axis: [x, y, z], angle: 30 deg }` (or a unit
//! quaternion `[w, x, y, z]`), `angular_velocity: [x, y, z]` (world frame, 1/time) and
//! `friction` (its Coulomb μ, 0.5 if not given). Its moments of inertia come from its shape and
//! mass.

use crate::block::{value_span, word, Block, Field, Reader};
use crate::diagnostic::{Diagnostic, Span};
use crate::Rule;
use lagra_checker::model::{Extent, Solid};
use lagra_checker::units::Dim;
use nalgebra::{Quaternion, Unit, UnitQuaternion, Vector3};

/// The fields only a rigid body has.
pub const RIGID_FIELDS: &[&str] = &["shape", "orientation", "angular_velocity", "friction"];

/// A solid's Coulomb friction coefficient when it gives none.
const FRICTION: f64 = 0.5;

/// How far from 1 a quaternion's norm may be: it is then normalised; farther is an error (a
/// typo is likelier than a scaled rotation).
const UNIT: f64 = 1e-9;

/// A rigid body read from an entity's fields.
pub struct Rigid {
    pub moments: [f64; 3],
    pub spin: Spin,
    pub solid: Solid,
    /// Its largest half-extent, for display.
    pub size: f64,
}

/// The rigid body an entity's fields describe, if it has a `shape`.
pub fn rigid<'a>(
    rd: &Reader,
    field: &mut impl FnMut(&str) -> Option<Field<'a>>,
    mass: f64,
) -> Result<Option<Rigid>, Diagnostic> {
    let Some(shape_field) = field("shape") else {
        for name in &RIGID_FIELDS[1..] {
            if let Some(f) = field(name) {
                return Err(Diagnostic::new(
                    f.span,
                    format!("entity.{name} needs a `shape` (box or sphere): a point mass has no orientation"),
                ));
            }
        }
        return Ok(None);
    };
    let (name, at) = word(&shape_field, "entity")?;
    let size = field("size").ok_or_else(|| {
        Diagnostic::new(at, "a rigid body needs a size: `size: [a, b, c]` for a box, `size: r` for a sphere")
    })?;
    let shape = match name {
        "box" => {
            let edges = rd.numbers(&size, "entity", Dim::LENGTH, 3)?;
            Shape::Cuboid([edges[0], edges[1], edges[2]])
        }
        "sphere" => Shape::Sphere(rd.numbers(&size, "entity", Dim::LENGTH, 1)?[0]),
        other => return Err(Diagnostic::new(at, format!("unknown shape `{other}`; known: box, sphere"))),
    };
    let moments =
        shape.moments(mass).map_err(|why| Diagnostic::new(value_span(&size), format!("entity.size: {why}")))?;
    let q = match field("orientation") {
        None => UnitQuaternion::identity(),
        Some(f) => orientation(rd, &f)?,
    };
    let omega = match field("angular_velocity") {
        None => Vector3::zeros(),
        Some(f) => Vector3::from_vec(rd.numbers(&f, "entity", Dim::TIME.pow(-1), 3)?),
    };
    let friction = match field("friction") {
        Some(f) => {
            let mu = rd.numbers(&f, "entity", Dim::NONE, 1)?[0];
            if !(mu >= 0.0) {
                return Err(Diagnostic::new(value_span(&f), format!("entity.friction must be ≥ 0, got {mu}")));
            }
            mu
        }
        None => FRICTION,
    };
    let (size, extent) = match shape {
        Shape::Cuboid(e) => (0.5 * e.iter().fold(0.0f64, |m, a| m.max(*a)), Extent::Cuboid(e.map(|c| 0.5 * c))),
        Shape::Sphere(r) => (r, Extent::Ball(r)),
    };
    let solid = Solid { extent, friction };
    Ok(Some(Rigid { moments: moments.into(), spin: spin_of(q, omega, moments), solid, size }))
}

/// `{ axis: [x, y, z], angle }` or a unit quaternion `[w, x, y, z]`.
fn orientation(rd: &Reader, f: &Field) -> Result<UnitQuaternion<f64>, Diagnostic> {
    let v = f.value.clone().into_inner().next().expect("a value has one child");
    if v.as_rule() == Rule::block {
        let mut b = Block::read(Some(v.clone()), v.as_span().into())?;
        let at: Span = v.as_span().into();
        let axis = b.take("axis").ok_or_else(|| Diagnostic::new(at, "orientation needs an `axis: [x, y, z]`"))?;
        let angle = b.take("angle").ok_or_else(|| Diagnostic::new(at, "orientation needs an `angle`"))?;
        b.check_names("orientation", &["axis", "angle"])?;
        let (angle, direction) = (
            rd.numbers(&angle, "orientation", Dim::NONE, 1)?[0],
            Vector3::from_vec(rd.numbers(&axis, "orientation", Dim::NONE, 3)?),
        );
        let axis = Unit::try_new(direction, 0.0)
            .ok_or_else(|| Diagnostic::new(value_span(&axis), "orientation.axis must not be zero"))?;
        return Ok(UnitQuaternion::from_axis_angle(&axis, angle));
    }
    let c = rd.numbers(f, "entity", Dim::NONE, 4)?;
    let q = Quaternion::new(c[0], c[1], c[2], c[3]);
    if (q.norm() - 1.0).abs() > UNIT {
        return Err(Diagnostic::new(
            value_span(f),
            format!("entity.orientation [w, x, y, z] must be a unit quaternion (its norm is {}); or write {{ axis: [x, y, z], angle: θ }}", q.norm()),
        ));
    }
    Ok(UnitQuaternion::from_quaternion(q))
}

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

/// A rigid body's spin as a state holds it (`State::spin`): its orientation, a unit quaternion
/// (w, x, y, z) from the body frame to the world's, then its angular momentum π = I ω in the
/// body frame.
pub type Spin = [f64; 7];

/// The spin of a body at orientation `q` turning at `omega` (world frame).
pub fn spin_of(q: UnitQuaternion<f64>, omega: Vector3<f64>, moments: Vector3<f64>) -> Spin {
    let pi = (q.inverse() * omega).component_mul(&moments);
    let w = q.quaternion();
    [w.w, w.i, w.j, w.k, pi[0], pi[1], pi[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
