//! Solids at rest and in contact: how deep two rigid bodies overlap (but two a joint holds
//! together, which may meet at it) or a body sinks below the floor (`no_penetration`), and how
//! fast the fastest point of a body moves (`resting`), evaluated in `R` on one state.
//!
//! Depth is bounded by separating axes. For convex solids A, B centred at c_A, c_B and any
//! direction n ≠ 0, the overlap of their shadows on n, (h_A(n) + h_B(n) − |n·(c_B − c_A)|)/|n|
//! with h the half-width of a solid's shadow, is at least their penetration depth (the shortest
//! translation that parts them, the least such overlap over all n). So the least overlap over
//! any few directions bounds the depth from above, whichever are tried: they are picked in
//! binary64 (each box's faces, the crosses of their edges, the line of centres), and only the
//! bound is evaluated in `R`.

use crate::enclosure::Enclosure;
use crate::model::{Extent, Model, Snapshot};
use crate::quantities::{rough_axes, Lifted, Spin};
use crate::real::{cross3, dot3, norm2, sub3, Vec3};

/// A rigid body's solid in the world: centre, axes (columns of q/|q|), extent.
struct Placed<R> {
    centre: Vec3<R>,
    axes: Option<[Vec3<R>; 3]>,
    extent: Option<Extent>,
}

impl<R: Enclosure> Placed<R> {
    /// The half-width of its shadow on n: Σ h_k |n·a_k| for a box, r|n| for a ball, 0 for a point.
    fn half_width(&self, n: &Vec3<R>) -> R {
        let zero = n[0].lift(0.0);
        match (self.extent, &self.axes) {
            (Some(Extent::Cuboid(h)), Some(a)) => {
                (0..3).fold(zero.clone(), |acc, k| acc + zero.lift(h[k]) * dot3(n, &a[k]).abs())
            }
            (Some(Extent::Ball(r)), _) => zero.lift(r) * norm2(n).sqrt(),
            _ => zero,
        }
    }
}

fn min<R: Enclosure>(a: R, b: R) -> R {
    -((-a).max(-b))
}

impl<R: crate::quantities::PairSum + Enclosure> Lifted<R> {
    fn placed(&self, model: &Model) -> Vec<Placed<R>> {
        let mut spins = self.spins.iter();
        let mut out = vec![];
        for (site, b) in self.sites.iter().zip(&model.bodies) {
            let spin = b.moments.and_then(|_| spins.next());
            out.push(Placed { centre: site.x.clone(), axes: spin.map(Spin::axes), extent: b.solid.map(|s| s.extent) });
        }
        out
    }

    /// The largest depth any body is below the floor or two solids overlap by, at least 0.
    pub fn penetration(&self, model: &Model, s: &Snapshot) -> R {
        let placed = self.placed(model);
        let mut worst = self.zero.clone();
        if let Some(floor) = model.floor {
            let up = [0.0, 1.0, 0.0].map(|c| self.zero.lift(c));
            for p in &placed {
                let depth = self.zero.lift(floor.y) - p.centre[1].clone() + p.half_width(&up);
                worst = worst.max(depth);
            }
        }
        for (a, b) in near_solids(model, s) {
            worst = worst.max(overlap(&placed[a], &placed[b]));
        }
        worst
    }

    /// The largest speed of any point of any body: |v| + |π/I|·ρ, ρ its solid's reach (a
    /// rotation keeps |ω|, so q is not needed).
    pub fn fastest_point(&self, model: &Model) -> R {
        let mut spins = self.spins.iter();
        let mut fastest = self.zero.clone();
        for (b, site) in model.bodies.iter().zip(&self.sites) {
            let mut speed = norm2(&site.v).sqrt();
            if let (Some(spin), Some(solid)) = (b.moments.and_then(|_| spins.next()), b.solid) {
                let omega: Vec3<R> = std::array::from_fn(|k| spin.pi[k].clone() / spin.moments[k].clone());
                let reach = match solid.extent {
                    Extent::Cuboid(h) => norm2(&h.map(|c| self.zero.lift(c))).sqrt(),
                    Extent::Ball(r) => self.zero.lift(r),
                };
                speed = speed + norm2(&omega).sqrt() * reach;
            }
            fastest = fastest.max(speed);
        }
        fastest
    }
}

