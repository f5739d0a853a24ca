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
    compile_on(source, &|_| None)
}

/// Where a compile may find the threads the run will take: asked with a lattice's bodies, and
/// only by a lattice of [`SPREAD_FROM`] bodies or more, so that a small scene starts none
/// before its run; none: one thread.
pub type Threads<'a> = &'a (dyn Fn(usize) -> Option<&'a rayon::ThreadPool> + Sync);

pub use lattice::SPREAD_FROM;

/// [`compile`], a large lattice laid out on the threads `threads` gives: the same scene, to the
/// bit, on any thread count. (The lattice is the one part of a compile that grows with the
/// scene: at 256,000 bodies ~40 ms on one thread, most of it first touches of fresh memory.)
pub fn compile_on<'a>(source: &'a str, threads: Threads<'a>) -> Result<Scene, Diagnostic> {
    let mut file = LagraParser::parse(Rule::file, source).map_err(|e| syntax::diagnostic(e, source))?;
    let scene = file.next().and_then(|f| f.into_inner().next()).expect("a file holds a scene");
    compile::scene(scene, threads)
}

#[cfg(test)]
mod tests;
