//! From the parse tree to a [`Scene`]: templates resolved, terms looked up in the checker's
//! vocabulary, every number checked for dimension and converted, every index checked.

use super::block::{flags, typed, value_span, word, Block, Field, Reader};
use super::diagnostic::{Diagnostic, Span};
use super::lattice::{self, Draw, Packing};
use super::shape;
use super::{Pair, Rule};
use crate::constraints::{Constraints, Tolerance};
use crate::contact::Solids;
use crate::predict::{Prediction, PredictionKind};
use crate::scene::{NoetherRequest, Sampling, Scene, Solver};
use crate::solvers::{Integrator, Settings};
use crate::tail::Tail;
use crate::thermostat::{self, Bath, Thermostat};
use lagra_checker::claims::{Between, Claim, ClaimKind};
use lagra_checker::model::{Body, Cell, Constraint, Floor, Model, TermInstance, UnitSystem};
use lagra_checker::terms::{Kind, Shape};
use lagra_checker::units::Dim;
use std::collections::HashMap;

/// Types every scene knows without declaring them: display sizes only.
const BUILTIN_TYPES: &[(&str, f64)] = &[("ball_small", 0.15), ("ball", 0.3), ("ball_large", 0.6)];
const LATTICE_FIELDS: &[&str] = &["type", "kind", "density", "cells", "temperature", "seed", "velocities"];
const ENTITY_FIELDS: &[&str] = &[
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
/// Run length when the solver gives neither `steps` nor `duration`.
const DEFAULT_STEPS: u64 = 5000;

/// A `solver` block as written: the integrator is settled once the whole scene is known (the
/// default depends on its constraints), and so are the settings it may take.
struct SolverBlock {
    integrator: Option<(Integrator, Span)>,
    /// `equilibrate` (a time), `sample_every`, `tail_corrections`.
    equilibrate: Option<f64>,
    sample_every: Option<u64>,
    /// Where `tail_corrections: true` was asked for.
    tail_corrections: Option<Span>,
    /// `tol`, `iterations`, `window`, each with where it was written.
    settings: Vec<(&'static str, f64, Span)>,
    dt: f64,
    steps: u64,
    steps_per_frame: u64,
    at: Span,
}

fn err<T>(span: impl Into<Span>, msg: impl Into<String>) -> Result<T, Diagnostic> {
    Err(Diagnostic::new(span.into(), msg))
}

struct Compiler<'a> {
    rd: Reader,
    templates: HashMap<&'a str, Block<'a>>,
    bodies: Vec<Body>,
    x0: Vec<[f64; 3]>,
    v0: Vec<[f64; 3]>,
    spin0: Vec<[f64; 7]>,
    sizes: Vec<f64>,
    terms: Vec<TermInstance>,
    /// Where each bond's indices were written, checked once all entities are known.
    indices: Vec<Vec<(usize, Span)>>,
    claims: Vec<Claim>,
    claim_spans: Vec<Span>,
    noether: Option<NoetherRequest>,
    predictions: Vec<(PredictionKind, Option<f64>, Span)>,
    solver: Option<SolverBlock>,
    /// The thermostat as declared: kT, what it is, where.
    thermostat: Option<(f64, Thermostat, Option<usize>, Span)>,
    /// Each `constraint [i, j] { length }`: its bodies, its length if given, where it stands.
    constraints: Vec<([usize; 2], Option<f64>, Span)>,
    cell: Option<(Cell, Span)>,
    /// Where each term was written, for errors found once the whole scene is known, and its line.
    term_at: Vec<Span>,
    term_line: Vec<usize>,
    description: Option<String>,
    domain: Option<String>,
    /// Whether the box came from a lattice.
    lattice: bool,
    /// A rigid floor (`floor` without `k`) and where it stands.
    floor: Option<(Floor, Span)>,
    /// Where each rigid body was declared, in body order (none for the others).
    solid_at: Vec<Option<Span>>,
}

pub fn scene(pair: Pair) -> Result<Scene, Diagnostic> {
    let scene_span: Span = pair.as_span().into();
    let mut inner = pair.into_inner();
    let name = inner.next().expect("scene name").as_str().to_string();
    let items: Vec<Pair> = inner.collect();

    let mut system = None;
    for u in items.iter().filter(|p| p.as_rule() == Rule::units) {
        let w = u.clone().into_inner().nth(1).expect("units name");
        if system.is_some() {
            return err(u.as_span(), "units declared twice");
        }
        system = Some(match w.as_str() {
            "reduced" => UnitSystem::Reduced,
            "si" => UnitSystem::Si,
            other => return err(w.as_span(), format!("unknown unit system `{other}`; expected reduced or si")),
        });
    }
    let mut c = Compiler {
        rd: Reader { system: system.unwrap_or(UnitSystem::Reduced) },
        templates: HashMap::new(),
        bodies: vec![],
        x0: vec![],
        v0: vec![],
        spin0: vec![],
        sizes: vec![],
        terms: vec![],
        indices: vec![],
        claims: vec![],
        claim_spans: vec![],
        noether: None,
        predictions: vec![],
        solver: None,
        thermostat: None,
        constraints: vec![],
        cell: None,
        floor: None,
        solid_at: vec![],
        term_at: vec![],
        term_line: vec![],
        description: None,
        domain: None,
        lattice: false,
    };
    for item in items {
        c.item(item)?;
    }
    c.finish(name, scene_span)
}

impl<'a> Compiler<'a> {
    fn item(&mut self, item: Pair<'a>) -> Result<(), Diagnostic> {
        let span: Span = item.as_span().into();
        let rule = item.as_rule();
        let mut parts = item.into_inner();
        let mut next = || parts.next();
        match rule {
            Rule::units => Ok(()),
            Rule::uses => {
                self.domain = Some(next().and(next()).expect("domain").as_str().to_string());
                Ok(())
            }
            Rule::description => {
                if self.description.is_some() {
                    return err(span, "second description");
                }
                let s = next().and(next()).expect("string").into_inner().next().expect("body");
                self.description = Some(s.as_str().to_string());
                Ok(())
            }
            Rule::template => {
                let name = next().and(next()).expect("template name");
                let block = Block::read(next(), span)?;
                block.check_names(&format!("entity {}", name.as_str()), &ENTITY_FIELDS[1..])?;
                if self.templates.contains_key(name.as_str()) || BUILTIN_TYPES.iter().any(|t| t.0 == name.as_str()) {
                    return err(name.as_span(), format!("entity type `{}` is defined twice", name.as_str()));
                }
                self.templates.insert(name.as_str(), block);
                Ok(())
            }
            Rule::entity => {
                let block = Block::read(next().and(next()), span)?;
                self.entity(block)
            }
            Rule::bond => {
                let kw = next().and(next()).expect("bond keyword");
                let idx = next().expect("indices");
                let kind = lookup(&kw, |s| matches!(s, Shape::Bond(_)), "bond")?;
                let indices = listed(&idx, kind.name(), kind.spec().shape.arity())?;
                let params = self.params(kind, Block::read(next(), kw.as_span().into())?, kw.as_span().into())?;
                self.terms.push(TermInstance { kind, sites: indices.iter().map(|i| i.0).collect(), params });
                self.term_at.push(kw.as_span().into());
                self.term_line.push(kw.line_col().0);
                self.indices.push(indices);
                Ok(())
            }
            Rule::constraint => {
                let kw = next().expect("constraint keyword");
                let indices = listed(&next().expect("indices"), "constraint", 2)?;
                let mut b = Block::read(next(), kw.as_span().into())?;
                let length = b.take("length").map(|f| self.rd.positive(&f, "constraint", Dim::LENGTH)).transpose()?;
                b.check_names("constraint", &["length"])?;
                self.constraints.push(([indices[0].0, indices[1].0], length, span));
                self.indices.push(indices);
                Ok(())
            }
            Rule::interaction | Rule::external => {
                let kw = if rule == Rule::interaction { next().and(next()) } else { next() }.expect("keyword");
                let (what, shape) = if rule == Rule::interaction {
                    ("interaction", Shape::Pairwise)
                } else {
                    ("term", Shape::External)
                };
                let kind = lookup(&kw, |s| s == shape, what)?;
                let mut block = Block::read(next(), kw.as_span().into())?;
                if kind == Kind::ContactFloor && block.get("k").is_none() {
                    return self.rigid_floor(block, kw.as_span().into());
                }
                // an external term acts on every body, or only on those listed in `on`
                let on = match block.take("on") {
                    Some(f) if shape == Shape::External => self.rd.body_list(&f, kind.name())?,
                    Some(f) => {
                        return err(
                            f.span,
                            format!("{} acts on every pair; `on` belongs to external terms", kind.name()),
                        )
                    }
                    None => vec![],
                };
                let params = self.params(kind, block, kw.as_span().into())?;
                self.terms.push(TermInstance { kind, sites: on.iter().map(|i| i.0).collect(), params });
                self.term_at.push(kw.as_span().into());
                self.term_line.push(kw.line_col().0);
                self.indices.push(on);
                Ok(())
            }
            Rule::expect => {
                let name = next().expect("claim name");
                let block = Block::read(next(), name.as_span().into())?;
                self.expect(name, block)
            }
            Rule::predict => {
                let name = next().expect("prediction name");
                let mut block = Block::read(next(), name.as_span().into())?;
                let kind = PredictionKind::from_name(name.as_str()).ok_or_else(|| {
                    let known: Vec<_> = PredictionKind::ALL.iter().map(|k| k.name()).collect();
                    Diagnostic::new(
                        name.as_span().into(),
                        format!("unknown prediction `{}`; known: {}", name.as_str(), known.join(", ")),
                    )
                })?;
                let tol = block.take("tol").map(|f| self.rd.positive(&f, name.as_str(), Dim::NONE)).transpose()?;
                block.check_names(name.as_str(), &[])?;
                self.predictions.push((kind, tol, name.as_span().into()));
                Ok(())
            }
            Rule::lattice => {
                let block = Block::read(next().and(next()), span)?;
                self.lattice(block, span)
            }
            Rule::cell => {
                if self.cell.is_some() {
                    return err(
                        span,
                        if self.lattice { "the lattice above sets the box: remove this box" } else { "second box" },
                    );
                }
                let mut b = Block::read(next().and(next()), span)?;
                let size =
                    b.take("size").ok_or_else(|| Diagnostic::new(span, "box needs a size: `size: [x, y, z]`"))?;
                let lengths = self.rd.numbers(&size, "box", Dim::LENGTH, 3)?;
                if let Some(l) = lengths.iter().find(|l| **l <= 0.0) {
                    return err(value_span(&size), format!("box.size must be positive, got {l}"));
                }
                let periodic = b.take("periodic").map(|f| flags::<3>(&f, "box")).transpose()?.unwrap_or([true; 3]);
                b.check_names("box", &[])?;
                self.cell = Some((Cell { size: [lengths[0], lengths[1], lengths[2]], periodic }, span));
                Ok(())
            }
            Rule::thermostat => {
                let kw = next().and(next()).expect("thermostat kind");
                let block = Block::read(next(), kw.as_span().into())?;
                if self.thermostat.is_some() {
                    return err(span, "second thermostat: one per scene");
                }
                self.thermostat = Some(self.thermostat(&kw, block)?);
                Ok(())
            }
            Rule::solver => {
                if self.solver.is_some() {
                    return err(span, "second solver block");
                }
                let block = Block::read(next().and(next()), span)?;
                self.solver = Some(self.solver(block)?);
                Ok(())
            }
            r => unreachable!("grammar produced {r:?} as an item"),
        }
    }

    fn entity(&mut self, mut b: Block<'a>) -> Result<(), Diagnostic> {
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
    fn lattice(&mut self, mut b: Block<'a>, at: Span) -> Result<(), Diagnostic> {
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
                    "a lattice of {bodies} bodies would need about {:.1} GB ({} bytes a body: state, forces, neighbour list, the checker's enclosures); this machine has {:.1} GB free",
                    gb(need),
                    lattice::BYTES_PER_BODY,
                    gb(free)
                ),
            );
        }
        let (x, side) = kind.sites(density, cells);
        let v = lattice::velocities(x.len(), temperature / body.mass, seed, draw);
        self.cell = Some((Cell { size: side, periodic: [true; 3] }, at));
        self.lattice = true;
        for (x, v) in x.into_iter().zip(v) {
            self.bodies.push(body.clone());
            self.solid_at.push(None);
            self.x0.push(x);
            self.v0.push(v);
            self.sizes.push(size);
        }
        Ok(())
    }

    /// `floor { y, friction }` with no `k`: a contact the solver keeps, not a spring.
    fn rigid_floor(&mut self, mut b: Block, at: Span) -> Result<(), Diagnostic> {
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

    /// The term's parameters in the order of its spec, each checked against its dimension.
    fn params(&self, kind: Kind, mut b: Block, at: Span) -> Result<Vec<f64>, Diagnostic> {
        let spec = kind.spec();
        let mut out = vec![];
        for p in spec.params {
            match (b.take(p.name), p.default) {
                (Some(f), _) => out.extend(self.rd.numbers(&f, spec.name, p.dim, p.len)?),
                (None, Some(d)) => out.extend(std::iter::repeat_n(d, p.len)),
                (None, None) => return err(at, format!("{} needs `{}` ({})", spec.name, p.name, typed(p.dim))),
            }
        }
        let names: Vec<&str> = spec.params.iter().map(|p| p.name).collect();
        b.check_names(spec.name, &names)?;
        Ok(out)
    }

    fn expect(&mut self, name: Pair, mut b: Block) -> Result<(), Diagnostic> {
        let at: Span = name.as_span().into();
        if name.as_str() == "noether" {
            return self.noether(at, b);
        }
        let kind = ClaimKind::from_name(name.as_str()).ok_or_else(|| {
            let known: Vec<_> = ClaimKind::ALL.iter().map(|k| k.name()).chain(["noether"]).collect();
            Diagnostic::new(at, format!("unknown claim `{}`; known claims: {}", name.as_str(), known.join(", ")))
        })?;
        if !kind.repeatable() && self.claims.iter().any(|c| c.kind == kind) {
            return err(at, format!("{} is declared twice", kind.name()));
        }
        let owner = kind.name();
        let mut claim = Claim::new(kind, None, 1);
        // a resting claim's tolerance is a speed, written `max_speed`
        let tol_name = if kind == ClaimKind::Resting { "max_speed" } else { "tol" };
        if let (Some(f), Some(dim)) = (b.take(tol_name), kind.tol_dim()) {
            claim.tol = Some(self.rd.positive(&f, owner, dim)?);
        }
        if kind.needs_tol() && claim.tol.is_none() {
            let example = match kind {
                ClaimKind::Resting => "`{ max_speed: 0.01, after: 2 }` (a speed, a time)",
                ClaimKind::NoPenetration => "`{ tol: 0.001 }` (a length)",
                _ => "`{ tol: 1e-5 }` (relative)",
            };
            return err(at, format!("{owner} needs a tolerance: {example}"));
        }
        if kind == ClaimKind::Resting {
            if let Some(f) = b.take("after") {
                let t = self.rd.numbers(&f, owner, Dim::TIME, 1)?[0];
                if !(t >= 0.0) {
                    return err(value_span(&f), format!("resting.after must be a time ≥ 0, got {t}"));
                }
                claim.after = Some(t);
            }
        }
        if kind.is_dynamic() {
            if let Some(f) = b.take("every") {
                claim.every = self.rd.count(&f, owner)?;
            }
        }
        let mut allowed = match kind {
            ClaimKind::DimensionalConsistency => vec![],
            ClaimKind::Distance => vec!["between", "min", "max", "every"],
            ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation => vec!["tol", "every", "axes"],
            ClaimKind::EnergyConservation | ClaimKind::ConstraintSatisfied | ClaimKind::NoPenetration => {
                vec!["tol", "every"]
            }
            ClaimKind::Resting => vec!["every"],
        };
        if allowed.contains(&"axes") {
            if let Some(f) = b.take("axes") {
                claim.axes = Some(axes(&f, owner)?);
            }
        }
        if kind == ClaimKind::Distance {
            let pair = b.take("between").ok_or_else(|| Diagnostic::new(at, "distance needs `between: [i, j]`"))?;
            let bodies = self.rd.indices(&pair, owner, 2)?;
            let mut bound = |name: &str| -> Result<f64, Diagnostic> {
                let f =
                    b.take(name).ok_or_else(|| Diagnostic::new(at, format!("distance needs `{name}` (a length)")))?;
                let x = self.rd.numbers(&f, owner, Dim::LENGTH, 1)?[0];
                if x < 0.0 {
                    return err(value_span(&f), format!("distance.{name} must not be negative"));
                }
                Ok(x)
            };
            let (min, max) = (bound("min")?, bound("max")?);
            if min > max {
                return err(at, format!("distance: min {min} is above max {max}"));
            }
            if bodies[0].0 == bodies[1].0 {
                return err(bodies[1].1, "distance needs two different bodies");
            }
            claim.between = Some(Between { bodies: [bodies[0].0, bodies[1].0], min, max });
            self.indices.push(bodies);
            allowed.clear();
        }
        b.check_names(owner, &allowed)?;
        self.claims.push(claim);
        self.claim_spans.push(at);
        Ok(())
    }

    /// `@expect noether { tol, every }`.
    fn noether(&mut self, at: Span, mut b: Block) -> Result<(), Diagnostic> {
        if self.noether.is_some() {
            return err(at, "noether is declared twice");
        }
        let tol = b.take("tol").map(|f| self.rd.positive(&f, "noether", Dim::NONE)).transpose()?;
        let every = b.take("every").map(|f| self.rd.count(&f, "noether")).transpose()?.unwrap_or(1);
        b.check_names("noether", &["tol", "every"])?;
        self.noether = Some(NoetherRequest { at, tol, every });
        Ok(())
    }

    /// `thermostat nose_hoover { T, tau, chain }` or `thermostat langevin { T, gamma, seed }`:
    /// T is k_B·T, an energy.
    #[allow(clippy::type_complexity)]
    fn thermostat(&self, kw: &Pair, mut b: Block) -> Result<(f64, Thermostat, Option<usize>, Span), Diagnostic> {
        let at: Span = kw.as_span().into();
        let name = kw.as_str();
        let mut need = |field: &str, dim: Dim, what: &str| -> Result<f64, Diagnostic> {
            let f = b.take(field).ok_or_else(|| Diagnostic::new(at, format!("{name} needs `{field}` ({what})")))?;
            self.rd.positive(&f, name, dim)
        };
        let kt = need("T", Dim::ENERGY, "k_B·T, an energy")?;
        let (thermostat, links) = match name {
            "nose_hoover" => {
                let tau = need("tau", Dim::TIME, "the relaxation time")?;
                let links = match b.take("chain") {
                    None => 3,
                    Some(f) => match self.rd.count(&f, name)? {
                        n @ 1..=64 => n as usize,
                        n => return err(value_span(&f), format!("nose_hoover.chain takes 1 to 64 links, got {n}")),
                    },
                };
                b.check_names(name, &["T", "tau", "chain"])?;
                (Thermostat::NoseHoover { tau }, Some(links))
            }
            "langevin" => {
                let gamma = need("gamma", Dim::TIME.pow(-1), "the friction rate, per time")?;
                let seed = b.take("seed").map(|f| self.rd.count(&f, name)).transpose()?.unwrap_or(1);
                b.check_names(name, &["T", "gamma", "seed"])?;
                (Thermostat::Langevin { kt, gamma, seed }, None)
            }
            _ => return err(at, format!("unknown thermostat `{name}`; known: nose_hoover, langevin")),
        };
        Ok((kt, thermostat, links, at))
    }

    fn solver(&self, mut b: Block) -> Result<SolverBlock, Diagnostic> {
        let integrator = match b.take("integrator") {
            None => None,
            Some(f) => {
                let (name, at) = word(&f, "solver")?;
                let integrator = Integrator::from_name(name).ok_or_else(|| {
                    let known: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
                    Diagnostic::new(at, format!("unknown integrator `{name}`; known: {}", known.join(", ")))
                })?;
                Some((integrator, at))
            }
        };
        let dt = b.take("dt").ok_or_else(|| Diagnostic::new(b.span, "solver needs a time step `dt`"))?;
        let dt = self.rd.positive(&dt, "solver", Dim::TIME)?;
        let steps = match (b.take("steps"), b.take("duration")) {
            (Some(_), Some(d)) => return err(d.span, "give `steps` or `duration`, not both"),
            (Some(s), None) => self.rd.count(&s, "solver")?,
            (None, Some(d)) => {
                let n = (self.rd.positive(&d, "solver", Dim::TIME)? / dt).round();
                if !(1.0..=9.0e15).contains(&n) {
                    return err(value_span(&d), format!("duration / dt = {n} steps is out of range"));
                }
                n as u64
            }
            (None, None) => DEFAULT_STEPS,
        };
        let steps_per_frame = b.take("steps_per_frame").map(|f| self.rd.count(&f, "solver")).transpose()?.unwrap_or(10);
        let mut settings = vec![];
        if let Some(f) = b.take("tol") {
            settings.push(("tol", self.rd.positive(&f, "solver", Dim::NONE)?, f.span));
        }
        for name in ["iterations", "window", "substeps"] {
            if let Some(f) = b.take(name) {
                let n = self.rd.count(&f, "solver")?;
                if n > u32::MAX as u64 {
                    return err(value_span(&f), format!("solver.{name} is at most {}", u32::MAX));
                }
                settings.push((name, n as f64, f.span));
            }
        }
        let equilibrate = match b.take("equilibrate") {
            None => None,
            Some(f) => {
                let t = self.rd.numbers(&f, "solver", Dim::TIME, 1)?[0];
                if !(t >= 0.0 && t.is_finite()) {
                    return err(value_span(&f), format!("solver.equilibrate must be a time ≥ 0, got {t}"));
                }
                Some(t)
            }
        };
        let sample_every = b.take("sample_every").map(|f| self.rd.count(&f, "solver")).transpose()?;
        let tail_corrections = match b.take("tail_corrections") {
            None => None,
            Some(f) => match word(&f, "solver")? {
                ("true", at) => Some(at),
                ("false", _) => None,
                (w, at) => return err(at, format!("solver.tail_corrections is true or false, got `{w}`")),
            },
        };
        b.check_names("solver", &[])?;
        Ok(SolverBlock {
            integrator,
            equilibrate,
            sample_every,
            tail_corrections,
            settings,
            dt,
            steps,
            steps_per_frame,
            at: b.span,
        })
    }

    /// The integrator the block names, or the one the model needs; its settings, each given one
    /// checked to be one it takes; and whether it handles the model's terms.
    fn settle(&self, b: SolverBlock) -> Result<Solver, Diagnostic> {
        let constrained = !self.constraints.is_empty();
        let touching = self.floor.is_some() || self.bodies.iter().filter(|b| b.solid.is_some()).count() >= 2;
        let (integrator, at) = b.integrator.unwrap_or((Integrator::default_for(constrained, touching), b.at));
        let mut settings: Settings = integrator.defaults();
        for (name, value, span) in b.settings {
            if !integrator.settings().contains(&name) {
                let takes = match integrator.settings() {
                    [] => "takes no settings".to_string(),
                    s => format!("takes {}", s.join(", ")),
                };
                let owners: Vec<&str> =
                    Integrator::ALL.iter().filter(|i| i.settings().contains(&name)).map(|i| i.name()).collect();
                return err(
                    span,
                    format!("`{name}` is a setting of {}; {} {takes}", owners.join(" and "), integrator.name()),
                );
            }
            match name {
                "tol" => settings.tol = value,
                "iterations" => settings.iterations = value as u32,
                "substeps" => settings.substeps = value as u32,
                _ => settings.window = value as u32,
            }
        }
        if let Some((_, t, _, _)) = &self.thermostat {
            if integrator != Integrator::VelocityVerlet {
                return err(
                    at,
                    format!(
                        "a {} thermostat runs inside velocity_verlet; {} cannot host it",
                        t.name(),
                        integrator.name()
                    ),
                );
            }
        }
        integrator.handles(&self.terms, constrained, touching).map_err(|(term, why)| {
            let wherefrom = term.map(|n| format!(" (line {})", self.term_line[n])).unwrap_or_default();
            Diagnostic::new(at, format!("{why}{wherefrom}"))
        })?;
        Ok(Solver { integrator, settings, dt: b.dt, steps: b.steps, steps_per_frame: b.steps_per_frame })
    }

    /// Each constraint with its length (the bodies' initial distance if none is given), the
    /// initial state checked to meet them within 10⁻⁶ and then moved onto them exactly (to the
    /// solver's tolerance), the velocities made tangent.
    fn constrain(&mut self, cell: &Option<Cell>, settings: &Settings) -> Result<Vec<Constraint>, Diagnostic> {
        const PLACED: f64 = 1e-6;
        let mut out = vec![];
        for &([i, j], length, at) in &self.constraints {
            let d = Cell::image(cell, std::array::from_fn(|c| self.x0[j][c] - self.x0[i][c]));
            let apart = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let length = length.unwrap_or(apart);
            if !(length > 0.0) {
                return err(at, format!("constraint [{i}, {j}]: its bodies start at one point: give a `length`"));
            }
            if (apart - length).abs() > PLACED * length {
                return err(at, format!("constraint [{i}, {j}] holds its bodies {length} apart, but they start {apart} apart: place them within {PLACED:e} of the length"));
            }
            out.push(Constraint { bodies: [i, j], length });
        }
        let model = Model {
            units: self.rd.system,
            cell: *cell,
            bodies: self.bodies.clone(),
            terms: vec![],
            constraints: out,
            thermostat: None,
            floor: None,
        };
        if let Some(k) = Constraints::of(&model) {
            let tol = Tolerance { tol: settings.tol.min(1e-12), sweeps: settings.iterations.max(1000) };
            let inverse: Vec<f64> = self.bodies.iter().map(|b| 1.0 / b.mass).collect();
            let before = self.x0.clone();
            let mut scratch = self.v0.clone();
            let placed = k
                .positions(&before, &mut self.x0, &mut scratch, &inverse, 1.0, tol)
                .and_then(|_| k.velocities(&self.x0, &mut self.v0, &inverse, 1.0, tol));
            if let Err(e) = placed {
                return err(
                    self.constraints[e.constraint].2,
                    format!("the initial state cannot be placed on the constraints: {e}"),
                );
            }
        }
        Ok(model.constraints)
    }

    fn finish(mut self, name: String, at: Span) -> Result<Scene, Diagnostic> {
        let n = self.bodies.len();
        if n == 0 {
            return err(at, format!("scene {name} has no entities"));
        }
        for (i, s) in self.indices.iter().flatten() {
            if *i >= n {
                return err(*s, format!("body index {i} is out of range: the scene has {n} entities (0..{})", n - 1));
            }
        }
        let block =
            self.solver.take().ok_or_else(|| Diagnostic::new(at, format!("scene {name} has no solver block")))?;
        if let Some((c, _)) = &self.cell {
            reach_within(c, &self.terms, &self.term_at)?;
        }
        let cell = self.cell.map(|c| c.0);
        let sampling =
            (self.thermostat.is_some() || block.equilibrate.is_some() || block.sample_every.is_some()).then(|| {
                Sampling {
                    equilibrate: block.equilibrate.unwrap_or(0.0),
                    every: block.sample_every.unwrap_or(10),
                    tail_corrections: block.tail_corrections.is_some(),
                }
            });
        let tail_at = block.tail_corrections;
        if let (Some(at), None) = (tail_at, sampling) {
            return err(at, "tail_corrections apply to the measured observables: give `equilibrate` too");
        }
        let solver = self.settle(block)?;
        let constraints = self.constrain(&cell, &solver.settings)?;
        for (c, s) in self.claims.iter().zip(&self.claim_spans) {
            if c.kind == ClaimKind::ConstraintSatisfied && constraints.is_empty() {
                return err(*s, "constraint_satisfied: the scene declares no constraint");
            }
        }
        let mut model = Model {
            units: self.rd.system,
            cell,
            bodies: self.bodies,
            terms: self.terms,
            constraints,
            thermostat: None,
            floor: self.floor.map(|f| f.0),
        };
        apart(&model, &self.x0, &self.spin0, &self.solid_at, self.floor.map(|f| f.1))?;
        for (c, s) in self.claims.iter().zip(&self.claim_spans) {
            if matches!(c.kind, ClaimKind::Resting | ClaimKind::NoPenetration) {
                c.validate(&model).map_err(|e| Diagnostic::new(*s, e))?;
            }
            if c.after.is_some_and(|t| t > solver.steps as f64 * solver.dt) {
                return err(
                    *s,
                    format!("resting.after is past the end of the run (t = {})", solver.steps as f64 * solver.dt),
                );
            }
        }
        let thermostat = match self.thermostat {
            None => None,
            Some((kt, t, links, at)) => {
                let dof = match t {
                    Thermostat::NoseHoover { .. } => thermostat::degrees_of_freedom(&model),
                    Thermostat::Langevin { .. } => 3.0 * model.bodies.len() as f64,
                };
                if dof < 1.0 {
                    return err(at, format!("{} has no kinetic degree of freedom to hold at a temperature: {} bod{} whose centre of mass the terms keep", t.name(), model.bodies.len(), if model.bodies.len() == 1 { "y" } else { "ies" }));
                }
                if let (Thermostat::NoseHoover { tau }, Some(links)) = (&t, links) {
                    model.thermostat = Some(thermostat::chain(kt, *tau, links, dof));
                }
                if let Thermostat::Langevin { .. } = t {
                    refuse_under_langevin(&self.claims, &self.claim_spans, &self.noether)?;
                }
                Some(t)
            }
        };
        if let Some(at) = tail_at {
            Tail::of(&model).map_err(|e| Diagnostic::new(at, e))?;
        }
        let bath = thermostat.as_ref().map(|t| Bath::of(t, &model));
        let predictions = self
            .predictions
            .into_iter()
            .map(|(kind, tol, s)| match kind.predict(&model, &self.x0, &self.v0, bath) {
                Ok(predicted) => Ok(Prediction { kind, tol, predicted }),
                Err(why) => err(s, format!("{}: {why}", kind.name())),
            })
            .collect::<Result<_, _>>()?;
        Ok(Scene {
            name,
            description: self.description,
            domain: self.domain,
            model,
            x0: self.x0,
            v0: self.v0,
            spin0: self.spin0,
            sizes: self.sizes,
            claims: self.claims,
            claim_spans: self.claim_spans,
            noether: self.noether,
            predictions,
            solver,
            thermostat,
            sampling,
        })
    }
}

