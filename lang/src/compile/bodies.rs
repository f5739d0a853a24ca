//! Bodies: `entity`, `lattice` and the rigid `floor` blocks, each body checked where it is
//! written, and solids checked to start apart.

use super::{err, Compiler};
use crate::block::{value_span, word, Block, Field};
use crate::diagnostic::{Diagnostic, Span};
use crate::lattice::{self, Draw, Packing};
use crate::shape;
use lagra_checker::model::{Body, Cell, Floor, UnitSystem};
use lagra_checker::terms::Kind;
use lagra_checker::units::Dim;

/// Types every scene knows without declaring them: display sizes only.
pub(super) const BUILTIN_TYPES: &[(&str, f64)] = &[("ball_small", 0.15), ("ball", 0.3), ("ball_large", 0.6)];
const LATTICE_FIELDS: &[&str] = &["type", "kind", "density", "cells", "temperature", "seed", "velocities"];
pub(super) const ENTITY_FIELDS: &[&str] = &[
    "type",
    "position",
    "velocity",
    "mass",
    "charge",
    "colour",
    "size",
    "shape",
    "orientation",
    "angular_velocity",
    "friction",
];

/// The colour charges, weights of SU(3)'s fundamental representation (|c|² = 1/3), and the
/// antiquarks' negatives.
const COLOURS: &[(&str, [f64; 2])] = &[
    ("red", [0.5, 0.288_675_134_594_812_9]),
    ("green", [-0.5, 0.288_675_134_594_812_9]),
    ("blue", [0.0, -0.577_350_269_189_625_8]),
    ("antired", [-0.5, -0.288_675_134_594_812_9]),
    ("antigreen", [0.5, -0.288_675_134_594_812_9]),
    ("antiblue", [0.0, 0.577_350_269_189_625_8]),
];

impl<'a> Compiler<'a> {
    pub(super) fn entity(&mut self, mut b: Block<'a>) -> Result<(), Diagnostic> {
        let (template, size) = self.entity_type(&mut b, "entity")?;
        b.check_names("entity", ENTITY_FIELDS)?;
        let at = b.span;
        // a rigid body's size is its shape's, read with it (`shape::rigid`)
        let shaped = b.get("shape").is_some() || template.is_some_and(|t| t.get("shape").is_some());
        let mut field = |name: &str| b.take(name).or_else(|| template.and_then(|t| t.get(name).cloned()));
        let vec3 = |v: Vec<f64>| [v[0], v[1], v[2]];
        let position = field("position").ok_or_else(|| Diagnostic::new(at, "entity needs a position"))?;
        let x = vec3(self.rd.numbers(&position, "entity", Dim::LENGTH, 3)?);
        let v = match field("velocity") {
            Some(f) => vec3(self.rd.numbers(&f, "entity", Dim::VELOCITY, 3)?),
            None => [0.0; 3],
        };
        let (mut body, mut size) =
            self.body(&mut |name| if shaped && name == "size" { None } else { field(name) }, at, size)?;
        if let Some(r) = shape::rigid(&self.rd, &mut field, body.mass)? {
            body.moments = Some(r.moments);
            body.solid = Some(r.solid);
            self.spin0.push(r.spin);
            size = r.size;
        }
        self.solid_at.push(body.solid.map(|_| at));
        self.bodies.push(body);
        self.x0.push(x);
        self.v0.push(v);
        self.sizes.push(size);
        Ok(())
    }

    /// The `type` field: a declared template (its fields are defaults), or a built-in type (a
    /// display size).
    fn entity_type(&self, b: &mut Block<'a>, owner: &str) -> Result<(Option<&Block<'a>>, Option<f64>), Diagnostic> {
        let Some(f) = b.take("type") else { return Ok((None, None)) };
        let (name, at) = word(&f, owner)?;
        if let Some(t) = BUILTIN_TYPES.iter().find(|t| t.0 == name) {
            Ok((None, Some(t.1)))
        } else if let Some(t) = self.templates.get(name) {
            Ok((Some(t), None))
        } else {
            let mut known: Vec<&str> =
                self.templates.keys().copied().chain(BUILTIN_TYPES.iter().map(|t| t.0)).collect();
            known.sort();
            err(at, format!("unknown entity type `{name}`; known types: {}", known.join(", ")))
        }
    }

