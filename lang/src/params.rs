//! The scene's numeric parameters by name, as `lagra grad --wrt`, `lagra fit` and `--set` spell
//! them:
//!
//! - `TERM.PARAM` — a term's parameter, TERM its keyword (`trap.k`, `lj.epsilon`); a vector
//!   parameter gives its three components, `TERM.PARAM.x` one of them;
//! - `TERM#N.PARAM` — the N-th declaration of that keyword (from 0, in the order written), where
//!   the keyword is declared more than once;
//! - `body[I].mass`, `body[I].charge`, `body[I].position`, `body[I].velocity` (the last two give
//!   `.x`, `.y`, `.z`, or one of them when written).

use crate::scene::Scene;
use lagra_checker::terms::Kind;
use std::sync::Arc;

/// One scalar of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// Component `index` of model term `term`'s parameters (flattened as in its spec).
    Term {
        term: usize,
        index: usize,
    },
    Mass(usize),
    Charge(usize),
    Position(usize, usize),
    Velocity(usize, usize),
}

/// A parameter and the name it is reported under.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    pub name: String,
    pub param: Param,
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Param {
    /// Its value in the scene.
    pub fn get(self, scene: &Scene) -> f64 {
        match self {
            Param::Term { term, index } => scene.model.terms[term].params[index],
            Param::Mass(i) => scene.model.bodies[i].mass,
            Param::Charge(i) => scene.model.bodies[i].charge,
            Param::Position(i, c) => scene.x0[i][c],
            Param::Velocity(i, c) => scene.v0[i][c],
        }
    }

    /// Sets it in the scene; a mass must stay positive and every value finite.
    pub fn set(self, scene: &mut Scene, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("{value} is not a finite number"));
        }
        // (the model is copied first only where a run or another scene still shares it)
        let model = Arc::make_mut(&mut scene.model);
        match self {
            Param::Term { term, index } => model.terms[term].params[index] = value,
            Param::Mass(_) if value <= 0.0 => return Err(format!("a mass must be positive, got {value}")),
            Param::Mass(i) => model.bodies[i].mass = value,
            Param::Charge(i) => model.bodies[i].charge = value,
            Param::Position(i, c) => scene.x0[i][c] = value,
            Param::Velocity(i, c) => scene.v0[i][c] = value,
        }
        Ok(())
    }
}

/// The axis named by a trailing `.x`, `.y`, `.z`, if any, and what is before it.
fn axis(s: &str) -> (&str, Option<usize>) {
    match s.rsplit_once('.') {
        Some((head, a)) if AXES.contains(&a) => (head, AXES.iter().position(|x| *x == a)),
        _ => (s, None),
    }
}

/// The three components of a vector (or the one asked for), named.
fn components(name: &str, one: Option<usize>, make: impl Fn(usize) -> Param) -> Vec<Named> {
    let axes: Vec<usize> = one.map_or((0..3).collect(), |a| vec![a]);
    axes.into_iter().map(|a| Named { name: format!("{name}.{}", AXES[a]), param: make(a) }).collect()
}

/// The parameters a comma-separated list names (`trap.k,body[0].velocity`), each checked to
/// exist in the scene; an unknown one is an error naming it and what there is.
pub fn parse_list(list: &str, scene: &Scene) -> Result<Vec<Named>, String> {
    let mut out: Vec<Named> = vec![];
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        for n in parse(item, scene)? {
            if out.iter().any(|o| o.param == n.param) {
                return Err(format!("parameter `{}` is named twice", n.name));
            }
            out.push(n);
        }
    }
    if out.is_empty() {
        return Err("no parameter named: give e.g. `--wrt trap.k,body[0].velocity`".into());
    }
    Ok(out)
}

