//! Physical units written after a number: each word is a known unit with a dimension and a
//! factor to SI base units (kg, m, s, C).

use crate::diagnostic::{Diagnostic, Span};
use crate::{Pair, Rule};
use lagra_checker::units::Dim;

/// A unit expression reduced to its dimension and its factor to SI, `factor · 10^exp10`. The
/// power of ten is kept apart so that it can be folded into the decimal literal before the
/// literal is rounded: `10 cm` is the correctly rounded 0.1, not 10 × 0.01.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    pub dim: Dim,
    pub factor: f64,
    pub exp10: i32,
    pub span: Span,
}

impl Unit {
    /// The SI value of the decimal literal `number` written with this unit.
    pub fn convert(&self, number: &str) -> f64 {
        let (mantissa, exp) = match number.split_once(['e', 'E']) {
            Some((m, e)) => (m, e.parse::<i32>().unwrap_or(0)),
            None => (number, 0),
        };
        let shifted: f64 = format!("{mantissa}e{}", exp.saturating_add(self.exp10)).parse().unwrap_or(f64::NAN);
        shifted * self.factor
    }
}

/// The known unit words: dimension, factor and power of ten to SI.
const WORDS: &[(&str, Dim, f64, i32)] = &[
    ("m", Dim::LENGTH, 1.0, 0),
    ("km", Dim::LENGTH, 1.0, 3),
    ("cm", Dim::LENGTH, 1.0, -2),
    ("mm", Dim::LENGTH, 1.0, -3),
    ("nm", Dim::LENGTH, 1.0, -9),
    ("kg", Dim::MASS, 1.0, 0),
    ("g", Dim::MASS, 1.0, -3),
    ("s", Dim::TIME, 1.0, 0),
    ("ms", Dim::TIME, 1.0, -3),
    ("ns", Dim::TIME, 1.0, -9),
    ("min", Dim::TIME, 60.0, 0),
    ("h", Dim::TIME, 3600.0, 0),
    ("d", Dim::TIME, 86400.0, 0),
    ("Hz", Dim([0, 0, -1, 0]), 1.0, 0),
    ("C", Dim::CHARGE, 1.0, 0),
    ("N", Dim([1, 1, -2, 0]), 1.0, 0),
    ("T", Dim::MAGNETIC, 1.0, 0),
    ("J", Dim::ENERGY, 1.0, 0),
    ("eV", Dim::ENERGY, 1.602_176_634, -19),
    ("rad", Dim::NONE, 1.0, 0),
    ("deg", Dim::NONE, std::f64::consts::PI / 180.0, 0),
];

fn known_words() -> String {
    WORDS.iter().map(|w| w.0).collect::<Vec<_>>().join(", ")
}

/// Reads a `unit` pair: factors multiply; `/` divides by the next factor or group only.
pub fn unit(pair: Pair) -> Result<Unit, Diagnostic> {
    let span = Span::from(pair.as_span());
    let mut acc = Unit { dim: Dim::NONE, factor: 1.0, exp10: 0, span };
    let mut divide = false;
    for p in pair.into_inner() {
        match p.as_rule() {
            Rule::unit_op => divide = p.as_str() == "/",
            Rule::unit_group => {
                let g = group(p)?;
                let n: i8 = if divide { -1 } else { 1 };
                acc = Unit {
                    dim: acc.dim * g.dim.pow(n),
                    factor: acc.factor * g.factor.powi(n.into()),
                    exp10: acc.exp10 + g.exp10 * i32::from(n),
                    span,
                };
                divide = false;
            }
            _ => unreachable!("unit holds only groups and operators"),
        }
    }
    Ok(acc)
}

fn group(pair: Pair) -> Result<Unit, Diagnostic> {
    let inner = pair.into_inner().next().expect("a group has one child");
    if inner.as_rule() == Rule::unit {
        return unit(inner);
    }
    let span = Span::from(inner.as_span());
    let mut parts = inner.into_inner();
    let word = parts.next().expect("a power starts with a word");
    let (_, dim, factor, exp10) = WORDS.iter().find(|w| w.0 == word.as_str()).ok_or_else(|| {
        Diagnostic::new(
            word.as_span().into(),
            format!("unknown unit `{}`; known units: {}", word.as_str(), known_words()),
        )
    })?;
    let n: i8 = match parts.next() {
        None => 1,
        Some(e) => e.as_str().parse().ok().filter(|n: &i8| n.unsigned_abs() <= 12).ok_or_else(|| {
            Diagnostic::new(e.as_span().into(), format!("exponent `{}` is out of range (at most 12)", e.as_str()))
        })?,
    };
    Ok(Unit { dim: dim.pow(n), factor: factor.powi(n.into()), exp10: exp10 * i32::from(n), span })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LagraParser, Rule};
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
        assert_eq!((u.dim, u.factor, u.exp10), (Dim::GRAVITATIONAL, 1.0, 0));
    }

    #[test]
    fn prefixes_convert_exactly() {
        assert_eq!(parse("km/ms").unwrap().convert("1"), 1e6);
        assert_eq!(parse("g cm^-3").unwrap().convert("1"), 1e3);
        assert_eq!(parse("cm").unwrap().convert("10"), 0.1);
        assert_eq!(parse("mm").unwrap().convert("1.5e3"), 1.5);
        // a factor that is not a power of ten costs one more rounding
        assert!((parse("eV").unwrap().convert("1") / 1.602_176_634e-19 - 1.0).abs() <= f64::EPSILON);
    }

    #[test]
    fn unknown_word_is_named() {
        let e = parse("m/furlong").unwrap_err();
        assert!(e.message.starts_with("unknown unit `furlong`"), "{}", e.message);
        assert_eq!(e.span.start, 2);
    }
}