    /// Mass, charge, colour and display size from an entity's fields.
    fn body(
        &self,
        field: &mut impl FnMut(&str) -> Option<Field<'a>>,
        at: Span,
        size: Option<f64>,
    ) -> Result<(Body, f64), Diagnostic> {
        let mass =
            field("mass").ok_or_else(|| Diagnostic::new(at, "entity needs a mass (or a type that gives one)"))?;
        let mass = self.rd.positive(&mass, "entity", Dim::MASS)?;
        let charge = match field("charge") {
            Some(f) => self.rd.numbers(&f, "entity", Dim::CHARGE, 1)?[0],
            None => 0.0,
        };
        let colour = match field("colour") {
            None => [0.0; 2],
            Some(f) => {
                let (name, at) = word(&f, "entity")?;
                match COLOURS.iter().find(|c| c.0 == name) {
                    Some(c) => c.1,
                    None => {
                        let known: Vec<&str> = COLOURS.iter().map(|c| c.0).collect();
                        return err(at, format!("unknown colour `{name}`; known: {}", known.join(", ")));
                    }
                }
            }
        };
        let size = match field("size") {
            Some(f) => self.rd.positive(&f, "entity", Dim::LENGTH)?,
            None => size.unwrap_or(0.0),
        };
        Ok((Body { mass, charge, colour, moments: None, solid: None }, size))
    }

