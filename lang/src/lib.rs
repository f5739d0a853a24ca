//! `lagra-lang`: the `.lagra` language. A scene's source is parsed (grammar, diagnostics with
//! spans), its numbers checked for dimension and converted (units), and compiled into a
//! [`Scene`]: data only — bodies, terms with their parameters, claims, the solver's name and
//! settings, the thermostat, the predictions' closed forms. It depends on no engine crate: the
//! kernel steps a `Scene`, the checker judges what the kernel produced.

mod block;
mod compile;
mod diagnostic;
pub mod integrator;
mod lattice;
pub mod params;
pub mod prediction;
pub mod random;
pub mod scene;
pub mod shape;
mod syntax;
pub mod thermostat;
mod units;

pub use diagnostic::{Diagnostic, Span};
pub use scene::Scene;

use pest::Parser;

#[derive(pest_derive::Parser)]
#[grammar = "lagra.pest"]
pub struct LagraParser;

pub type Pair<'a> = pest::iterators::Pair<'a, Rule>;

/// Parses and compiles a scene, or says what is wrong and where. What only the engine can check
/// (the initial state placed on its constraints, solids apart) is `lagra_run::compile`'s.
pub fn compile(source: &str) -> Result<Scene, Diagnostic> {
    let mut file = LagraParser::parse(Rule::file, source).map_err(|e| syntax::diagnostic(e, source))?;
    let scene = file.next().and_then(|f| f.into_inner().next()).expect("a file holds a scene");
    compile::scene(scene)
}

#[cfg(test)]
mod tests;
