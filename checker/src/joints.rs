//! Joints held (`joint_satisfied`): how far apart each pin's two points are, evaluated in `R` on
//! one state. A point fixed in a body's frame is seen in the world as its centre plus the point
//! turned by q/|q| (the same turn the angular momentum uses), so nothing of the kernel's own
//! rotation matrices is trusted.

use crate::enclosure::Enclosure;
use crate::model::Model;
use crate::quantities::{Lifted, PairSum};
use crate::real::{norm2, sub3, Vec3};

impl<R: PairSum + Enclosure> Lifted<R> {
    /// Each pin's gap |p_b − p_a|, in the model's order of pins.
    pub fn pin_gaps(&self, model: &Model) -> Vec<R> {
        let mut spin_of = vec![None; model.bodies.len()];
        let mut spins = self.spins.iter();
        for (i, b) in model.bodies.iter().enumerate() {
            spin_of[i] = b.moments.and_then(|_| spins.next());
        }
        let lift = |p: &[f64; 3]| -> Vec3<R> { p.map(|c| self.zero.lift(c)) };
        let placed = |i: usize, p: &[f64; 3]| -> Vec3<R> {
            let spin = spin_of[i].expect("a pin joins rigid bodies (Model::validate)");
            let turned = spin.turn(&lift(p));
            std::array::from_fn(|c| self.sites[i].x[c].clone() + turned[c].clone())
        };
        model
            .pins
            .iter()
            .map(|pin| {
                let a = pin.a.map_or_else(|| lift(&pin.on_a), |a| placed(a, &pin.on_a));
                norm2(&sub3(&placed(pin.b, &pin.on_b), &a)).sqrt()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::claims::{Claim, ClaimKind};
    use crate::enclosure::Enclosure;
    use crate::model::{Cell, Extent, Model, Pin, Snapshot};
    use crate::outward::Outward;
    use crate::quantities::Lifted;
    use crate::solids::tests::{model, solid};
    use nalgebra::{Unit, UnitQuaternion, Vector3};
    use proptest::prelude::*;

    fn gaps(m: &Model, x: &[[f64; 3]], spins: &[[f64; 7]]) -> Vec<(f64, f64)> {
        let v = vec![[0.0; 3]; x.len()];
        let s = Snapshot { step: 0, t: 0.0, x, v: &v, chain: &[], spin: spins };
        Lifted::new(m, &s, &Outward::NAN).pin_gaps(m).into_iter().map(|g| g.bounds()).collect()
    }

    fn spin(q: &UnitQuaternion<f64>) -> [f64; 7] {
        let w = q.quaternion();
        [w.w, w.i, w.j, w.k, 0.0, 0.0, 0.0]
    }

    proptest! {
        /// A pin placed where both bodies' points meet has a gap enclosing 0; moving b by d
        /// opens it by |d| (enclosed): the checker's turn, against nalgebra's in binary64.
        #[test]
        fn a_pin_shut_encloses_nothing_and_opens_by_the_move(
            xa in prop::array::uniform3(-2.0f64..2.0), xb in prop::array::uniform3(-2.0f64..2.0),
            p in prop::array::uniform3(-2.0f64..2.0), d in prop::array::uniform3(-0.5f64..0.5),
            axis in prop::array::uniform3(-1.0f64..1.0), angle in -3.0f64..3.0,
        ) {
            let Some(axis) = Unit::try_new(Vector3::from(axis), 0.1) else { return Ok(()) };
            let (qa, qb) = (UnitQuaternion::from_axis_angle(&axis, angle), UnitQuaternion::from_axis_angle(&axis, -0.7 * angle));
            let local = |q: &UnitQuaternion<f64>, x: [f64; 3]| -> [f64; 3] { (q.inverse() * (Vector3::from(p) - Vector3::from(x))).into() };
            let mut m = model(vec![solid(Extent::Cuboid([0.5; 3])), solid(Extent::Ball(0.3))], None);
            m.pins = vec![Pin { a: Some(0), b: 1, on_a: local(&qa, xa), on_b: local(&qb, xb) }, Pin { a: None, b: 1, on_a: p, on_b: local(&qb, xb) }];
            let spins = [spin(&qa), spin(&qb)];
            for (lo, hi) in gaps(&m, &[xa, xb], &spins) {
                prop_assert!(0.0 <= lo && lo <= hi && hi < 1e-13, "[{lo}, {hi}]");
            }
            let moved = [xb[0] + d[0], xb[1] + d[1], xb[2] + d[2]];
            let size = Vector3::from(d).norm();
            for (lo, hi) in gaps(&m, &[xa, moved], &spins) {
                prop_assert!(lo <= size + 1e-12 && size - 1e-12 <= hi && hi - lo < 1e-12, "[{lo}, {hi}] vs {size}");
            }
        }
    }

    #[test]
    fn a_joint_claim_needs_a_joint_and_no_periodic_box() {
        let claim = Claim::new(ClaimKind::JointSatisfied, Some(1e-3), 1);
        let mut m = model(vec![solid(Extent::Ball(0.3))], None);
        assert_eq!(claim.validate(&m).unwrap_err(), "joint_satisfied: the model has no joint");
        m.pins = vec![Pin { a: None, b: 0, on_a: [0.0; 3], on_b: [0.3, 0.0, 0.0] }];
        assert!(claim.validate(&m).is_ok() && m.validate().is_ok());
        m.cell = Some(Cell { size: [10.0; 3], periodic: [true; 3] });
        assert!(m.validate().unwrap_err().contains("periodic"));
        m.cell = None;
        m.pins[0].a = Some(0);
        assert!(m.validate().unwrap_err().contains("two different rigid bodies"));
        m.pins[0] = Pin { a: None, b: 0, on_a: [f64::NAN, 0.0, 0.0], on_b: [0.0; 3] };
        assert!(m.validate().unwrap_err().contains("finite"));
    }
}