/// The parameters one spelling names.
pub fn parse(spelling: &str, scene: &Scene) -> Result<Vec<Named>, String> {
    if let Some(rest) = spelling.strip_prefix("body[") {
        return body(spelling, rest, scene);
    }
    let (head, field) = spelling
        .split_once('.')
        .ok_or_else(|| format!("`{spelling}` is not a parameter: write TERM.PARAM (e.g. trap.k) or body[I].mass"))?;
    let (keyword, nth) = match head.split_once('#') {
        Some((k, n)) => {
            (k, Some(n.parse::<usize>().map_err(|_| format!("`{spelling}`: `#{n}` is not a declaration number"))?))
        }
        None => (head, None),
    };
    let declared: Vec<usize> =
        (0..scene.model.terms.len()).filter(|&t| scene.model.terms[t].kind.spec().keyword == keyword).collect();
    if declared.is_empty() {
        let mut words: Vec<&str> = scene.model.terms.iter().map(|t| t.kind.spec().keyword).collect();
        words.dedup();
        return Err(format!("`{spelling}`: the scene has no term `{keyword}`; its terms: {}", words.join(", ")));
    }
    let term = match (nth, declared.len()) {
        (None, 1) => declared[0],
        (None, n) => {
            return Err(format!(
                "`{spelling}`: `{keyword}` is declared {n} times: name one as {keyword}#N.{field} (N from 0 to {})",
                n - 1
            ))
        }
        (Some(k), n) if k < n => declared[k],
        (Some(k), n) => return Err(format!("`{spelling}`: `{keyword}` is declared {n} times, so #{k} does not exist")),
    };
    let kind: Kind = scene.model.terms[term].kind;
    let spec = kind.spec();
    let (name, one) = axis(field);
    let Some(at) = spec.params.iter().position(|p| p.name == name) else {
        let names: Vec<&str> = spec.params.iter().map(|p| p.name).collect();
        return Err(format!("`{spelling}`: {keyword} has no parameter `{name}`; it has {}", names.join(", ")));
    };
    let offset: usize = spec.params[..at].iter().map(|p| p.len).sum();
    let prefix =
        spelling.strip_suffix(&format!(".{}", AXES[one.unwrap_or(0)])).filter(|_| one.is_some()).unwrap_or(spelling);
    match (spec.params[at].len, one) {
        (1, None) => Ok(vec![Named { name: spelling.to_string(), param: Param::Term { term, index: offset } }]),
        (1, Some(_)) => Err(format!("`{spelling}`: {keyword}.{name} is a scalar")),
        (_, one) => Ok(components(prefix, one, |a| Param::Term { term, index: offset + a })),
    }
}

fn body(spelling: &str, rest: &str, scene: &Scene) -> Result<Vec<Named>, String> {
    let n = scene.model.bodies.len();
    let (index, field) = rest
        .split_once("].")
        .ok_or_else(|| format!("`{spelling}`: write body[I].mass, .charge, .position or .velocity"))?;
    let i: usize = index.parse().map_err(|_| format!("`{spelling}`: `{index}` is not a body index"))?;
    if i >= n {
        return Err(format!("`{spelling}`: body {i} does not exist: the scene has {n} bodies (0..{})", n - 1));
    }
    let (what, one) = axis(field);
    let prefix = format!("body[{i}].{what}");
    match (what, one) {
        ("mass", None) => Ok(vec![Named { name: prefix, param: Param::Mass(i) }]),
        ("charge", None) => Ok(vec![Named { name: prefix, param: Param::Charge(i) }]),
        ("position", one) => Ok(components(&prefix, one, |a| Param::Position(i, a))),
        ("velocity", one) => Ok(components(&prefix, one, |a| Param::Velocity(i, a))),
        _ => Err(format!("`{spelling}`: a body has mass, charge, position and velocity")),
    }
}

