//! The canonical Lagrangian graph as the checker sees it: bodies and term instances with their
//! parameters as exact binary64 values. The kernel's fast graph is built from this, and the
//! certificate carries it, so a re-check needs nothing else.

use crate::terms::{Kind, Shape};
use crate::thermostat::Chain;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnitSystem {
    /// Numbers are in the scene's own reduced units; no physical unit may be written.
    Reduced,
    /// Numbers are in SI base units (kg, m, s, C) after conversion of any written unit.
    Si,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    pub mass: f64,
    pub charge: f64,
    /// Colour charge, a weight of SU(3)'s fundamental representation (zero: colourless).
    #[serde(default, skip_serializing_if = "colourless")]
    pub colour: [f64; 2],
    /// A rigid body's principal moments of inertia about its centre of mass (its body frame is
    /// the principal frame); none for a point mass. Its orientation and angular momentum are in
    /// each state (`Snapshot::spin`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moments: Option<[f64; 3]>,
    /// A rigid body's solid: its extent (for contacts and `no_penetration`) and friction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solid: Option<Solid>,
}

/// The solid a rigid body is, in its body frame, centred on its centre of mass.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solid {
    pub extent: Extent,
    /// Its Coulomb friction coefficient μ (a contact of two bodies takes √(μ₁μ₂)).
    pub friction: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Extent {
    /// A box's half edge lengths along the body axes.
    Cuboid([f64; 3]),
    /// A ball's radius.
    Ball(f64),
}

impl Extent {
    /// The radius of the smallest ball about the centre holding the solid.
    pub fn reach(&self) -> f64 {
        match *self {
            Extent::Cuboid(h) => h.iter().map(|c| c * c).sum::<f64>().sqrt(),
            Extent::Ball(r) => r,
        }
    }
}

/// The plane y = `y`, normal +y, as a contact the solver keeps (not a spring): nothing may
/// pass below it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Floor {
    pub y: f64,
    /// μ of its contacts; none: each body's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

fn colourless(c: &[f64; 2]) -> bool {
    *c == [0.0; 2]
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TermInstance {
    pub kind: Kind,
    /// Body indices: a bond's bodies; empty for a pairwise term (every pair); for an external
    /// term the bodies it acts on, empty for every body.
    pub sites: Vec<usize>,
    /// Parameters flattened in the order of the kind's `Spec::params`.
    pub params: Vec<f64>,
}

impl TermInstance {
    /// Whether this instance can remove energy (its kind's own rule: a bond with zero damping
    /// cannot).
    pub fn dissipates(&self) -> bool {
        self.kind.dissipates(&self.params)
    }
}

/// A holonomic distance constraint: two bodies held `length` apart, as by a massless rigid rod.
/// It does no work, so it enters no energy; the solver keeps it (RATTLE) and the
/// `constraint_satisfied` claim certifies how well.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constraint {
    pub bodies: [usize; 2],
    pub length: f64,
}

/// A box, periodic along some axes: pair and bond terms see the nearest image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cell {
    pub size: [f64; 3],
    pub periodic: [bool; 3],
}

impl Cell {
    /// How many box lengths to take off a displacement `d` along each axis to reach its nearest
    /// image: d·(1/L) rounded to the nearest integer, ties to even (one instruction, where ties
    /// away from zero take four, in every distance test of the broad phase; at a tie either
    /// image is as near), on periodic axes, 0 elsewhere. Kernel and checker both choose images
    /// with this one rule (`Images`).
    pub fn shift(cell: &Option<Cell>, d: [f64; 3]) -> [f64; 3] {
        Images::of(cell).shift(d)
    }

    /// The nearest image of the displacement `d`, in binary64 (the kernel's fast path).
    pub fn image(cell: &Option<Cell>, d: [f64; 3]) -> [f64; 3] {
        Images::of(cell).image(d)
    }
}

/// The nearest-image rule of a cell (or of open space), with the box's reciprocal lengths worked
/// out once: a loop over pairs holds one in registers instead of dividing per pair and axis.
/// Within an ulp of a tie between two images either is as near. An open axis has length and
/// reciprocal 0, so the same arithmetic takes nothing off it, without a branch.
#[derive(Clone, Copy, Debug)]
pub struct Images {
    size: [f64; 3],
    inverse: [f64; 3],
}

impl Images {
    pub fn of(cell: &Option<Cell>) -> Images {
        let open = Images { size: [0.0; 3], inverse: [0.0; 3] };
        cell.map_or(open, |c| Images {
            size: std::array::from_fn(|a| if c.periodic[a] { c.size[a] } else { 0.0 }),
            inverse: std::array::from_fn(|a| if c.periodic[a] { 1.0 / c.size[a] } else { 0.0 }),
        })
    }

