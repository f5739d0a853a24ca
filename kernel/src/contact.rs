//! Where solids touch: the points of contact between rigid bodies (box–box, sphere–box,
//! sphere–sphere) and between any body and a rigid floor, each with its normal and depth, for
//! the contact solver (`solvers/impulses.rs`) to keep apart.
//!
//! Box–box contacts follow the usual manifold construction (Gottschalk's separating axes, then
//! the incident face clipped against the reference face, as in ODE's and Box2D's box colliders):
//! the face axis of least overlap is the normal, the incident box's face most opposed to it is
//! clipped to the reference face's sides, and each clipped corner below the reference face (or
//! within `margin` above it: a speculative contact) is a point. An edge axis separates, but edge–
//! edge contacts take the best face's normal too: a first layer, good for faces that rest on
//! faces (stacks, walls), rough for boxes that meet edge on edge.
//!
//! None of this is trusted: `no_penetration` is certified by the checker's own geometry.

use crate::rigid::Spin;
use crate::spread;
use grid::Grid;
use lagra_checker::model::{Extent, Floor, Model, Pin};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rayon::ThreadPool;

type V = Vector3<f64>;

mod grid;

/// One point of contact between `a` (none: the floor) and `b`: `normal` points from a to b,
/// `depth` > 0 is an overlap, < 0 a gap of a speculative contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    pub a: Option<usize>,
    pub b: usize,
    pub point: V,
    pub normal: V,
    pub depth: f64,
    pub friction: f64,
}

/// A body's place: its centre and its rotation (columns: its axes in the world).
#[derive(Clone, Copy, Debug)]
pub struct Pose {
    pub centre: V,
    pub rotation: Matrix3<f64>,
}

#[derive(Clone, Copy, Debug)]
struct Solid {
    extent: Extent,
    friction: f64,
}

/// The solids of a model and its floor: what can touch.
#[derive(Clone, Debug)]
pub struct Solids {
    /// Per body: its solid, none for a point mass.
    solids: Vec<Option<Solid>>,
    floor: Option<Floor>,
    /// The joints' pins (AVBD holds them); two bodies a pin joins never touch.
    pub pins: Vec<Pin>,
    /// How far apart two surfaces may be and still make a (speculative) contact.
    pub margin: f64,
}

/// Bodies a thread takes at once in the contact search.
const RUN: usize = 16;

impl Solids {
    /// Nothing to touch, for `n` bodies (a contact solver named where nothing can meet).
    pub fn none(n: usize) -> Solids {
        Solids { solids: vec![None; n], floor: None, pins: vec![], margin: 0.0 }
    }

    /// None when nothing can touch and nothing is pinned: no floor, no joint and fewer than two
    /// solids.
    pub fn of(model: &Model) -> Option<Solids> {
        // (counted before anything is allocated: a liquid of 256,000 atoms has no solid)
        let count = model.bodies.iter().filter(|b| b.solid.is_some()).count();
        if model.floor.is_none() && model.pins.is_empty() && count < 2 {
            return None;
        }
        let solids: Vec<Option<Solid>> =
            model.bodies.iter().map(|b| b.solid.map(|s| Solid { extent: s.extent, friction: s.friction })).collect();
        let smallest = solids.iter().flatten().map(|s| least(&s.extent)).fold(f64::INFINITY, f64::min);
        let margin = if smallest.is_finite() { 0.02 * smallest } else { 1e-3 };
        Some(Solids { solids, floor: model.floor, pins: model.pins.clone(), margin })
    }

    /// The poses of the bodies at positions `x` and spins `spin` (rigid bodies in order).
    pub fn poses(&self, x: &[[f64; 3]], spin: &[Spin]) -> Vec<Pose> {
        let mut spins = spin.iter();
        self.solids
            .iter()
            .zip(x)
            .map(|(s, x)| {
                let rotation = match s.and_then(|_| spins.next()) {
                    Some(q) => UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
                        .to_rotation_matrix()
                        .into_inner(),
                    None => Matrix3::identity(),
                };
                Pose { centre: V::from(*x), rotation }
            })
            .collect()
    }