/// Solids must start apart and above the floor: the contact solver would fling overlapping
/// bodies apart. An overlap is an error at the later body's entity (or at the floor).
fn apart(
    model: &Model,
    x: &[[f64; 3]],
    spin: &[[f64; 7]],
    at: &[Option<Span>],
    floor_at: Option<Span>,
) -> Result<(), Diagnostic> {
    let Some(solids) = Solids::of(model) else { return Ok(()) };
    // well above rounding, well below any overlap the solver would have to undo
    let tolerance = 1e-6 * solids.margin;
    let touches = solids.touching(&solids.poses(x, spin));
    match touches.into_iter().find(|t| t.depth > tolerance) {
        None => Ok(()),
        Some(t) => {
            let depth = t.depth;
            match t.a {
                None => err(
                    at[t.b].or(floor_at).expect("a floor contact has a floor"),
                    format!("body {} starts {depth:.3e} below the floor: solids must start apart", t.b),
                ),
                Some(a) => err(
                    at[a.max(t.b)].expect("a solid was declared"),
                    format!("bodies {a} and {} start interpenetrated by {depth:.3e}: solids must start apart", t.b),
                ),
            }
        }
    }
}

/// A Langevin bath exchanges energy and momentum with the bodies at random: the claims that
/// they are conserved cannot hold, and the checker would have no record of the noise to state
/// the balance with, so they are refused where they are declared.
fn refuse_under_langevin(claims: &[Claim], at: &[Span], noether: &Option<NoetherRequest>) -> Result<(), Diagnostic> {
    let why = "a Langevin thermostat exchanges energy and momentum with its bath at random, so it cannot be conserved; remove the claim, or use `thermostat nose_hoover`, whose extended energy is certified";
    for (c, s) in claims.iter().zip(at) {
        if matches!(
            c.kind,
            ClaimKind::EnergyConservation | ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation
        ) {
            return err(*s, format!("{}: {why}", c.kind.name()));
        }
    }
    if let Some(n) = noether {
        return err(n.at, format!("noether: {why}"));
    }
    Ok(())
}