    /// `lattice { type, kind: fcc, density, cells: [nx, ny, nz], temperature, seed, velocities }`:
    /// bodies on a lattice filling a periodic box of its own, with thermal velocities
    /// (Maxwell–Boltzmann, or `velocities: uniform` like LAMMPS's `velocity create`).
    pub(super) fn lattice(&mut self, mut b: Block<'a>, at: Span) -> Result<(), Diagnostic> {
        if self.cell.is_some() {
            let what = if self.lattice {
                "second lattice: one per scene"
            } else {
                "a lattice sets the box itself: remove the box above"
            };
            return err(at, what);
        }
        b.check_names("lattice", LATTICE_FIELDS)?;
        let (template, size) = self.entity_type(&mut b, "lattice")?;
        let template =
            template.ok_or_else(|| Diagnostic::new(at, "lattice needs `type:` an entity type declared with a mass"))?;
        if let Some(f) = template.get("shape") {
            return err(f.span, "a lattice's bodies are point masses: its entity type cannot have a shape");
        }
        let kind = match b.take("kind") {
            None => Packing::Fcc,
            Some(f) => {
                let (name, at) = word(&f, "lattice")?;
                Packing::from_name(name)
                    .ok_or_else(|| Diagnostic::new(at, format!("unknown lattice kind `{name}`; known: fcc, sc")))?
            }
        };
        let need = |b: &mut Block<'a>, name: &str, what: &str| {
            b.take(name).ok_or_else(|| Diagnostic::new(at, format!("lattice needs `{name}: {what}`")))
        };
        let density =
            self.rd.positive(&need(&mut b, "density", "bodies per unit volume")?, "lattice", Dim::LENGTH.pow(-3))?;
        let cells_f = need(&mut b, "cells", "[nx, ny, nz]")?;
        let cells = self.rd.numbers(&cells_f, "lattice", Dim::NONE, 3)?;
        if let Some(c) = cells.iter().find(|c| !(**c >= 1.0 && c.fract() == 0.0 && **c <= 1000.0)) {
            return err(value_span(&cells_f), format!("lattice.cells expects whole numbers from 1 to 1000, got {c}"));
        }
        let temperature = match b.take("temperature") {
            None => 0.0,
            Some(f) if self.rd.system == UnitSystem::Reduced => self.rd.numbers(&f, "lattice", Dim::NONE, 1)?[0],
            Some(f) => {
                return err(f.span, "lattice.temperature is k_B·T in reduced units; an SI scene lists its velocities")
            }
        };
        if !(temperature >= 0.0 && temperature.is_finite()) {
            return err(at, format!("lattice.temperature must be zero or positive, got {temperature}"));
        }
        let seed = b.take("seed").map(|f| self.rd.count(&f, "lattice")).transpose()?.unwrap_or(1);
        let draw = match b.take("velocities") {
            None => Draw::Gaussian,
            Some(f) => {
                let (name, at) = word(&f, "lattice")?;
                Draw::from_name(name).ok_or_else(|| {
                    Diagnostic::new(at, format!("unknown velocity draw `{name}`; known: gaussian, uniform"))
                })?
            }
        };
        let mut field = |name: &str| template.get(name).cloned();
        let (body, size) = self.body(&mut field, at, size)?;
        let cells = [cells[0] as usize, cells[1] as usize, cells[2] as usize];
        let (bodies, need) = (kind.count(cells), kind.count(cells).saturating_mul(lattice::BYTES_PER_BODY));
        if let Some(free) = lattice::available_memory().filter(|&free| need > free) {
            let gb = |b: u64| b as f64 / 1e9;
            return err(
                value_span(&cells_f),
                format!(
                    "a lattice of {bodies} bodies would need about {:.1} GB ({} bytes a body: state, forces, neighbour list, the checker's enclosures); this process may take {:.1} GB more (the machine's free memory, its control group's and its address-space limits)",
                    gb(need),
                    lattice::BYTES_PER_BODY,
                    gb(free)
                ),
            );
        }
        // a large lattice is laid out on the run's threads, asked for only then
        let pool = match bodies as usize >= lattice::SPREAD_FROM {
            true => (self.threads)(bodies as usize),
            false => None,
        };
        let (x, side) = kind.sites(density, cells, pool);
        let v = lattice::velocities(x.len(), temperature / body.mass, seed, draw, pool);
        self.cell = Some((Cell { size: side, periodic: [true; 3] }, at));
        self.lattice = true;
        // each list grown once to its length (pushed a body at a time, 256,000 bodies cost ~40 ms
        // of copies and page faults as the lists doubled), the long ones where they are laid out
        let n = x.len();
        append(&mut self.bodies, lattice::laid(pool, n, |_| body.clone()));
        append(&mut self.solid_at, lattice::laid(pool, n, |_| None));
        append(&mut self.sizes, lattice::laid(pool, n, |_| size));
        append(&mut self.x0, x);
        append(&mut self.v0, v);
        Ok(())
    }

    /// `floor { y, friction }` with no `k`: a contact the solver keeps, not a spring.
    pub(super) fn rigid_floor(&mut self, mut b: Block, at: Span) -> Result<(), Diagnostic> {
        if self.floor.is_some() {
            return err(at, "second rigid floor");
        }
        let y = b.take("y").map(|f| self.rd.numbers(&f, "floor", Dim::LENGTH, 1)).transpose()?.map_or(0.0, |v| v[0]);
        let friction = match b.take("friction") {
            Some(f) => {
                let mu = self.rd.numbers(&f, "floor", Dim::NONE, 1)?[0];
                if !(mu >= 0.0) {
                    return err(value_span(&f), format!("floor.friction must be ≥ 0, got {mu}"));
                }
                Some(mu)
            }
            None => None,
        };
        let names = ["y", "friction"];
        let penalty: Vec<&str> = Kind::ContactFloor.spec().params.iter().map(|p| p.name).collect();
        if let Some(f) = penalty.iter().filter(|n| !names.contains(n)).find_map(|n| b.get(n)) {
            let extra = f.name;
            return err(f.span, format!("floor.{extra} belongs to a penalty floor: give `k` too (a spring), or leave it out (a rigid floor)"));
        }
        b.check_names("floor", &names)?;
        self.floor = Some((Floor { y, friction }, at));
        Ok(())
    }
}

/// `copies` after what `list` holds: taken whole where it holds nothing, so that its memory stays
/// where it was first written (on the threads that laid it out).
fn append<T>(list: &mut Vec<T>, copies: Vec<T>) {
    match list.is_empty() {
        true => *list = copies,
        false => list.extend(copies),
    }
}
