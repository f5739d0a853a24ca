//! `{ name: value, ... }` blocks and typed reading of their values: numbers are checked for
//! length, finiteness and dimension, and converted to the scene's unit system.

use crate::diagnostic::{Diagnostic, Span};
use crate::units::unit;
use crate::{Pair, Rule};
use lagra_checker::model::UnitSystem;
use lagra_checker::units::Dim;

#[derive(Clone)]
pub struct Field<'a> {
    pub name: &'a str,
    pub span: Span,
    pub value: Pair<'a>,
}

/// The fields of one block, each to be taken once; what is left over is an unknown field.
pub struct Block<'a> {
    pub span: Span,
    fields: Vec<Field<'a>>,
}

impl<'a> Block<'a> {
    /// Reads an optional `block` pair; a missing block is an empty one at `at`.
    pub fn read(pair: Option<Pair<'a>>, at: Span) -> Result<Self, Diagnostic> {
        let Some(pair) = pair else {
            return Ok(Block { span: at, fields: vec![] });
        };
        let span = pair.as_span().into();
        let mut fields: Vec<Field> = vec![];
        for f in pair.into_inner() {
            let mut parts = f.into_inner();
            let (name, value) = (parts.next().expect("field name"), parts.next().expect("field value"));
            if fields.iter().any(|g| g.name == name.as_str()) {
                return Err(Diagnostic::new(name.as_span().into(), format!("duplicate field `{}`", name.as_str())));
            }
            fields.push(Field { name: name.as_str(), span: name.as_span().into(), value });
        }
        Ok(Block { span, fields })
    }

    pub fn take(&mut self, name: &str) -> Option<Field<'a>> {
        let i = self.fields.iter().position(|f| f.name == name)?;
        Some(self.fields.remove(i))
    }

    pub fn get(&self, name: &str) -> Option<&Field<'a>> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// Every field left must be one of `allowed` (for blocks read in parts), else an error.
    pub fn check_names(&self, owner: &str, allowed: &[&str]) -> Result<(), Diagnostic> {
        match self.fields.iter().find(|f| !allowed.contains(&f.name)) {
            None => Ok(()),
            Some(f) => {
                let known = if allowed.is_empty() {
                    "it takes no fields".to_string()
                } else {
                    format!("expected {}", allowed.join(", "))
                };
                Err(Diagnostic::new(f.span, format!("unknown field `{}` for {owner}; {known}", f.name)))
            }
        }
    }
}

/// `M·T⁻² (energy/length²)`.
pub fn typed(d: Dim) -> String {
    match d.describe() {
        Some(n) => format!("{d} ({n})"),
        None => d.to_string(),
    }
}

/// Reads values in the scene's unit system.
pub struct Reader {
    pub system: UnitSystem,
}