/// In a periodic box a pair term sees only the nearest image of each body: its reach must be
/// finite and at most half the box, or the model would silently be another one.
fn reach_within(c: &Cell, terms: &[TermInstance], at: &[Span]) -> Result<(), Diagnostic> {
    let half = (0..3).filter(|&a| c.periodic[a]).map(|a| c.size[a] / 2.0).fold(f64::INFINITY, f64::min);
    if half.is_infinite() {
        return Ok(());
    }
    for (t, s) in terms.iter().zip(at).filter(|(t, _)| t.kind.spec().shape == Shape::Pairwise) {
        match t.kind.reach(&t.params) {
            None => {
                return err(*s, format!("{} has unbounded reach: in a periodic box it would see only the nearest image; use a term with a cutoff", t.kind.name()))
            }
            Some(r) if r > half => {
                return err(*s, format!("{} reaches {r}, more than half the periodic box ({half})", t.kind.name()))
            }
            _ => {}
        }
    }
    Ok(())
}

/// `axes: "xz"`: the momentum components a claim is about.
fn axes(f: &Field, owner: &str) -> Result<[bool; 3], Diagnostic> {
    let (text, at) = word(f, owner)?;
    let mut a = [false; 3];
    for c in text.chars() {
        match "xyz".find(c) {
            Some(i) if !a[i] => a[i] = true,
            _ => return err(at, format!("{owner}.axes takes some of x, y, z once each, got `{text}`")),
        }
    }
    if a == [false; 3] {
        return err(at, format!("{owner}.axes names no axis"));
    }
    Ok(a)
}

