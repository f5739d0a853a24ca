//! Physical units written after a number: each word is a known unit with a dimension and a
//! factor to SI base units (kg, m, s, C).

use super::diagnostic::{Diagnostic, Span};
use super::{Pair, Rule};
use lagra_checker::units::Dim;

/// A unit expression reduced to its dimension and its factor to SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    pub dim: Dim,
    pub to_si: f64,
    pub span: Span,
}

const E: f64 = 1.602_176_634e-19;

/// The known unit words.
const WORDS: &[(&str, Dim, f64)] = &[
    ("m", Dim::LENGTH, 1.0),
    ("km", Dim::LENGTH, 1e3),
    ("cm", Dim::LENGTH, 1e-2),
    ("mm", Dim::LENGTH, 1e-3),
    ("nm", Dim::LENGTH, 1e-9),
    ("kg", Dim::MASS, 1.0),
    ("g", Dim::MASS, 1e-3),
    ("s", Dim::TIME, 1.0),
    ("ms", Dim::TIME, 1e-3),
    ("ns", Dim::TIME, 1e-9),
    ("Hz", Dim([0, 0, -1, 0]), 1.0),
    ("C", Dim::CHARGE, 1.0),
    ("N", Dim([1, 1, -2, 0]), 1.0),
    ("J", Dim::ENERGY, 1.0),
    ("eV", Dim::ENERGY, E),
];

pub fn known_words() -> String {
    WORDS.iter().map(|w| w.0).collect::<Vec<_>>().join(", ")
}

/// Reads a `unit` pair: factors multiply; `/` divides by the next factor or group only.
pub fn unit(pair: Pair) -> Result<Unit, Diagnostic> {
    let span = Span::from(pair.as_span());
    let mut dim = Dim::NONE;
    let mut to_si = 1.0;
    let mut divide = false;
    for p in pair.into_inner() {
        match p.as_rule() {
            Rule::unit_op => divide = p.as_str() == "/",
            Rule::unit_group => {
                let g = group(p)?;
                let n: i8 = if divide { -1 } else { 1 };
                dim = dim.mul(g.dim.pow(n));
                to_si *= g.to_si.powi(n.into());
                divide = false;
            }
            _ => unreachable!("unit holds only groups and operators"),
        }
    }
    Ok(Unit { dim, to_si, span })
}

fn group(pair: Pair) -> Result<Unit, Diagnostic> {
    let inner = pair.into_inner().next().expect("a group has one child");
    if inner.as_rule() == Rule::unit {
        return unit(inner);
    }
    let span = Span::from(inner.as_span());
    let mut parts = inner.into_inner();
    let word = parts.next().expect("a power starts with a word");
    let (_, dim, to_si) = WORDS.iter().find(|w| w.0 == word.as_str()).ok_or_else(|| {
        Diagnostic::new(
            word.as_span().into(),
            format!(
                "unknown unit `{}`; known units: {}",
                word.as_str(),
                known_words()
            ),
        )
    })?;
    let n: i8 = match parts.next() {
        None => 1,
        Some(e) => e
            .as_str()
            .parse()
            .ok()
            .filter(|n: &i8| n.unsigned_abs() <= 12)
            .ok_or_else(|| {
                Diagnostic::new(
                    e.as_span().into(),
                    format!("exponent `{}` is out of range (at most 12)", e.as_str()),
                )
            })?,
    };
    Ok(Unit {
        dim: dim.pow(n),
        to_si: to_si.powi(n.into()),
        span,
    })
}

#[cfg(test)]
mod tests {
    use super::super::{LagraParser, Rule};
    use super::*;
    use pest::Parser;

    fn parse(s: &str) -> Result<Unit, Diagnostic> {
        unit(LagraParser::parse(Rule::unit, s).unwrap().next().unwrap())
    }

    #[test]
    fn newton_per_metre_is_stiffness() {
        assert_eq!(parse("N/m").unwrap().dim, Dim::STIFFNESS);
    }

    #[test]
    fn gravitational_constant() {
        let u = parse("m^3/(kg s^2)").unwrap();
        assert_eq!((u.dim, u.to_si), (Dim::GRAVITATIONAL, 1.0));
    }

    #[test]
    fn prefixes_scale() {
        assert_eq!(parse("km/ms").unwrap().to_si, 1e6);
        assert_eq!(parse("g cm^-3").unwrap().to_si, 1e-3 / 1e-6);
    }

    #[test]
    fn unknown_word_is_named() {
        let e = parse("m/furlong").unwrap_err();
        assert!(
            e.message.starts_with("unknown unit `furlong`"),
            "{}",
            e.message
        );
        assert_eq!(e.span.start, 2);
    }
}