    /// Every contact at these poses, in an order fixed by the state: the floor's, body by body,
    /// then each near pair's, pairs in index order. One pass shares the bodies out in runs of
    /// `RUN`, finding a run's floor contacts and then its pairs' with the solids after them,
    /// and the runs are gathered in that order: the same contacts for any thread count. (The
    /// pairs were first listed in a pass of their own, and the floor's and the pairs' contacts
    /// found in two more: three passes, each one's end a wait, where the stack's contact search
    /// scaled 1.36× on two threads; a body at a time, two lists each, 1.5×.)
    pub fn touching(&self, poses: &[Pose], pool: Option<&ThreadPool>) -> Vec<Touch> {
        let reach = |i: usize| self.solids[i].map(|s| s.extent.reach() + self.margin);
        let balls: Vec<(usize, f64)> = (0..self.solids.len()).filter_map(|i| reach(i).map(|r| (i, r))).collect();
        let grid = Grid::of(&balls, poses);
        let floor =
            |i: usize| {
                let s = self.solids[i];
                let found =
                    self.floor.map(|floor| {
                        let mu = floor.friction.unwrap_or(s.map_or(0.0, |s| s.friction));
                        on_floor(s.map(|s| s.extent), &poses[i], floor.y, self.margin).map(move |(point, depth)| {
                            Touch { a: None, b: i, point, normal: V::y(), depth, friction: mu }
                        })
                    });
                found.into_iter().flatten()
            };
        let pinned = |i: usize, j: usize| self.pins.iter().any(|p| p.joins(i, j));
        let pair = |i: usize, j: usize| {
            let (si, sj) = (self.solids[i].expect("a solid"), self.solids[j].expect("a solid"));
            let mu = (si.friction * sj.friction).sqrt();
            let found = between((i, si.extent), (j, sj.extent), poses, self.margin).into_iter();
            found.map(move |(a, b, point, normal, depth)| Touch { a: Some(a), b, point, normal, depth, friction: mu })
        };
        // a run of bodies' floor contacts, then their pairs' with the solids after them
        let run = |k: usize| {
            let bodies = k * RUN..((k + 1) * RUN).min(self.solids.len());
            let floors: Vec<Touch> = bodies.clone().flat_map(floor).collect();
            let (mut near, mut pairs) = (vec![], vec![]);
            for i in bodies {
                if let Some(r) = reach(i) {
                    grid.after(i, r, &mut near);
                    near.iter().filter(|&&j| !pinned(i, j)).for_each(|&j| pairs.extend(pair(i, j)));
                }
            }
            (floors, pairs)
        };
        let runs = spread::share(pool, self.solids.len().div_ceil(RUN), 1, run);
        // a run's list at a time, each a copy of memory (a flat iterator over them pushed touch
        // by touch: 90 µs a step on the stack's 4,000 touches, serial)
        let mut out = Vec::with_capacity(runs.iter().map(|r| r.0.len() + r.1.len()).sum());
        runs.iter().for_each(|r| out.extend_from_slice(&r.0));
        runs.iter().for_each(|r| out.extend_from_slice(&r.1));
        out
    }
}

/// The smallest half-size of a solid.
fn least(e: &Extent) -> f64 {
    match *e {
        Extent::Cuboid(h) => h.iter().copied().fold(f64::INFINITY, f64::min),
        Extent::Ball(r) => r,
    }
}

/// The corners of a box, in the world.
fn corners(p: &Pose, h: [f64; 3]) -> [V; 8] {
    std::array::from_fn(|n| {
        let s = |k: usize| if n >> k & 1 == 1 { h[k] } else { -h[k] };
        p.centre + p.rotation * V::new(s(0), s(1), s(2))
    })
}

/// The points of a body within `margin` of the floor y = y₀ or below it, with their depths.
fn on_floor(extent: Option<Extent>, p: &Pose, y0: f64, margin: f64) -> impl Iterator<Item = (V, f64)> {
    let (points, n) = match extent {
        Some(Extent::Cuboid(h)) => (corners(p, h), 8),
        Some(Extent::Ball(r)) => ([p.centre - V::y() * r; 8], 1),
        None => ([p.centre; 8], 1),
    };
    points.into_iter().take(n).map(move |q| (q, y0 - q.y)).filter(move |(_, d)| *d > -margin)
}

type Contact = (usize, usize, V, V, f64);