    /// `Cell::shift` (±0 on open axes).
    #[inline]
    pub fn shift(&self, d: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| (d[a] * self.inverse[a]).round_ties_even())
    }

    /// `Cell::image`: d − k·L (d itself on open axes, but for the sign of a zero).
    #[inline]
    pub fn image(&self, d: [f64; 3]) -> [f64; 3] {
        let k = self.shift(d);
        std::array::from_fn(|a| d[a] - k[a] * self.size[a])
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    pub units: UnitSystem,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell: Option<Cell>,
    pub bodies: Vec<Body>,
    pub terms: Vec<TermInstance>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<Constraint>,
    /// A Nosé–Hoover chain: its links are in every state (`Snapshot::chain`) and its energy in H.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermostat: Option<Chain>,
    /// A rigid floor (contacts; no energy).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<Floor>,
    /// The joints, as the points they hold together (no energy: a joint does no work).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pins: Vec<Pin>,
}

/// A point of rigid body b, `on_b` in its frame, held at a point of rigid body a (`on_a` in a's
/// frame) or, where a is none, at the world point `on_a`. A ball joint is one pin; a hinge two,
/// on its axis, so that it turns about that axis alone.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pin {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<usize>,
    pub b: usize,
    pub on_a: [f64; 3],
    pub on_b: [f64; 3],
}

impl Pin {
    /// Whether it holds bodies i and j together (either way round). Two bodies a joint holds
    /// may meet at it: they make no contact in the kernel, and `no_penetration` does not measure
    /// their overlap.
    pub fn joins(&self, i: usize, j: usize) -> bool {
        self.a == Some(i) && self.b == j || self.a == Some(j) && self.b == i
    }
}

/// A state of the system as the kernel produced it, exactly.
#[derive(Clone, Copy, Debug)]
pub struct Snapshot<'a> {
    pub step: u64,
    pub t: f64,
    pub x: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    /// The thermostat's links (η_j, ξ_j), empty without one.
    pub chain: &'a [[f64; 2]],
    /// Each rigid body's spin, in body order: its orientation, a quaternion (w, x, y, z) from
    /// the body frame to the world's, read as q/|q|, then its angular momentum π in the body
    /// frame. Empty without rigid bodies.
    pub spin: &'a [[f64; 7]],
}