/// Applies `NAME=VALUE` settings (`--set trap.k=2.5`) to a scene.
pub fn apply_settings(scene: &mut Scene, settings: &[String]) -> Result<(), String> {
    for s in settings {
        let (name, value) = s.split_once('=').ok_or_else(|| format!("`{s}`: write --set NAME=VALUE"))?;
        let value: f64 = value.trim().parse().map_err(|_| format!("`{s}`: `{value}` is not a number"))?;
        let params = parse(name.trim(), scene)?;
        if params.len() != 1 {
            return Err(format!("`{s}`: {name} is a vector: set one component (`{}`)", params[0].name));
        }
        params[0].param.set(scene, value).map_err(|e| format!("`{s}`: {e}"))?;
    }
    scene.model.validate().map_err(|e| format!("after --set: {e}"))?;
    scene.repredict().map_err(|e| format!("after --set: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile;

    fn scene() -> Scene {
        compile(
            "scene s { entity { position: [0, 0, 0], mass: 1 } entity { position: [1, 0, 0], mass: 2, charge: 1 }
               bond harmonic [0, 1] { k: 2, r0: 1 } bond harmonic [0, 1] { k: 3, r0: 1 }
               trap { k: 4, center: [0, 1, 0] } solver { dt: 0.01 } }",
        )
        .unwrap()
    }

    fn names(v: &[Named]) -> Vec<&str> {
        v.iter().map(|n| n.name.as_str()).collect()
    }

    #[test]
    fn spellings_name_their_parameters() {
        let s = scene();
        assert_eq!(parse("trap.k", &s).unwrap()[0].param, Param::Term { term: 2, index: 0 });
        assert_eq!(names(&parse("trap.center", &s).unwrap()), ["trap.center.x", "trap.center.y", "trap.center.z"]);
        assert_eq!(parse("trap.center.y", &s).unwrap()[0].param, Param::Term { term: 2, index: 2 });
        assert_eq!(parse("harmonic#1.k", &s).unwrap()[0].param, Param::Term { term: 1, index: 0 });
        assert_eq!(parse("body[1].mass", &s).unwrap()[0].param, Param::Mass(1));
        assert_eq!(
            names(&parse("body[0].velocity", &s).unwrap()),
            ["body[0].velocity.x", "body[0].velocity.y", "body[0].velocity.z"]
        );
        assert_eq!(parse("body[0].position.z", &s).unwrap()[0].param, Param::Position(0, 2));
        assert_eq!(parse_list("trap.k, body[1].charge", &s).unwrap().len(), 2);
    }

    #[test]
    fn unknown_parameters_are_errors_naming_them() {
        let s = scene();
        for (spelling, message) in [
            ("spring.k", "`spring.k`: the scene has no term `spring`; its terms: harmonic, trap"),
            ("trap.kk", "`trap.kk`: trap has no parameter `kk`; it has k, center"),
            ("harmonic.k", "`harmonic.k`: `harmonic` is declared 2 times: name one as harmonic#N.k (N from 0 to 1)"),
            ("harmonic#2.k", "`harmonic#2.k`: `harmonic` is declared 2 times, so #2 does not exist"),
            ("body[5].mass", "`body[5].mass`: body 5 does not exist: the scene has 2 bodies (0..1)"),
            ("body[0].spin", "`body[0].spin`: a body has mass, charge, position and velocity"),
            ("k", "`k` is not a parameter: write TERM.PARAM (e.g. trap.k) or body[I].mass"),
            ("trap.k.x", "`trap.k.x`: trap.k is a scalar"),
        ] {
            assert_eq!(parse(spelling, &s).unwrap_err(), message);
        }
        assert!(parse_list("trap.k,trap.k", &s).unwrap_err().contains("named twice"));
    }

    /// A scene's model is shared with its runs (`Arc`): a parameter set in one copy of a scene
    /// changes that copy alone, its model copied at the first change and not before.
    #[test]
    fn a_setting_changes_its_own_scene_and_no_other() {
        let mut s = scene();
        let before = s.clone();
        assert!(Arc::ptr_eq(&s.model, &before.model));
        Param::Term { term: 2, index: 0 }.set(&mut s, 2.5).unwrap();
        Param::Mass(1).set(&mut s, 3.0).unwrap();
        assert_eq!((s.model.terms[2].params[0], s.model.bodies[1].mass), (2.5, 3.0));
        assert_eq!((before.model.terms[2].params[0], before.model.bodies[1].mass), (4.0, 2.0));
        let alone = Arc::as_ptr(&s.model);
        Param::Charge(1).set(&mut s, -1.0).unwrap();
        assert_eq!(Arc::as_ptr(&s.model), alone, "a model no one shares is changed in place");
    }

    #[test]
    fn settings_change_the_scene() {
        let mut s = scene();
        apply_settings(&mut s, &["trap.k=2.5".into(), "body[1].velocity.y=0.3".into()]).unwrap();
        // predictions follow a parameter set
        let mut osc = compile(
            "scene o { entity { position: [0, 0, 0], mass: 1 } entity { position: [1.5, 0, 0], mass: 1 }
            bond harmonic [0, 1] { k: 2, r0: 1 } @predict oscillator_period solver { dt: 0.01 } }",
        )
        .unwrap();
        let before = osc.predictions[0].predicted.unwrap();
        apply_settings(&mut osc, &["harmonic.k=8".into()]).unwrap();
        assert!((osc.predictions[0].predicted.unwrap() - 0.5 * before).abs() < 1e-12);
        assert_eq!((s.model.terms[2].params[0], s.v0[1][1]), (2.5, 0.3));
        assert!(apply_settings(&mut s, &["body[0].mass=-1".into()]).unwrap_err().contains("positive"));
        assert!(apply_settings(&mut s, &["trap.center=1".into()]).unwrap_err().contains("is a vector"));
    }
}
