//! `lagra-derive`: `lagra_noether_derive::cli` (which its tests run), nothing else, so that
//! `cargo test` need not build this binary (`test = false`): with the release profile's fat LTO
//! over all of symbolica it would be CI's longest link.

fn main() -> std::process::ExitCode {
    lagra_noether_derive::cli::main(std::env::args().skip(1).collect())
}