impl Model {
    /// Rejects a model the definitions cannot be evaluated on.
    pub fn validate(&self) -> Result<(), String> {
        if self.bodies.is_empty() {
            return Err("the scene has no bodies".into());
        }
        if let Some(c) = &self.cell {
            if c.size.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
                return Err(format!("the box size must be finite and positive, got {:?}", c.size));
            }
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if !(b.mass.is_finite() && b.mass > 0.0) {
                return Err(format!("body {i}: mass must be finite and positive, got {}", b.mass));
            }
            if !b.charge.is_finite() || b.colour.iter().any(|c| !c.is_finite()) {
                return Err(format!("body {i}: charge must be finite, got {}", b.charge));
            }
            if let Some(m) = b.moments.filter(|m| !m.iter().all(|c| c.is_finite() && *c > 0.0)) {
                return Err(format!("body {i}: moments of inertia must be finite and positive, got {m:?}"));
            }
            if b.solid.is_some() != b.moments.is_some() {
                return Err(format!("body {i}: a rigid body has both moments and a solid, a point mass neither"));
            }
            if let Some(s) = &b.solid {
                let sizes = match s.extent {
                    Extent::Cuboid(h) => h.to_vec(),
                    Extent::Ball(r) => vec![r],
                };
                if !sizes.iter().all(|c| c.is_finite() && *c > 0.0) || !(s.friction.is_finite() && s.friction >= 0.0) {
                    return Err(format!(
                        "body {i}: a solid needs a finite positive extent and a finite μ ≥ 0, got {s:?}"
                    ));
                }
            }
        }
        for (n, t) in self.terms.iter().enumerate() {
            let spec = t.kind.spec();
            let name = spec.name;
            if t.params.len() != spec.width() {
                return Err(format!("term {n} ({name}): {} parameters, expected {}", t.params.len(), spec.width()));
            }
            if let Some(p) = t.params.iter().find(|p| !p.is_finite()) {
                return Err(format!("term {n} ({name}): non-finite parameter {p}"));
            }
            let mut at = 0;
            for p in spec.params {
                if p.positive && t.params[at..at + p.len].iter().any(|&c| c <= 0.0) {
                    return Err(format!("term {n} ({name}): {} must be positive", p.name));
                }
                at += p.len;
            }
            if let Err((p, why)) = t.kind.accepts(&t.params) {
                return Err(format!("term {n} ({name}): {p} {why}"));
            }
            let sites_ok = match spec.shape {
                Shape::Bond(arity) => t.sites.len() == arity,
                Shape::Pairwise | Shape::Density => t.sites.is_empty(),
                // every body, or only those listed
                Shape::External => true,
            };
            if !sites_ok {
                return Err(format!("term {n} ({name}): wrong number of sites ({})", t.sites.len()));
            }
            if let Some(&s) = t.sites.iter().find(|&&s| s >= self.bodies.len()) {
                return Err(format!("term {n} ({name}): body {s} does not exist ({} bodies)", self.bodies.len()));
            }
        }
        for (n, c) in self.constraints.iter().enumerate() {
            let [i, j] = c.bodies;
            if i == j || i.max(j) >= self.bodies.len() {
                return Err(format!("constraint {n}: needs two different bodies of the {}", self.bodies.len()));
            }
            if !(c.length.is_finite() && c.length > 0.0) {
                return Err(format!("constraint {n}: length must be finite and positive, got {}", c.length));
            }
        }
        if !self.pins.is_empty() && self.cell.as_ref().is_some_and(|c| c.periodic.iter().any(|&p| p)) {
            return Err("joints in a periodic box are not supported (a pin's gap would need the nearest image)".into());
        }
        for (n, p) in self.pins.iter().enumerate() {
            let rigid = |i: usize| self.bodies.get(i).is_some_and(|b| b.moments.is_some());
            if !rigid(p.b) || p.a.is_some_and(|a| a == p.b || !rigid(a)) {
                return Err(format!(
                    "joint pin {n}: joins two different rigid bodies (or one and the world), got {:?} and {}",
                    p.a, p.b
                ));
            }
            if !p.on_a.iter().chain(&p.on_b).all(|c| c.is_finite()) {
                return Err(format!("joint pin {n}: its points must be finite, got {:?} and {:?}", p.on_a, p.on_b));
            }
        }
        if let Some(f) =
            self.floor.filter(|f| !f.y.is_finite() || f.friction.is_some_and(|m| !(m.is_finite() && m >= 0.0)))
        {
            return Err(format!("the floor needs a finite y and a finite μ ≥ 0, got {f:?}"));
        }
        self.thermostat.as_ref().map_or(Ok(()), Chain::validate)
    }

    /// The links a state of this model holds.
    pub fn links(&self) -> usize {
        self.thermostat.as_ref().map_or(0, |c| c.masses.len())
    }

    /// The rigid bodies' moments, in body order: what each of a state's `spin` belongs to.
    pub fn rigid(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        self.bodies.iter().filter_map(|b| b.moments)
    }

    /// Rejects a state that does not fit the model or holds a non-finite number.
    pub fn check_state(&self, s: &Snapshot) -> Result<(), String> {
        let n = self.bodies.len();
        if s.x.len() != n || s.v.len() != n {
            return Err(format!("state has {} positions and {} velocities for {n} bodies", s.x.len(), s.v.len()));
        }
        if !s.t.is_finite() {
            return Err(format!("step {}: time is {}", s.step, s.t));
        }
        for (i, (x, v)) in s.x.iter().zip(s.v).enumerate() {
            if x.iter().chain(v).any(|c| !c.is_finite()) {
                return Err(format!("step {}: body {i} has a non-finite coordinate ({x:?}, {v:?})", s.step));
            }
        }
        if s.chain.len() != self.links() {
            return Err(format!("state has {} thermostat links for a chain of {}", s.chain.len(), self.links()));
        }
        if let Some(l) = s.chain.iter().find(|l| l.iter().any(|c| !c.is_finite())) {
            return Err(format!("step {}: a thermostat link is not finite ({l:?})", s.step));
        }
        if s.spin.len() != self.rigid().count() {
            return Err(format!("state has {} spins for {} rigid bodies", s.spin.len(), self.rigid().count()));
        }
        if let Some(r) = s.spin.iter().find(|r| r.iter().any(|c| !c.is_finite()) || r[..4] == [0.0; 4]) {
            return Err(format!(
                "step {}: a rigid body's spin is not finite or its orientation is zero ({r:?})",
                s.step
            ));
        }
        Ok(())
    }
}
