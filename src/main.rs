//! `lagra`: run a scene and certify its claims.

use clap::{Parser, Subcommand};
use lagra::{bench, check, grad, lean, list, mcp, noether, run, sweep, terms, view};
use std::process::ExitCode;

/// mimalloc, for its heaps per thread: the kernel on two threads, 1,000 steps of 32,000 atoms,
/// 143–153 → 118–135 ns/atom-step with the system allocator's arenas replaced; one thread
/// unchanged (docs/bench/README.md). Its transparent huge pages are off (`no_thp`): they cut a
/// 100-step run's page faults from ~12,000 to ~300 but stalled some checkpoints by 10–20 ms
/// (a huge page's fault can compact memory first on this machine).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Exit codes: 0 every claim PASSed, 1 a claim FAILed or was UNDECIDED (or a prediction
/// disagreed, or the run halted), 2 bad input.
#[derive(Parser)]
#[command(
    name = "lagra",
    version,
    about = "A physics engine whose program is the Lagrangian, with certified invariants"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a .lagra scene and certify its @expect claims with interval arithmetic.
    #[command(after_help = run::after_help())]
    Run(run::Args),
    /// Run variants of a scene (every combination of --set NAME=V1,V2,...), each in a process of
    /// its own with its own certificate, a few at a time; then one table.
    #[command(after_help = "Exit status: 0 every variant ran and PASSed every claim and prediction; 1 one did \
not (or crashed: its row says how); 2 bad input, found before any variant runs (every variant is compiled \
first); 130 or 143 stopped by SIGINT or SIGTERM, passed on to the running variants, which write their \
certificates as far as they got.\n\nUnder mpirun (a lagra built with --features mpi): the variants are dealt to the ranks in turn \
(variant i to rank i mod P), each rank runs its own --jobs at a time, and rank 0 gathers the rows and prints the \
table; the --out folder must be one every rank can write (a shared file system on a cluster).")]
    Sweep(sweep::Args),
    /// Re-check a certificate without the kernel (the same code and output as `lagra-check`),
    /// and with --scene, check that it certifies that scene.
    #[command(after_help = "Exit status: 0 the re-check agrees and every claim PASSed; 1 it disagrees, a claim \
did not PASS, or the certificate is not of the scene given; 2 a file is missing, malformed or does not fit.")]
    Check(check::Args),
    /// List the scenes of a folder with their domains, terms, claims and predictions.
    List(list::Args),
    /// Print the vocabulary of terms: name, how it is written, parameters and dimensions.
    Terms,
    /// Write Lean 4: a certificate's certified claims as theorems over its exact checkpoint
    /// values, or (--definitions) the term definitions and their invariance theorems.
    Lean(lean::Args),
    /// What a scene's symmetries conserve (Noether's theorem, from the derived table), and which
    /// term breaks each of the others.
    Noether(noether::Args),
    /// Studies of speed and accuracy (`lagra bench precision`: run time against error).
    Bench(bench::Args),
    /// The exact gradient of an objective of the run with respect to the scene's parameters
    /// (reverse mode through every velocity Verlet step).
    Grad(grad::GradArgs),
    /// Fit parameters to a trace: L-BFGS on the mean squared distance of the positions, with
    /// exact gradients.
    Fit(grad::FitArgs),
    /// Write a self-contained HTML page that plays a trace in 3D, with plots of the energy, the
    /// momentum and each claim's certified bound per checkpoint.
    View(view::Args),
    /// A Model Context Protocol server on stdin/stdout, for agents: list, read, check and run
    /// scenes, the vocabulary, Noether, certificates and gradients as tools.
    Mcp(mcp::Args),
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Run(args) => run::main(args),
        Command::Sweep(args) => sweep::main(args),
        Command::Check(args) => check::main(args),
        Command::List(args) => list::main(args),
        Command::Terms => terms::main(),
        Command::Bench(args) => bench::main(args),
        Command::Lean(args) => lean::main(args),
        Command::Noether(args) => noether::main(args),
        Command::Grad(args) => grad::grad(args),
        Command::Fit(args) => grad::fit(args),
        Command::Mcp(args) => mcp::main(args),
        Command::View(args) => view::main(args),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// The options of `c` and of every command under it that `--help` shows without a word of
    /// what they do, as "lagra fit --threads".
    fn unexplained(c: &clap::Command, path: &str) -> Vec<String> {
        let path = format!("{path} {}", c.get_name()).trim().to_string();
        let bare = c.get_arguments().filter(|a| !a.is_hide_set() && a.get_help().is_none());
        let mut found: Vec<String> = bare.map(|a| format!("{path} --{}", a.get_id())).collect();
        c.get_subcommands().for_each(|s| found.extend(unexplained(s, &path)));
        found
    }

    /// clap's own checks of the commands (conflicting names, defaults a parser refuses), and
    /// every option of every command says in `--help` what it does.
    #[test]
    fn every_option_says_what_it_does() {
        Cli::command().debug_assert();
        assert_eq!(unexplained(&Cli::command(), ""), Vec::<String>::new());
    }
}
