//! `lagra terms`: the vocabulary, printed from the checker's specs (the language reference
//! embeds this table, and a test holds the two together).

use lagra_checker::terms::{Kind, Shape};
use std::process::ExitCode;

/// The vocabulary as a Markdown table.
pub fn table() -> String {
    let mut s = String::from("| term | written | acts on | parameters (dimension, default) |\n|---|---|---|---|\n");
    for k in Kind::ALL {
        let spec = k.spec();
        let (written, on) = match spec.shape {
            Shape::Bond(n) => (
                format!("`bond {} [{}]`", spec.keyword, (0..n).map(|i| format!("i{i}")).collect::<Vec<_>>().join(", ")),
                format!("{n} listed bodies"),
            ),
            Shape::Pairwise => (format!("`interaction {}`", spec.keyword), "every pair".to_string()),
            Shape::External => (format!("`{}`", spec.keyword), "every body, or those `on: [..]`".to_string()),
            Shape::Density => {
                (format!("`{}`", spec.keyword), "every body, through the density of its neighbours".to_string())
            }
        };
        // a term that shares its keyword is written with its variant's field
        let written = match k.variant() {
            Some(v) if Kind::lookup(spec.keyword, |s| s == spec.shape, None) == Some(*k) => {
                format!("{written} (`{}: {}`, the default)", v.field, v.value)
            }
            Some(v) => format!("{written} with `{}: {}`", v.field, v.value),
            None => written,
        };
        let params: Vec<String> = spec
            .params
            .iter()
            .map(|p| {
                let dim = p.dim.to_string();
                let kind = if p.len == 3 { " vector" } else { "" };
                let default = p.default.map(|d| format!(", default {d}")).unwrap_or_default();
                format!("`{}` ({dim}{kind}{default})", p.name)
            })
            .collect();
        let dissipative = if k.dissipative() { " — dissipative" } else { "" };
        s.push_str(&format!("| {}{dissipative} | {written} | {on} | {} |\n", spec.name, params.join(", ")));
    }
    s
}

pub fn main() -> ExitCode {
    print!("{}", table());
    ExitCode::SUCCESS
}
