//! The `.lagra` language: grammar, diagnostics, units and the compiler to a [`Scene`].

mod block;
mod compile;
mod diagnostic;
mod lattice;
mod shape;
mod syntax;
mod units;

pub use diagnostic::{Diagnostic, Span};

use crate::scene::Scene;
use pest::Parser;

#[derive(pest_derive::Parser)]
#[grammar = "lang/lagra.pest"]
pub struct LagraParser;

pub type Pair<'a> = pest::iterators::Pair<'a, Rule>;

/// Parses and compiles a scene, or says what is wrong and where.
pub fn compile(source: &str) -> Result<Scene, Diagnostic> {
    let mut file = LagraParser::parse(Rule::file, source).map_err(|e| syntax::diagnostic(e, source))?;
    let scene = file.next().and_then(|f| f.into_inner().next()).expect("a file holds a scene");
    compile::scene(scene)
}

#[cfg(test)]
mod tests;
