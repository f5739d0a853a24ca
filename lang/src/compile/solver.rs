//! The solver and thermostat blocks, settled once the scene is known, and the constraints
//! the initial state is placed on.

use super::{err, Compiler};
use crate::block::{value_span, word, Block};
use crate::diagnostic::{Diagnostic, Span};
use crate::integrator::{Integrator, Settings};
use crate::scene::Solver;
use crate::thermostat::Thermostat;
use crate::Pair;
use lagra_checker::claims::ClaimKind;
use lagra_checker::model::{Cell, Constraint};
use lagra_checker::units::Dim;

/// Run length when the solver gives neither `steps` nor `duration`.
const DEFAULT_STEPS: u64 = 5000;

/// A `solver` block as written: the integrator is settled once the whole scene is known (the
/// default depends on its constraints), and so are the settings it may take.
pub(super) struct SolverBlock {
    pub(super) integrator: Option<(Integrator, Span)>,
    /// `equilibrate` (a time), `sample_every`, `tail_corrections`.
    pub(super) equilibrate: Option<f64>,
    pub(super) sample_every: Option<u64>,
    /// Where `tail_corrections: true` was asked for.
    pub(super) tail_corrections: Option<Span>,
    /// `tol`, `iterations`, `window`, each with where it was written.
    pub(super) settings: Vec<(&'static str, f64, Span)>,
    pub(super) dt: f64,
    pub(super) steps: u64,
    pub(super) steps_per_frame: u64,
    pub(super) at: Span,
}

impl<'a> Compiler<'a> {
    /// `thermostat nose_hoover { T, tau, chain }` or `thermostat langevin { T, gamma, seed }`:
    /// T is k_B·T, an energy.
    #[allow(clippy::type_complexity)]
    pub(super) fn thermostat(
        &self,
        kw: &Pair,
        mut b: Block,
    ) -> Result<(f64, Thermostat, Option<usize>, Span), Diagnostic> {
        let at: Span = kw.as_span().into();
        let name = kw.as_str();
        let mut need = |field: &str, dim: Dim, what: &str| -> Result<f64, Diagnostic> {
            let f = b.take(field).ok_or_else(|| Diagnostic::new(at, format!("{name} needs `{field}` ({what})")))?;
            self.rd.positive(&f, name, dim)
        };
        let kt = need("T", Dim::ENERGY, "k_B·T, an energy")?;
        let (thermostat, links) = match name {
            "nose_hoover" => {
                let tau = need("tau", Dim::TIME, "the relaxation time")?;
                let links = match b.take("chain") {
                    None => 3,
                    Some(f) => match self.rd.count(&f, name)? {
                        n @ 1..=64 => n as usize,
                        n => return err(value_span(&f), format!("nose_hoover.chain takes 1 to 64 links, got {n}")),
                    },
                };
                b.check_names(name, &["T", "tau", "chain"])?;
                (Thermostat::NoseHoover { tau }, Some(links))
            }
            "langevin" => {
                let gamma = need("gamma", Dim::TIME.pow(-1), "the friction rate, per time")?;
                let seed = b.take("seed").map(|f| self.rd.count(&f, name)).transpose()?.unwrap_or(1);
                b.check_names(name, &["T", "gamma", "seed"])?;
                (Thermostat::Langevin { kt, gamma, seed }, None)
            }
            _ => return err(at, format!("unknown thermostat `{name}`; known: nose_hoover, langevin")),
        };
        Ok((kt, thermostat, links, at))
    }

    pub(super) fn solver(&self, mut b: Block) -> Result<SolverBlock, Diagnostic> {
        let integrator = match b.take("integrator") {
            None => None,
            Some(f) => {
                let (name, at) = word(&f, "solver")?;
                let integrator = Integrator::from_name(name).ok_or_else(|| {
                    let known: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
                    Diagnostic::new(at, format!("unknown integrator `{name}`; known: {}", known.join(", ")))
                })?;
                Some((integrator, at))
            }
        };
        let dt = b.take("dt").ok_or_else(|| Diagnostic::new(b.span, "solver needs a time step `dt`"))?;
        let dt = self.rd.positive(&dt, "solver", Dim::TIME)?;
        let steps = match (b.take("steps"), b.take("duration")) {
            (Some(_), Some(d)) => return err(d.span, "give `steps` or `duration`, not both"),
            (Some(s), None) => self.rd.count(&s, "solver")?,
            (None, Some(d)) => {
                let n = (self.rd.positive(&d, "solver", Dim::TIME)? / dt).round();
                if !(1.0..=9.0e15).contains(&n) {
                    return err(value_span(&d), format!("duration / dt = {n} steps is out of range"));
                }
                n as u64
            }
            (None, None) => DEFAULT_STEPS,
        };
        let steps_per_frame = b.take("steps_per_frame").map(|f| self.rd.count(&f, "solver")).transpose()?.unwrap_or(10);
        let mut settings = vec![];
        if let Some(f) = b.take("tol") {
            settings.push(("tol", self.rd.positive(&f, "solver", Dim::NONE)?, f.span));
        }
        for name in ["iterations", "window", "substeps"] {
            if let Some(f) = b.take(name) {
                let n = self.rd.count(&f, "solver")?;
                if n > u32::MAX as u64 {
                    return err(value_span(&f), format!("solver.{name} is at most {}", u32::MAX));
                }
                settings.push((name, n as f64, f.span));
            }
        }
        let equilibrate = match b.take("equilibrate") {
            None => None,
            Some(f) => {
                let t = self.rd.numbers(&f, "solver", Dim::TIME, 1)?[0];
                if !(t >= 0.0 && t.is_finite()) {
                    return err(value_span(&f), format!("solver.equilibrate must be a time ≥ 0, got {t}"));
                }
                Some(t)
            }
        };
        let sample_every = b.take("sample_every").map(|f| self.rd.count(&f, "solver")).transpose()?;
        let tail_corrections = match b.take("tail_corrections") {
            None => None,
            Some(f) => match word(&f, "solver")? {
                ("true", at) => Some(at),
                ("false", _) => None,
                (w, at) => return err(at, format!("solver.tail_corrections is true or false, got `{w}`")),
            },
        };
        b.check_names("solver", &[])?;
        Ok(SolverBlock {
            integrator,
            equilibrate,
            sample_every,
            tail_corrections,
            settings,
            dt,
            steps,
            steps_per_frame,
            at: b.span,
        })
    }