/// The least shadow overlap of two solids over the directions tried, at least 0.
fn overlap<R: Enclosure>(a: &Placed<R>, b: &Placed<R>) -> R {
    let d = sub3(&b.centre, &a.centre);
    let mut directions: Vec<Vec3<R>> = vec![d.clone()];
    let faces = |p: &Placed<R>| p.axes.clone().filter(|_| matches!(p.extent, Some(Extent::Cuboid(_))));
    let (fa, fb) = (faces(a), faces(b));
    directions.extend(fa.iter().flatten().cloned());
    directions.extend(fb.iter().flatten().cloned());
    if let (Some(fa), Some(fb)) = (&fa, &fb) {
        // an edge pair's cross, unless its edges are near parallel (then a face does as well)
        for ea in fa {
            for eb in fb {
                let c = cross3(ea, eb);
                if norm2(&c).bounds().0 > 1e-12 {
                    directions.push(c);
                }
            }
        }
    }
    let zero = d[0].lift(0.0);
    let mut least: Option<R> = None;
    for n in &directions {
        let length = norm2(n).sqrt();
        let o = (a.half_width(n) + b.half_width(n) - dot3(n, &d).abs()) / length;
        least = Some(match least {
            None => o,
            Some(l) => min(l, o),
        });
    }
    least.map_or(zero.clone(), |l| l.max(zero))
}

/// Each pair of solids that may touch, found in binary64: swept along x with their reaches,
/// then tried for a separating direction (`Rough::apart`). A pair left out is certainly apart,
/// so overlaps by nothing; each test's margin is far above binary64's rounding of it (1e-9 of
/// the sizes involved, against ~1e-15). Two solids a joint holds together are left out too:
/// they may meet at the joint (`Pin::joins`).
fn near_solids(model: &Model, s: &Snapshot) -> Vec<(usize, usize)> {
    let x = s.x;
    let rough = Rough::all(model, s);
    let mut solids: Vec<(usize, f64)> =
        model.bodies.iter().enumerate().filter_map(|(i, b)| b.solid.map(|s| (i, s.extent.reach()))).collect();
    solids.sort_by(|a, b| x[a.0][0].total_cmp(&x[b.0][0]));
    let widest = solids.iter().fold(0.0f64, |m, s| m.max(s.1));
    let mut near = vec![];
    for (n, &(i, ri)) in solids.iter().enumerate() {
        for &(j, rj) in &solids[n + 1..] {
            let margin = 1e-9 * (1.0 + x[i][0].abs() + x[j][0].abs());
            if x[j][0] - x[i][0] > ri + widest + margin {
                break;
            }
            let beyond_reach = (0..3).any(|c| (x[j][c] - x[i][c]).abs() > ri + rj + margin);
            let joined = || model.pins.iter().any(|p| p.joins(i, j));
            if !beyond_reach && !joined() && !rough[i].apart(&rough[j], ri + rj) {
                near.push((i.min(j), i.max(j)));
            }
        }
    }
    near
}

/// A solid as binary64 sees it, for culling only: its centre, and a box's axes where its spin's
/// quaternion is near unit (|q|² within [½, 2]: far from overflow, and from the subnormals that
/// would turn its axes wrong without a NaN to say so).
struct Rough {
    centre: [f64; 3],
    extent: Option<Extent>,
    axes: Option<[[f64; 3]; 3]>,
}

impl Rough {
    fn all(model: &Model, s: &Snapshot) -> Vec<Rough> {
        let mut spins = s.spin.iter();
        let near_unit = |q: &&[f64; 7]| (0.5..=2.0).contains(&q[..4].iter().map(|c| c * c).sum::<f64>());
        let rough = |(b, x): (&crate::model::Body, &[f64; 3])| {
            let spin = b.moments.and_then(|_| spins.next());
            let extent = b.solid.map(|s| s.extent);
            // a spin off unit: no axes, and a box without them is never cleared (`half_width`)
            let axes = spin.filter(near_unit).map(rough_axes);
            Rough { centre: *x, extent, axes }
        };
        model.bodies.iter().zip(s.x).map(rough).collect()
    }

    /// The half-width of its shadow on n, as `Placed::half_width`; `None` for a box whose axes
    /// are not known.
    fn half_width(&self, n: &[f64; 3]) -> Option<f64> {
        match (self.extent, &self.axes) {
            (Some(Extent::Cuboid(h)), Some(a)) => Some((0..3).map(|k| h[k] * dot3(n, &a[k]).abs()).sum()),
            (Some(Extent::Cuboid(_)), None) => None,
            (Some(Extent::Ball(r)), _) => Some(r * norm2(n).sqrt()),
            (None, _) => Some(0.0),
        }
    }

