//! From the parse tree to a [`Scene`]: templates resolved, terms looked up in the checker's
//! vocabulary, every number checked for dimension and converted, every index checked.

use crate::block::{flags, typed, value_span, word, Block, Reader};
use crate::diagnostic::{Diagnostic, Span};
use crate::prediction::{Prediction, PredictionKind};
use crate::scene::{NoetherRequest, Sampling, Scene, Spans};
use crate::thermostat::{self, Bath, Thermostat};
use crate::{Pair, Rule, Threads};
use lagra_checker::claims::{Claim, ClaimKind};
use lagra_checker::model::{Body, Cell, Floor, Model, TermInstance, UnitSystem};
use lagra_checker::terms::{Kind, Shape};
use lagra_checker::units::Dim;
use std::collections::HashMap;

mod bodies;
mod claims;
mod joints;
mod solver;

use bodies::{BUILTIN_TYPES, ENTITY_FIELDS};
use claims::refuse_under_langevin;
use solver::SolverBlock;

fn err<T>(span: impl Into<Span>, msg: impl Into<String>) -> Result<T, Diagnostic> {
    Err(Diagnostic::new(span.into(), msg))
}

struct Compiler<'a> {
    rd: Reader,
    /// The run's threads, asked for where a large lattice is laid out.
    threads: Threads<'a>,
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
    /// Each `joint`, as written.
    joints: Vec<joints::JointDecl>,
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