/// The body indices of a bond or constraint: `arity` of them, each once.
fn listed(idx: &Pair, owner: &str, arity: usize) -> Result<Vec<(usize, Span)>, Diagnostic> {
    let indices: Vec<(usize, Span)> = idx
        .clone()
        .into_inner()
        .map(|i| match i.as_str().parse::<usize>() {
            Ok(n) => Ok((n, i.as_span().into())),
            Err(_) => err(i.as_span(), format!("body index `{}` is too large", i.as_str())),
        })
        .collect::<Result<_, _>>()?;
    if indices.len() != arity {
        return err(idx.as_span(), format!("{owner} joins {arity} bodies, got {}", indices.len()));
    }
    for (n, (a, s)) in indices.iter().enumerate() {
        if indices[..n].iter().any(|(b, _)| a == b) {
            return err(*s, format!("{owner} lists body {a} twice"));
        }
    }
    Ok(indices)
}

fn lookup(kw: &Pair, fits: impl Fn(Shape) -> bool + Copy, what: &str) -> Result<Kind, Diagnostic> {
    Kind::lookup(kw.as_str(), fits).ok_or_else(|| {
        let known: Vec<_> = Kind::ALL.iter().filter(|k| fits(k.spec().shape)).map(|k| k.spec().keyword).collect();
        Diagnostic::new(kw.as_span().into(), format!("unknown {what} `{}`; known: {}", kw.as_str(), known.join(", ")))
    })
}