    /// Whether the solids are certainly apart: along the line of centres or a face of either
    /// box their shadows miss each other by more than the margin (NaN anywhere: not apart).
    fn apart(&self, other: &Rough, reaches: f64) -> bool {
        let d = sub3(&other.centre, &self.centre);
        let far = |c: &[f64; 3]| c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let size = 1.0 + far(&self.centre) + far(&other.centre) + reaches;
        let faces = |r: &Rough| r.axes.filter(|_| matches!(r.extent, Some(Extent::Cuboid(_))));
        let directions =
            std::iter::once(d).chain(faces(self).into_iter().flatten()).chain(faces(other).into_iter().flatten());
        directions.into_iter().any(|n| match (self.half_width(&n), other.half_width(&n)) {
            (Some(a), Some(b)) => dot3(&n, &d).abs() - a - b > 1e-9 * size * norm2(&n).sqrt(),
            _ => false,
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::enclosure::Enclosure;
    use crate::model::{Body, Extent, Floor, Model, Pin, Snapshot, Solid, UnitSystem};
    use crate::outward::Outward;
    use crate::quantities::Lifted;
    use proptest::prelude::*;

    pub(crate) fn solid(extent: Extent) -> Body {
        let moments = Some([1.0; 3]);
        Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments, solid: Some(Solid { extent, friction: 0.5 }) }
    }

    pub(crate) fn model(bodies: Vec<Body>, floor: Option<f64>) -> Model {
        let floor = floor.map(|y| Floor { y, friction: None });
        Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies,
            terms: vec![],
            constraints: vec![],
            thermostat: None,
            floor,
            pins: vec![],
        }
    }

    /// A turn by `angle` about the unit axis, as a spin at rest or turning with π.
    fn spin(axis: [f64; 3], angle: f64, pi: [f64; 3]) -> [f64; 7] {
        let (s, c) = (0.5 * angle).sin_cos();
        [c, s * axis[0], s * axis[1], s * axis[2], pi[0], pi[1], pi[2]]
    }

    fn depth(m: &Model, x: &[[f64; 3]], spins: &[[f64; 7]]) -> (f64, f64) {
        let v = vec![[0.0; 3]; x.len()];
        let s = Snapshot { step: 0, t: 0.0, x, v: &v, chain: &[], spin: spins };
        Lifted::new(m, &s, &Outward::NAN).penetration(m, &s).bounds()
    }

    const CUBE: Extent = Extent::Cuboid([0.5; 3]);
    const REST: [f64; 7] = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];

    #[test]
    fn two_cubes_overlapping_along_x_overlap_by_that_much() {
        let m = model(vec![solid(CUBE), solid(CUBE)], None);
        let (lo, hi) = depth(&m, &[[0.0; 3], [0.9, 0.2, -0.1]], &[REST, REST]);
        assert!(lo <= 0.1 && hi >= 0.1 && hi - 0.1 < 1e-14, "[{lo}, {hi}]");
        assert_eq!(depth(&m, &[[0.0; 3], [1.1, 0.0, 0.0]], &[REST, REST]), (0.0, 0.0));
        // bounding balls apart: never even tried
        assert_eq!(depth(&m, &[[0.0; 3], [5.0, 0.0, 0.0]], &[REST, REST]), (0.0, 0.0));
    }

    /// Two cubes a joint holds together may meet at it: their overlap is not measured, a third
    /// cube's with either is, and a pin to the world leaves nothing out.
    #[test]
    fn solids_a_joint_holds_together_are_not_measured_against_each_other() {
        let mut m = model(vec![solid(CUBE), solid(CUBE), solid(CUBE)], None);
        let pin = |a: Option<usize>, b: usize| Pin { a, b, on_a: [0.45, 0.0, 0.0], on_b: [-0.45, 0.0, 0.0] };
        let x = [[0.0; 3], [0.9, 0.0, 0.0], [5.0, 0.0, 0.0]];
        let overlapped = depth(&m, &x, &[REST; 3]);
        assert!(overlapped.0 <= 0.1 && 0.1 <= overlapped.1, "{overlapped:?}");
        m.pins = vec![pin(None, 0), pin(None, 1)];
        assert_eq!(depth(&m, &x, &[REST; 3]), overlapped);
        m.pins = vec![pin(Some(1), 0)];
        assert_eq!(depth(&m, &x, &[REST; 3]), (0.0, 0.0));
        let (lo, hi) = depth(&m, &[x[0], x[1], [-0.8, 0.0, 0.0]], &[REST; 3]);
        assert!(lo <= 0.2 && 0.2 <= hi && hi - 0.2 < 1e-14, "[{lo}, {hi}]");
    }

