//! pest's syntax errors, said in the language's own words.

use crate::diagnostic::{Diagnostic, Span};
use crate::Rule;
use pest::error::{Error, ErrorVariant, InputLocation};

fn describe(r: &Rule) -> &'static str {
    match r {
        Rule::EOI => "end of file",
        Rule::scene => "`scene NAME { ... }`",
        Rule::ident | Rule::dotted => "a name",
        Rule::string | Rule::string_body => "a quoted string",
        Rule::number => "a number",
        Rule::index | Rule::indices => "a body index",
        Rule::block => "`{`",
        Rule::field => "a field `name: value`",
        Rule::value | Rule::quantity => "a value",
        Rule::vector => "`[x, y, z]`",
        Rule::unit | Rule::unit_group | Rule::unit_power | Rule::unit_word => "a unit",
        Rule::exponent => "an integer exponent",
        Rule::unit_op => "`*` or `/`",
        Rule::uses | Rule::kw_uses => "`uses`",
        Rule::description | Rule::kw_description => "`description`",
        Rule::units | Rule::kw_units => "`units`",
        Rule::template | Rule::entity | Rule::kw_entity => "`entity`",
        Rule::bond | Rule::kw_bond => "`bond`",
        Rule::constraint | Rule::kw_constraint => "`constraint`",
        Rule::joint | Rule::kw_joint => "`joint`",
        Rule::interaction | Rule::kw_interaction => "`interaction`",
        Rule::thermostat | Rule::kw_thermostat => "`thermostat`",
        Rule::external => "a term",
        Rule::expect => "`@expect`",
        Rule::predict => "`@predict`",
        Rule::solver | Rule::kw_solver => "`solver`",
        Rule::cell | Rule::kw_box => "`box`",
        Rule::lattice | Rule::kw_lattice => "`lattice`",
        Rule::flags => "`[true, false, ...]`",
        Rule::item => "a scene item",
        Rule::file | Rule::WHITESPACE | Rule::COMMENT | Rule::ident_char => "input",
    }
}

/// One line: what was expected, and what was found instead.
pub fn diagnostic(e: Error<Rule>, source: &str) -> Diagnostic {
    let at = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let found = match source[at..].chars().next() {
        None => "end of file".to_string(),
        Some(_) => {
            let word: String = source[at..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            let token = if word.is_empty() { source[at..].chars().take(1).collect() } else { word };
            format!("`{token}`")
        }
    };
    let message = match &e.variant {
        ErrorVariant::ParsingError { positives, .. } if positives[..] == [Rule::ident] => {
            if let Some(d) = named_in_vector(source, at) {
                return d;
            }
            format!("expected a name, found {found}")
        }
        ErrorVariant::ParsingError { positives, .. } if !positives.is_empty() => {
            let mut names: Vec<&str> = positives.iter().map(describe).collect();
            names.dedup();
            let expected = match names.split_last() {
                Some((last, [])) => last.to_string(),
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => unreachable!(),
            };
            format!("expected {expected}, found {found}")
        }
        _ => format!("unexpected {found}"),
    };
    Diagnostic::new(Span { start: at, end: at }, message)
}

/// `[nan, 0, 0]` or `[x0, 1, 2]`: a list that opens with a name is read as flags, and pest
/// fails at the first number, saying a name was expected there. The mistake is the name, in what
/// was meant as a vector: said at the name, where the list at `at` holds a number there (a list
/// of flags that opens with `true` or `false` keeps pest's word).
fn named_in_vector(source: &str, at: usize) -> Option<Diagnostic> {
    let number = |s: &str| s.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.');
    let open = source[..at].rfind('[').filter(|&o| !source[o..at].contains([']', '\n']))?;
    let first = source[open + 1..at].split(',').next()?;
    let name = first.trim();
    let flag = matches!(name, "true" | "false");
    if flag || !number(&source[at..]) || name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || c == '_') {
        return None;
    }
    let start = open + 1 + (first.len() - first.trim_start().len());
    let hint = match name.to_ascii_lowercase().as_str() {
        "nan" | "inf" | "infinity" => ": a value must be finite",
        _ => "",
    };
    let message = format!("expected a number, found `{name}` (a vector holds numbers only{hint})");
    Some(Diagnostic::new(Span { start, end: start + name.len() }, message))
}
