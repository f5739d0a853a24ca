//! `lagra`, the front: the CLI's subcommands as a library, so that the Python package (and any
//! other front) runs scenes and reports exactly as the command line does.

pub mod bench;
pub mod check;
pub mod fluid;
pub mod grad;
pub mod lean;
pub mod list;
pub mod mcp;
pub mod noether;
pub mod progress;
pub mod ranks;
pub mod reading;
pub mod report;
pub mod run;
pub mod summation;
pub mod sweep;
pub mod terms;
pub mod validation;
pub mod view;