    #[test]
    fn a_tilted_cube_sinks_below_the_floor_by_its_lowest_corner() {
        let m = model(vec![solid(CUBE)], Some(0.0));
        // turned 45° about z its lowest corner is √2/2 below its centre
        let (lo, hi) = depth(&m, &[[0.0, 0.7, 0.0]], &[spin([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_4, [0.0; 3])]);
        let sunk = 0.5f64.sqrt() - 0.7;
        assert!(lo <= sunk && sunk <= hi && hi - sunk < 1e-14, "[{lo}, {hi}] vs {sunk}");
    }

    #[test]
    fn two_balls_overlap_by_their_radii_less_their_distance() {
        let m = model(vec![solid(Extent::Ball(0.5)), solid(Extent::Ball(0.25))], None);
        let (lo, hi) = depth(&m, &[[0.0; 3], [0.3, 0.4, 0.0]], &[REST, REST]);
        assert!(lo <= 0.25 && 0.25 <= hi && hi - 0.25 < 1e-14);
    }

    #[test]
    fn the_fastest_point_adds_the_turn_times_the_reach() {
        let m = model(vec![solid(CUBE)], None);
        let (x, v) = ([[0.0; 3]], [[3.0, 4.0, 0.0]]);
        let spins = [spin([0.0, 1.0, 0.0], 0.3, [0.0, 2.0, 0.0])];
        let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &spins };
        let (lo, hi) = Lifted::new(&m, &s, &Outward::NAN).fastest_point(&m).bounds();
        let exact = 5.0 + 2.0 * 0.75f64.sqrt();
        assert!(lo <= exact && exact <= hi && hi - lo < 1e-13, "[{lo}, {hi}] vs {exact}");
    }

    /// A resting claim is judged from its time on: a fast body before it is no breach, after
    /// it is one; and no_penetration needs something to touch.
    #[test]
    fn resting_speaks_from_its_time_on() {
        use crate::claims::{Claim, ClaimKind};
        use crate::monitor::Monitor;
        let m = model(vec![solid(CUBE)], Some(-1.0));
        let resting = Claim { after: Some(1.0), ..Claim::new(ClaimKind::Resting, Some(1e-3), 1) };
        let observe = |mon: &mut Monitor, step: u64, speed: f64| {
            let (x, v) = ([[0.0; 3]], [[speed, 0.0, 0.0]]);
            let s = Snapshot { step, t: step as f64 * 0.5, x: &x, v: &v, chain: &[], spin: &[REST] };
            mon.observe(&s).is_ok()
        };
        let mut mon = Monitor::new(m.clone(), vec![resting.clone()], 3).unwrap();
        assert!(observe(&mut mon, 0, 10.0) && observe(&mut mon, 1, 10.0));
        assert!(observe(&mut mon, 2, 1e-4) && observe(&mut mon, 3, 0.0));
        assert!(mon.finish().verdicts[0].is_pass());
        let mut mon = Monitor::new(m.clone(), vec![resting], 3).unwrap();
        assert!(observe(&mut mon, 0, 0.0) && !observe(&mut mon, 2, 0.01));
        let alone = model(vec![solid(CUBE)], None);
        assert!(Claim::new(ClaimKind::NoPenetration, Some(1e-3), 1).validate(&alone).is_err());
        let late = Claim { after: Some(1.0), ..Claim::new(ClaimKind::NoPenetration, Some(1e-3), 1) };
        assert!(late.validate(&m).is_err());
    }

    fn near(m: &Model, x: &[[f64; 3]], spins: &[[f64; 7]]) -> Vec<(usize, usize)> {
        let v = vec![[0.0; 3]; x.len()];
        super::near_solids(m, &Snapshot { step: 0, t: 0.0, x, v: &v, chain: &[], spin: spins })
    }

