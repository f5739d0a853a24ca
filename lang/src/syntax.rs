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