/// The contacts of two solids (normal from the first index to the second).
fn between(a: (usize, Extent), b: (usize, Extent), poses: &[Pose], margin: f64) -> Vec<Contact> {
    let (pa, pb) = (&poses[a.0], &poses[b.0]);
    match (a.1, b.1) {
        (Extent::Cuboid(ha), Extent::Cuboid(hb)) => boxes((a.0, pa, ha), (b.0, pb, hb), margin),
        (Extent::Cuboid(h), Extent::Ball(r)) => ball_box((b.0, pb, r), (a.0, pa, h), margin).into_iter().collect(),
        (Extent::Ball(r), Extent::Cuboid(h)) => ball_box((a.0, pa, r), (b.0, pb, h), margin).into_iter().collect(),
        (Extent::Ball(ra), Extent::Ball(rb)) => {
            let d = pb.centre - pa.centre;
            let dist = d.norm();
            let depth = ra + rb - dist;
            if depth < -margin {
                return vec![];
            }
            let n = if dist > 0.0 { d / dist } else { V::y() };
            vec![(a.0, b.0, pa.centre + n * (ra - 0.5 * depth), n, depth)]
        }
    }
}

/// A ball against a box: the box's point nearest the ball's centre (or, for a centre inside,
/// the nearest face). The normal points from the box to the ball.
fn ball_box(ball: (usize, &Pose, f64), cube: (usize, &Pose, [f64; 3]), margin: f64) -> Option<Contact> {
    let ((i, pb, r), (j, pc, h)) = (ball, cube);
    let local = pc.rotation.transpose() * (pb.centre - pc.centre);
    let nearest = V::from_fn(|k, _| local[k].clamp(-h[k], h[k]));
    let (n, depth, at) = if nearest == local {
        let k = (0..3).min_by(|&a, &b| (h[a] - local[a].abs()).total_cmp(&(h[b] - local[b].abs()))).expect("an axis");
        let n = pc.rotation.column(k) * local[k].signum();
        (n.into_owned(), r + h[k] - local[k].abs(), pb.centre - n * r)
    } else {
        let gap = local - nearest;
        let dist = gap.norm();
        ((pc.rotation * gap) / dist, r - dist, pc.centre + pc.rotation * nearest)
    };
    (depth > -margin).then_some((j, i, at, n, depth))
}

/// Two boxes: separating axes, then the incident face clipped to the reference face.
fn boxes(a: (usize, &Pose, [f64; 3]), b: (usize, &Pose, [f64; 3]), margin: f64) -> Vec<Contact> {
    let ((ia, pa, ha), (ib, pb, hb)) = (a, b);
    let d = pb.centre - pa.centre;
    let half = |p: &Pose, h: [f64; 3], n: &V| (0..3).map(|k| h[k] * n.dot(&p.rotation.column(k)).abs()).sum::<f64>();
    let overlap = |n: &V| half(pa, ha, n) + half(pb, hb, n) - n.dot(&d).abs();
    // the face of least overlap, A's preferred on a near tie (a steadier manifold)
    let mut best: Option<(f64, bool, usize)> = None;
    for (on_b, p) in [(false, pa), (true, pb)] {
        for k in 0..3 {
            let o = overlap(&p.rotation.column(k).into_owned());
            if o < -margin {
                return vec![];
            }
            let slack = if on_b { 1e-9 * (1.0 + o.abs()) } else { 0.0 };
            if best.is_none_or(|(m, _, _)| o + slack < m) {
                best = Some((o, on_b, k));
            }
        }
    }
    for k in 0..3 {
        for l in 0..3 {
            let c = pa.rotation.column(k).cross(&pb.rotation.column(l));
            if c.norm() > 1e-6 && overlap(&c.normalize()) < -margin {
                return vec![];
            }
        }
    }
    let (_, on_b, k) = best.expect("six faces");
    let (reference, incident) = if on_b { ((ib, pb, hb), (ia, pa, ha)) } else { ((ia, pa, ha), (ib, pb, hb)) };
    clipped(reference, incident, k, margin)
}

