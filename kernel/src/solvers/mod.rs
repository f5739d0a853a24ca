//! Solvers: programs over the graph that advance the state.

mod velocity_verlet;

pub use velocity_verlet::VelocityVerlet;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    VelocityVerlet,
}

impl Integrator {
    pub const ALL: [Integrator; 1] = [Integrator::VelocityVerlet];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::VelocityVerlet => "velocity_verlet",
        }
    }

    pub fn from_name(s: &str) -> Option<Integrator> {
        Integrator::ALL.into_iter().find(|i| i.name() == s)
    }
}
