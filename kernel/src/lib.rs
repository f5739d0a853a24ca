//! `lagra-kernel`: what steps a state. A compiled scene (`lagra_lang::Scene`) becomes the
//! Lagrangian graph; fast forces (bonded, pairwise over neighbour lists, fields), constraints,
//! contact and rigid bodies, thermostats, and the solvers that advance a state, each mapped from
//! the name the scene gives. Nothing here is trusted: the checker re-evaluates every claim on
//! the exact states this crate produces.

pub mod constraints;
pub mod contact;
pub mod derivatives;
pub mod forces;
pub mod graph;
pub mod lanes;
#[cfg(target_arch = "x86_64")]
pub(crate) mod lanes8;
pub mod neighbours;
pub mod pieces;
pub mod rigid;
pub mod setup;
pub mod solvers;
pub mod spread;
pub mod state;
pub mod step;
pub mod sum;
pub mod thermostat;
pub mod traverse;