/// The incident box's face most opposed to the reference face k (normal toward the incident
/// box), clipped to the reference face's four sides; its corners below the face or within
/// `margin` above it.
fn clipped(
    reference: (usize, &Pose, [f64; 3]),
    incident: (usize, &Pose, [f64; 3]),
    k: usize,
    margin: f64,
) -> Vec<Contact> {
    let ((ir, pr, hr), (ii, pi, hi)) = (reference, incident);
    let mut n: V = pr.rotation.column(k).into_owned();
    if n.dot(&(pi.centre - pr.centre)) < 0.0 {
        n = -n;
    }
    let j = (0..3).max_by(|&a, &b| n.dot(&pi.rotation.column(a)).abs().total_cmp(&n.dot(&pi.rotation.column(b)).abs()));
    let j = j.expect("an axis");
    let axis: V = pi.rotation.column(j).into_owned();
    let face_centre = pi.centre - axis * (hi[j] * n.dot(&axis).signum());
    let (u, w) = ((j + 1) % 3, (j + 2) % 3);
    let (eu, ew): (V, V) = (pi.rotation.column(u) * hi[u], pi.rotation.column(w) * hi[w]);
    let mut polygon = vec![face_centre + eu + ew, face_centre - eu + ew, face_centre - eu - ew, face_centre + eu - ew];
    for side in (0..3).filter(|&s| s != k) {
        let s: V = pr.rotation.column(side).into_owned();
        let c = s.dot(&pr.centre);
        polygon = clip(&polygon, &s, c + hr[side]);
        polygon = clip(&polygon, &(-s), -c + hr[side]);
    }
    let top = n.dot(&pr.centre) + hr[k];
    let points: Vec<(V, f64)> =
        polygon.into_iter().map(|p| (p, top - n.dot(&p))).filter(|(_, depth)| *depth > -margin).collect();
    four(points, &n).into_iter().map(|(p, depth)| (ir, ii, p, n, depth)).collect()
}

/// At most four of a manifold's points that hold it as well: the deepest, the farthest from
/// it, and the two that span the most area on either side of their line. Clipping nearly equal
/// faces also makes points along their edges, which come and go from step to step; four
/// corners carry the same load steadily.
fn four(points: Vec<(V, f64)>, n: &V) -> Vec<(V, f64)> {
    if points.len() <= 4 {
        return points;
    }
    let most = |score: &dyn Fn(&(V, f64)) -> f64| {
        (0..points.len()).max_by(|&a, &b| score(&points[a]).total_cmp(&score(&points[b]))).expect("points")
    };
    let a = most(&|p| p.1);
    let b = most(&|p| (p.0 - points[a].0).norm_squared());
    let side = |p: &(V, f64)| (points[b].0 - points[a].0).cross(&(p.0 - points[a].0)).dot(n);
    let (c, d) = (most(&|p| side(p)), most(&|p| -side(p)));
    let mut kept = vec![a, b];
    kept.extend([c, d].into_iter().filter(|&i| side(&points[i]).abs() > 0.0));
    kept.dedup();
    kept.into_iter().map(|i| points[i]).collect()
}

