//! The end-to-end tests: the `lagra` binary run as a user runs it, on scene files, certificates
//! and state files. One test program, not one per file: each program is linked with the release
//! profile's fat LTO, about 30 s of a core apiece, so sixteen of them cost CI minutes. (Two stay
//! their own programs: tests/peak_memory.rs reads its process's peak memory, and tests/mpi.rs
//! needs `--features mpi`.) `cargo test --release --test end_to_end -- MODULE::` runs one file.

#[path = "../common/mod.rs"]
mod common;

mod adversarial;
mod bench;
mod cli;
mod contact;
mod fluid;
mod grad;
mod house;
mod lean;
mod long_runs;
mod mcp;
mod noether;
mod restart;
mod rigid;
mod solvers;
mod stress;
mod subnormal;
mod sweep;
mod thermostat;
mod threads;
mod view;