    /// Neighbouring towers of a stack (a gap of 0.1 between faces, their reaches overlapping)
    /// are cleared in binary64; touching cubes are not; nor is a cube whose quaternion is far
    /// from unit (its axes in binary64 are not trusted), nor one exactly touching.
    #[test]
    fn the_broad_phase_clears_only_solids_certainly_apart() {
        let m = model(vec![solid(CUBE), solid(CUBE)], None);
        let turned = spin([0.0, 1.0, 0.0], 0.004, [0.0; 3]);
        assert!(near(&m, &[[0.0; 3], [1.1, 0.0, 0.3]], &[REST, turned]).is_empty());
        assert!(near(&m, &[[0.0; 3], [1.1, 1.0, 1.1]], &[REST, turned]).is_empty());
        assert_eq!(near(&m, &[[0.0; 3], [0.99, 0.0, 0.3]], &[REST, turned]), vec![(0, 1)]);
        assert_eq!(near(&m, &[[0.0; 3], [1.0, 0.0, 0.0]], &[REST, REST]), vec![(0, 1)]);
        let tiny = REST.map(|c| c * 1e-170);
        assert_eq!(near(&m, &[[0.0; 3], [1.1, 0.0, 0.3]], &[REST, tiny]), vec![(0, 1)]);
        let balls = model(vec![solid(Extent::Ball(0.5)), solid(CUBE)], None);
        assert!(near(&balls, &[[0.0; 3], [0.0, 1.05, 0.0]], &[REST, REST]).is_empty());
        assert_eq!(near(&balls, &[[0.0; 3], [0.0, 0.95, 0.0]], &[REST, REST]), vec![(0, 1)]);
    }

    proptest! {
    /// The broad phase's clearing against the enclosure: a pair it leaves out overlaps by
            /// nothing over the checker's own directions in `Outward` (a ball or a turned box
            /// beside a cube, anywhere near it).
            #[test]
            fn a_pair_the_broad_phase_clears_has_no_overlap_in_the_enclosure(
                h in prop::array::uniform3(0.1f64..1.0), c in prop::array::uniform3(-2.0f64..2.0),
                axis in prop::array::uniform3(-1.0f64..1.0), angle in -3.0f64..3.0, ball in prop::bool::ANY,
            ) {
                use nalgebra::{Unit, UnitQuaternion, Vector3};
                let Some(axis) = Unit::try_new(Vector3::from(axis), 0.1) else { return Ok(()) };
                let w = *UnitQuaternion::from_axis_angle(&axis, angle).quaternion();
                let first = if ball { Extent::Ball(h[0]) } else { Extent::Cuboid(h) };
                let m = model(vec![solid(first), solid(CUBE)], None);
                let (x, spins) = ([[0.0; 3], c], [[w.w, w.i, w.j, w.k, 0.0, 0.0, 0.0], REST]);
                if near(&m, &x, &spins).is_empty() {
                    let v = vec![[0.0; 3]; 2];
                    let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &spins };
                    let placed = Lifted::new(&m, &s, &Outward::NAN).placed(&m);
                    prop_assert_eq!(super::overlap(&placed[0], &placed[1]).bounds(), (0.0, 0.0));
                }
            }

            /// Soundness against an independent witness: a point of one box inside the other at
            /// distance d from its surface needs a translation of at least d to leave it, so d is
            /// at most the penetration depth, and so at most the certified bound. Points sampled on
            /// a grid through the second box, turned first box, in binary64 with nalgebra.
            #[test]
            fn every_point_inside_is_no_deeper_than_the_bound(
                h in prop::array::uniform3(0.1f64..1.0), c in prop::array::uniform3(-0.8f64..0.8),
                axis in prop::array::uniform3(-1.0f64..1.0), angle in -3.0f64..3.0,
            ) {
                use nalgebra::{Unit, UnitQuaternion, Vector3};
                let Some(axis) = Unit::try_new(Vector3::from(axis), 0.1) else { return Ok(()) };
                let q = UnitQuaternion::from_axis_angle(&axis, angle);
                let w = q.quaternion();
                let m = model(vec![solid(Extent::Cuboid(h)), solid(CUBE)], None);
                let (lo, hi) = depth(&m, &[[0.0; 3], c], &[[w.w, w.i, w.j, w.k, 0.0, 0.0, 0.0], REST]);
                prop_assert!(0.0 <= lo && lo <= hi);
                let grid = |k: usize| -0.5 + 0.125 * k as f64;
                for (i, j, k) in (0..9).flat_map(|i| (0..9).flat_map(move |j| (0..9).map(move |k| (i, j, k)))) {
                    let p = Vector3::new(c[0] + grid(i), c[1] + grid(j), c[2] + grid(k));
                    let local = q.inverse() * p;
                    let inside = (0..3).map(|a| h[a] - local[a].abs()).fold(f64::INFINITY, f64::min);
                    prop_assert!(inside <= hi + 1e-12, "a point {inside} deep, bound {hi}");
                }
                let reach = h.iter().map(|a| a * a).sum::<f64>().sqrt() + 0.75f64.sqrt();
                prop_assert_eq!(depth(&m, &[[0.0; 3], [reach + 0.01, c[1], c[2]]], &[REST, REST]), (0.0, 0.0));
            }
        }
}