/// The part of a convex polygon with s·p ≤ c (Sutherland–Hodgman, one plane).
fn clip(polygon: &[V], s: &V, c: f64) -> Vec<V> {
    let mut out = vec![];
    for (n, p) in polygon.iter().enumerate() {
        let q = polygon[(n + 1) % polygon.len()];
        let (dp, dq) = (s.dot(p) - c, s.dot(&q) - c);
        if dp <= 0.0 {
            out.push(*p);
        }
        if (dp < 0.0) != (dq < 0.0) && dp != dq {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(centre: [f64; 3], turned: f64) -> Pose {
        let rotation = UnitQuaternion::from_axis_angle(&V::y_axis(), turned).to_rotation_matrix().into_inner();
        Pose { centre: V::from(centre), rotation }
    }

    #[test]
    fn a_box_resting_on_a_box_touches_at_four_corners() {
        let poses = [pose([0.0; 3], 0.0), pose([0.0, 0.999, 0.0], 0.0)];
        let c = boxes((0, &poses[0], [0.5; 3]), (1, &poses[1], [0.5; 3]), 0.01);
        assert_eq!(c.len(), 4);
        for (_, _, p, n, depth) in c {
            assert!((n - V::y()).norm() < 1e-12 && (depth - 0.001).abs() < 1e-12 && (p.y - 0.499).abs() < 1e-12);
        }
    }

    #[test]
    fn a_box_half_over_an_edge_touches_where_the_faces_overlap() {
        let poses = [pose([0.0; 3], 0.0), pose([0.6, 0.99, 0.0], 0.0)];
        let c = boxes((0, &poses[0], [0.5; 3]), (1, &poses[1], [0.5; 3]), 0.01);
        let xs: Vec<f64> = c.iter().map(|t| t.2.x).collect();
        assert_eq!(c.len(), 4);
        assert!(xs.iter().all(|x| (0.1 - 1e-12..=0.5 + 1e-12).contains(x)), "{xs:?}");
    }

    #[test]
    fn a_turned_box_on_a_box_keeps_four_points() {
        // a quarter-turned square on a square clips to an octagon: four of its corners hold it
        let poses = [pose([0.0; 3], 0.0), pose([0.0, 0.999, 0.0], 0.3)];
        let c = boxes((0, &poses[0], [0.5; 3]), (1, &poses[1], [0.5; 3]), 0.01);
        assert_eq!(c.len(), 4);
        let spread = c.iter().map(|t| t.2.xz().norm()).fold(f64::INFINITY, f64::min);
        assert!(spread > 0.45, "the points are corners of the overlap, not mid-edge: {spread}");
    }

    #[test]
    fn boxes_apart_or_turned_apart_do_not_touch() {
        let poses = [pose([0.0; 3], 0.0), pose([1.1, 0.0, 0.0], 0.0), pose([1.3, 0.0, 0.0], 0.785)];
        assert!(boxes((0, &poses[0], [0.5; 3]), (1, &poses[1], [0.5; 3]), 0.01).is_empty());
        // a box turned 45° about y reaches 0.707 along x: 1.3 is clear of 0.5 + 0.707
        assert!(boxes((0, &poses[0], [0.5; 3]), (2, &poses[2], [0.5; 3]), 0.01).is_empty());
    }

    /// The pairs the grid finds, in order.
    fn near(solids: &Solids, poses: &[Pose]) -> Vec<(usize, usize)> {
        let balls: Vec<(usize, f64)> =
            (0..poses.len()).filter_map(|i| solids.solids[i].map(|s| (i, s.extent.reach() + solids.margin))).collect();
        let grid = Grid::of(&balls, poses);
        let mut near = vec![];
        balls
            .iter()
            .flat_map(|&(i, r)| grid.after(i, r, &mut near).iter().map(move |&j| (i, j)).collect::<Vec<_>>())
            .collect()
    }

    /// A centre at NaN or infinity (a state the run is about to refuse) does not break the grid:
    /// the finite neighbours still meet.
    #[test]
    fn a_non_finite_centre_leaves_the_grid_whole() {
        let ball = Some(Solid { extent: Extent::Ball(0.5), friction: 0.5 });
        let solids = Solids { solids: vec![ball; 4], floor: None, pins: vec![], margin: 0.01 };
        for odd in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let poses =
                [pose([0.0; 3], 0.0), pose([odd, 0.0, 0.0], 0.0), pose([0.9, 0.0, 0.0], 0.0), pose([5.0; 3], 0.0)];
            assert_eq!(near(&solids, &poses), vec![(0, 2)]);
        }
    }

    #[test]
    fn a_tilted_box_touches_the_floor_at_its_lowest_corner() {
        let p = Pose {
            centre: V::new(0.0, 0.67, 0.0),
            rotation: UnitQuaternion::from_axis_angle(&V::z_axis(), 0.5).to_rotation_matrix().into_inner(),
        };
        let c: Vec<_> = on_floor(Some(Extent::Cuboid([0.5; 3])), &p, 0.0, 0.01).collect();
        let lowest = corners(&p, [0.5; 3]).iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
        assert_eq!(c.len(), 2);
        assert!(c.iter().all(|(q, d)| (q.y - lowest).abs() < 1e-12 && (*d + lowest).abs() < 1e-12));
    }

    proptest::proptest! {
        /// The grid finds the pairs that testing every pair finds, in the same order, on one thread
        /// and on a pool: solids of mixed sizes, point masses among them, one sometimes far off
        /// (which makes the cells large) or flat along an axis with the others (a thin span).
        #[test]
        fn the_grid_finds_every_near_pair(
            bodies in proptest::collection::vec((proptest::array::uniform3(-4.0f64..4.0), 0.05f64..1.5, 0u8..3), 2..60),
            outlier in proptest::option::of(1e3f64..1e9),
            flat in proptest::bool::ANY,
        ) {
            let solids: Vec<Option<Solid>> = bodies
                .iter()
                .map(|&(_, size, kind)| match kind {
                    0 => Some(Solid { extent: Extent::Ball(size), friction: 0.5 }),
                    1 => Some(Solid { extent: Extent::Cuboid([size, 0.5 * size, 0.1]), friction: 0.5 }),
                    _ => None,
                })
                .collect();
            let mut poses: Vec<Pose> = bodies
                .iter()
                .map(|&(c, _, _)| pose([c[0], if flat { 0.0 } else { c[1] }, c[2]], c[2]))
                .collect();
            if let Some(far) = outlier {
                poses[0].centre.x = far;
            }
            let solids = Solids { solids, floor: None, pins: vec![], margin: 0.01 };
            let reach = |i: usize| solids.solids[i].map(|s| s.extent.reach() + solids.margin);
            let mut every = vec![];
            for i in 0..poses.len() {
                for j in i + 1..poses.len() {
                    if let (Some(ri), Some(rj)) = (reach(i), reach(j)) {
                        if (poses[j].centre - poses[i].centre).norm() <= ri + rj {
                            every.push((i, j));
                        }
                    }
                }
            }
            proptest::prop_assert_eq!(near(&solids, &poses), every);
            // and the contacts they make, with a floor under them, found alone and on a pool
            let solids = Solids { floor: Some(Floor { y: -1.0, friction: None }), ..solids };
            let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().expect("a pool");
            proptest::prop_assert_eq!(solids.touching(&poses, Some(&pool)), solids.touching(&poses, None));
        }

        /// The floor's contacts do not depend on where along it a body stands or how it is
        /// turned about the vertical: the same depths, in some order.
        #[test]
        fn floor_contacts_are_the_same_anywhere_along_it(
            tilt in proptest::array::uniform3(-1.0f64..1.0), angle in -1.0f64..1.0, y in 0.3f64..0.9,
            shift in proptest::array::uniform2(-50.0f64..50.0), yaw in -3.0f64..3.0,
        ) {
            let Some(axis) = nalgebra::Unit::try_new(V::from(tilt), 0.1) else { return Ok(()) };
            let turned = UnitQuaternion::from_axis_angle(&axis, angle);
            let at = |q: UnitQuaternion<f64>, x: f64, z: f64| {
                let p = Pose { centre: V::new(x, y, z), rotation: q.to_rotation_matrix().into_inner() };
                let mut d: Vec<f64> = on_floor(Some(Extent::Cuboid([0.5, 0.3, 0.2])), &p, 0.0, 0.05).map(|c| c.1).collect();
                d.sort_by(f64::total_cmp);
                d
            };
            let here = at(turned, 0.0, 0.0);
            let there = at(UnitQuaternion::from_axis_angle(&V::y_axis(), yaw) * turned, shift[0], shift[1]);
            proptest::prop_assert_eq!(here.len(), there.len());
            for (a, b) in here.iter().zip(&there) {
                proptest::prop_assert!((a - b).abs() < 1e-12, "{here:?} {there:?}");
            }
        }
    }

    #[test]
    fn a_ball_on_a_box_face_and_beside_its_edge() {
        let poses = [pose([0.0; 3], 0.0), pose([0.0, 0.7, 0.0], 0.0), pose([0.6, 0.6, 0.0], 0.0)];
        let (_, _, _, n, depth) = ball_box((1, &poses[1], 0.25), (0, &poses[0], [0.5; 3]), 0.01).unwrap();
        assert!((n - V::y()).norm() < 1e-12 && (depth - 0.05).abs() < 1e-12);
        let (_, _, at, n, depth) = ball_box((2, &poses[2], 0.2), (0, &poses[0], [0.5; 3]), 0.01).unwrap();
        let s = 0.5f64.sqrt();
        assert!((n - V::new(s, s, 0.0)).norm() < 1e-12 && (depth - (0.2 - 0.02f64.sqrt())).abs() < 1e-12);
        assert!((at - V::new(0.5, 0.5, 0.0)).norm() < 1e-12);
    }
}