impl Reader {
    /// `len` numbers (1, or 3 for a vector, 4 for a quaternion) of dimension `dim`, in the
    /// scene's units.
    pub fn numbers(&self, f: &Field, owner: &str, dim: Dim, len: usize) -> Result<Vec<f64>, Diagnostic> {
        let what = match len {
            1 => "a number",
            3 => "a vector [x, y, z]",
            _ => "a quaternion [w, x, y, z]",
        };
        let q = f.value.clone().into_inner().next().expect("a value has one child");
        if q.as_rule() != Rule::quantity {
            return Err(Diagnostic::new(
                q.as_span().into(),
                format!("{owner}.{} expects {what}, found `{}`", f.name, q.as_str()),
            ));
        }
        let mut parts = q.into_inner();
        let body = parts.next().expect("a quantity has a number or vector");
        let nums: Vec<Pair> = match body.as_rule() {
            Rule::vector => body.clone().into_inner().collect(),
            _ => vec![body.clone()],
        };
        if (body.as_rule() == Rule::vector) != (len > 1) || nums.len() != len {
            return Err(Diagnostic::new(body.as_span().into(), format!("{owner}.{} expects {what}", f.name)));
        }
        let mut convert = None;
        if let Some(u) = parts.next() {
            let u = unit(u)?;
            if u.dim != dim {
                return Err(Diagnostic::new(
                    u.span,
                    format!("{owner}.{} expects {}, found {}", f.name, typed(dim), typed(u.dim)),
                ));
            }
            // rad and deg carry no dimension, so they mean the same in every unit system
            if self.system == UnitSystem::Reduced && u.dim != Dim::NONE {
                return Err(Diagnostic::new(
                    u.span,
                    "a physical unit in a scene with reduced units; declare `units si` or write a bare number",
                ));
            }
            convert = Some(u);
        }
        nums.iter()
            .map(|n| {
                let x = match convert {
                    Some(u) => u.convert(n.as_str()),
                    None => n.as_str().parse::<f64>().unwrap_or(f64::NAN),
                };
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(Diagnostic::new(n.as_span().into(), format!("non-finite number `{}`", n.as_str())))
                }
            })
            .collect()
    }

    /// `n` body indices, written `[i, j, ...]` (their range is checked once all bodies are known).
    pub fn indices(&self, f: &Field, owner: &str, n: usize) -> Result<Vec<(usize, Span)>, Diagnostic> {
        self.list_of(f, owner, Some(n))
    }

    /// Any number of body indices, at least one.
    pub fn body_list(&self, f: &Field, owner: &str) -> Result<Vec<(usize, Span)>, Diagnostic> {
        self.list_of(f, owner, None)
    }

    fn list_of(&self, f: &Field, owner: &str, n: Option<usize>) -> Result<Vec<(usize, Span)>, Diagnostic> {
        let count = n.map_or("a list of".to_string(), |n| n.to_string());
        let bad =
            || Diagnostic::new(value_span(f), format!("{owner}.{} expects {count} body indices `[i, j]`", f.name));
        let q = f.value.clone().into_inner().next().expect("a value has one child");
        let mut parts = q.into_inner();
        let list = parts.next().filter(|v| v.as_rule() == Rule::vector).ok_or_else(bad)?;
        let nums: Vec<Pair> = list.into_inner().collect();
        if n.is_some_and(|n| nums.len() != n) || parts.next().is_some() {
            return Err(bad());
        }
        nums.iter()
            .map(|p| match p.as_str().parse::<usize>() {
                Ok(i) => Ok((i, p.as_span().into())),
                Err(_) => Err(Diagnostic::new(p.as_span().into(), format!("`{}` is not a body index", p.as_str()))),
            })
            .collect()
    }

    /// One number of dimension `dim` that must be positive.
    pub fn positive(&self, f: &Field, owner: &str, dim: Dim) -> Result<f64, Diagnostic> {
        let x = self.numbers(f, owner, dim, 1)?[0];
        if x > 0.0 {
            Ok(x)
        } else {
            Err(Diagnostic::new(value_span(f), format!("{owner}.{} must be positive, got {x}", f.name)))
        }
    }

    /// A whole, positive, dimensionless number.
    pub fn count(&self, f: &Field, owner: &str) -> Result<u64, Diagnostic> {
        let x = self.numbers(f, owner, Dim::NONE, 1)?[0];
        if x >= 1.0 && x.fract() == 0.0 && x <= 9.007_199_254_740_992e15 {
            Ok(x as u64)
        } else {
            Err(Diagnostic::new(value_span(f), format!("{owner}.{} expects a whole number ≥ 1, got {x}", f.name)))
        }
    }
}

/// `[true, false, true]`.
pub fn flags<const N: usize>(f: &Field, owner: &str) -> Result<[bool; N], Diagnostic> {
    let bad = |at: Span| {
        Diagnostic::new(at, format!("{owner}.{} expects {N} of true or false, like [true, true, false]", f.name))
    };
    let v = f.value.clone().into_inner().next().expect("a value has one child");
    if v.as_rule() != Rule::flags {
        return Err(bad(v.as_span().into()));
    }
    let words: Vec<Pair> = v.clone().into_inner().collect();
    if words.len() != N {
        return Err(bad(v.as_span().into()));
    }
    let mut out = [false; N];
    for (o, w) in out.iter_mut().zip(&words) {
        *o = match w.as_str() {
            "true" => true,
            "false" => false,
            _ => return Err(bad(w.as_span().into())),
        };
    }
    Ok(out)
}

/// A name or a quoted string.
pub fn word<'a>(f: &Field<'a>, owner: &str) -> Result<(&'a str, Span), Diagnostic> {
    let v = f.value.clone().into_inner().next().expect("a value has one child");
    match v.as_rule() {
        Rule::ident => Ok((v.as_str(), v.as_span().into())),
        Rule::string => {
            let body = v.into_inner().next().expect("a string has a body");
            Ok((body.as_str(), body.as_span().into()))
        }
        _ => Err(Diagnostic::new(
            v.as_span().into(),
            format!("{owner}.{} expects a name, found `{}`", f.name, v.as_str()),
        )),
    }
}

pub fn value_span(f: &Field) -> Span {
    f.value.as_span().into()
}