    /// The integrator the block names, or the one the model needs; its settings, each given one
    /// checked to be one it takes; and whether it handles the model's terms.
    pub(super) fn settle(&self, b: SolverBlock) -> Result<Solver, Diagnostic> {
        let constrained = !self.constraints.is_empty();
        let touching = self.floor.is_some() || self.bodies.iter().filter(|b| b.solid.is_some()).count() >= 2;
        let jointed = self.joints.first().map(|j| j.span);
        let conserves = self.noether.is_some()
            || self.claims.iter().any(|c| {
                matches!(
                    c.kind,
                    ClaimKind::EnergyConservation
                        | ClaimKind::MomentumConservation
                        | ClaimKind::AngularMomentumConservation
                )
            });
        let default = if jointed.is_some() {
            Integrator::Avbd
        } else {
            Integrator::default_for(constrained, touching, conserves)
        };
        let (integrator, at) = b.integrator.unwrap_or((default, b.at));
        if let (Some(joint), true) = (jointed, integrator != Integrator::Avbd) {
            return err(
                joint,
                format!(
                    "joints are held by `avbd` alone; the solver's {} cannot keep them: set `integrator: \"avbd\"`",
                    integrator.name()
                ),
            );
        }
        let mut settings: Settings = integrator.defaults();
        for (name, value, span) in b.settings {
            if !integrator.settings().contains(&name) {
                let takes = match integrator.settings() {
                    [] => "takes no settings".to_string(),
                    s => format!("takes {}", s.join(", ")),
                };
                let owners: Vec<&str> =
                    Integrator::ALL.iter().filter(|i| i.settings().contains(&name)).map(|i| i.name()).collect();
                return err(
                    span,
                    format!("`{name}` is a setting of {}; {} {takes}", owners.join(" and "), integrator.name()),
                );
            }
            match name {
                "tol" => settings.tol = value,
                "iterations" => settings.iterations = value as u32,
                "substeps" => settings.substeps = value as u32,
                _ => settings.window = value as u32,
            }
        }
        if let Some((_, t, _, _)) = &self.thermostat {
            if integrator != Integrator::VelocityVerlet {
                return err(
                    at,
                    format!(
                        "a {} thermostat runs inside velocity_verlet; {} cannot host it",
                        t.name(),
                        integrator.name()
                    ),
                );
            }
        }
        integrator.handles(&self.terms, constrained, touching).map_err(|(term, why)| {
            let wherefrom = term.map(|n| format!(" (line {})", self.term_line[n])).unwrap_or_default();
            Diagnostic::new(at, format!("{why}{wherefrom}"))
        })?;
        Ok(Solver { integrator, settings, dt: b.dt, steps: b.steps, steps_per_frame: b.steps_per_frame })
    }

    /// Each constraint with its length (the bodies' initial distance if none is given), the
    /// initial state checked to meet them within 10⁻⁶ (the kernel then moves it onto them exactly,
    /// `lagra_kernel::setup::place`).
    pub(super) fn constrain(&mut self, cell: &Option<Cell>) -> Result<Vec<Constraint>, Diagnostic> {
        const PLACED: f64 = 1e-6;
        let mut out = vec![];
        for &([i, j], length, at) in &self.constraints {
            let d = Cell::image(cell, std::array::from_fn(|c| self.x0[j][c] - self.x0[i][c]));
            let apart = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let length = length.unwrap_or(apart);
            if !(length > 0.0) {
                return err(at, format!("constraint [{i}, {j}]: its bodies start at one point: give a `length`"));
            }
            if (apart - length).abs() > PLACED * length {
                return err(at, format!("constraint [{i}, {j}] holds its bodies {length} apart, but they start {apart} apart: place them within {PLACED:e} of the length"));
            }
            out.push(Constraint { bodies: [i, j], length });
        }
        Ok(out)
    }
}
