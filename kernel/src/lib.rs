//! `lagra-kernel`: the `.lagra` language, the Lagrangian graph, fast forces, solvers and the
//! run loop. Nothing here is trusted: the checker re-evaluates every claim on the exact states
//! this crate produces.

pub mod checking;
pub mod constraints;
pub mod contact;
pub mod derivatives;
pub mod forces;
pub mod grad;
pub mod graph;
pub mod lang;
pub mod neighbours;
pub mod observables;
pub mod predict;
pub mod random;
pub mod rigid;
pub mod run;
pub mod scene;
pub mod solvers;
pub mod state;
pub mod step;
pub mod sum;
pub mod tail;
pub mod thermostat;
pub mod trace;
pub mod traverse;