pub fn scene<'a>(pair: Pair<'a>, threads: Threads<'a>) -> Result<Scene, Diagnostic> {
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
        threads,
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
        joints: vec![],
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
                let bond = |s| matches!(s, Shape::Bond(_));
                let mut block = Block::read(next(), kw.as_span().into())?;
                let kind = chosen(&kw, bond, lookup(&kw, bond, "bond")?, &mut block)?;
                let indices = listed(&idx, kind.name(), kind.spec().shape.arity())?;
                let params = self.params(kind, block, kw.as_span().into())?;
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
            Rule::joint => {
                let (_, kind, idx) = (next(), next().expect("joint kind"), next().expect("indices"));
                self.joint(&kind, &idx, next(), span)
            }
            Rule::interaction | Rule::external => {
                let kw = if rule == Rule::interaction { next().and(next()) } else { next() }.expect("keyword");
                let (what, shape) = if rule == Rule::interaction {
                    ("interaction", Shape::Pairwise)
                } else {
                    ("term", Shape::External)
                };
                // a fluid is written like an external term: its density's pairs are its own
                let fits = |s| s == shape || (shape == Shape::External && s == Shape::Density);
                let mut block = Block::read(next(), kw.as_span().into())?;
                let kind = chosen(&kw, fits, lookup(&kw, fits, what)?, &mut block)?;
                let shape = kind.spec().shape;
                if kind == Kind::ContactFloor && block.get("k").is_none() {
                    return self.rigid_floor(block, kw.as_span().into());
                }
                // an external term acts on every body, or only on those listed in `on`
                let on = match block.take("on") {
                    Some(f) if shape == Shape::External => self.rd.body_list(&f, kind.name())?,
                    Some(f) => {
                        let every = if shape == Shape::Density { "body of the fluid" } else { "pair" };
                        return err(
                            f.span,
                            format!("{} acts on every {every}; `on` belongs to external terms", kind.name()),
                        );
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

    /// The term's parameters in the order of its spec, each checked against its dimension.
    fn params(&self, kind: Kind, mut b: Block, at: Span) -> Result<Vec<f64>, Diagnostic> {
        let spec = kind.spec();
        let (mut out, mut written) = (vec![], vec![]);
        for p in spec.params {
            match (b.take(p.name), p.default) {
                (Some(f), _) => {
                    written.push((p.name, value_span(&f)));
                    match p.positive && p.len == 1 {
                        true => out.push(self.rd.positive(&f, spec.name, p.dim)?),
                        false => out.extend(self.rd.numbers(&f, spec.name, p.dim, p.len)?),
                    }
                }
                (None, Some(d)) => out.extend(std::iter::repeat_n(d, p.len)),
                (None, None) => return err(at, format!("{} needs `{}` ({})", spec.name, p.name, typed(p.dim))),
            }
        }
        // (a variant's field was taken when it chose the term)
        let names: Vec<&str> = spec.params.iter().map(|p| p.name).chain(kind.variant().map(|v| v.field)).collect();
        b.check_names(spec.name, &names)?;
        if let Err((name, why)) = kind.accepts(&out) {
            let span = written.iter().find(|w| w.0 == name).map_or(at, |w| w.1);
            return err(span, format!("{}.{name} {why}", spec.name));
        }
        Ok(out)
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
        let constraints = self.constrain(&cell)?;
        for (c, s) in self.claims.iter().zip(&self.claim_spans) {
            if c.kind == ClaimKind::ConstraintSatisfied && constraints.is_empty() {
                return err(*s, "constraint_satisfied: the scene declares no constraint");
            }
        }
        let pins = self.pins()?;
        let mut model = Model {
            units: self.rd.system,
            cell,
            bodies: self.bodies,
            terms: self.terms,
            constraints,
            thermostat: None,
            floor: self.floor.map(|f| f.0),
            pins,
        };
        for (c, s) in self.claims.iter().zip(&self.claim_spans) {
            if matches!(c.kind, ClaimKind::Resting | ClaimKind::NoPenetration | ClaimKind::JointSatisfied) {
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
        let bath = thermostat.as_ref().map(|t| Bath::of(t, &model));
        let spans = Spans {
            constraints: self.constraints.iter().map(|c| c.2).collect(),
            solids: self.solid_at,
            floor: self.floor.map(|f| f.1),
            tail_corrections: tail_at,
            predictions: self.predictions.iter().map(|p| p.2).collect(),
            terms: self.term_at,
        };
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
            model: model.into(),
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
            spans,
        })
    }
}

/// In a periodic box a pair term sees only the nearest image of each body: its reach must be
/// finite and at most half the box, or the model would silently be another one.
fn reach_within(c: &Cell, terms: &[TermInstance], at: &[Span]) -> Result<(), Diagnostic> {
    let half = (0..3).filter(|&a| c.periodic[a]).map(|a| c.size[a] / 2.0).fold(f64::INFINITY, f64::min);
    if half.is_infinite() {
        return Ok(());
    }
    for (t, s) in terms.iter().zip(at).filter(|(t, _)| matches!(t.kind.spec().shape, Shape::Pairwise | Shape::Density))
    {
        let r = t.kind.reach(&t.params);
        if r.is_infinite() {
            return err(*s, format!("{} has unbounded reach: in a periodic box it would see only the nearest image; use a term with a cutoff", t.kind.name()));
        }
        if r > half {
            return err(*s, format!("{} reaches {r}, more than half the periodic box ({half})", t.kind.name()));
        }
    }
    Ok(())
}

/// The body indices written `[i, j, ...]`, each where it stands.
fn indices_of(idx: &Pair) -> Result<Vec<(usize, Span)>, Diagnostic> {
    idx.clone()
        .into_inner()
        .map(|i| match i.as_str().parse::<usize>() {
            Ok(n) => Ok((n, i.as_span().into())),
            Err(_) => err(i.as_span(), format!("body index `{}` is too large", i.as_str())),
        })
        .collect()
}

/// The body indices of a bond or constraint: `arity` of them, each once.
fn listed(idx: &Pair, owner: &str, arity: usize) -> Result<Vec<(usize, Span)>, Diagnostic> {
    let indices = indices_of(idx)?;
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
    Kind::lookup(kw.as_str(), fits, None).ok_or_else(|| {
        let mut known: Vec<_> = Kind::ALL.iter().filter(|k| fits(k.spec().shape)).map(|k| k.spec().keyword).collect();
        known.dedup();
        Diagnostic::new(kw.as_span().into(), format!("unknown {what} `{}`; known: {}", kw.as_str(), known.join(", ")))
    })
}

/// The term among those of `kind`'s keyword that the block's choice selects (`sph { kernel:
/// cubic_spline }`), the field taken from the block; `kind` where there is no choice to make.
fn chosen(kw: &Pair, fits: impl Fn(Shape) -> bool + Copy, kind: Kind, block: &mut Block) -> Result<Kind, Diagnostic> {
    let Some(variant) = kind.variant() else { return Ok(kind) };
    let Some(field) = block.take(variant.field) else { return Ok(kind) };
    let (value, at) = word(&field, kw.as_str())?;
    Kind::lookup(kw.as_str(), fits, Some(value)).ok_or_else(|| {
        let known: Vec<_> = Kind::ALL
            .iter()
            .filter(|k| k.spec().keyword == kw.as_str() && fits(k.spec().shape))
            .filter_map(|k| k.variant().map(|v| v.value))
            .collect();
        Diagnostic::new(
            at,
            format!("unknown {} `{value}` for {}; known: {}", variant.field, kw.as_str(), known.join(", ")),
        )
    })
}
