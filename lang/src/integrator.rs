//! The solver a scene names, as data: which integrator, the settings it iterates to, what it
//! can handle. The kernel maps each name to its implementation (`lagra_kernel::solvers`).

use lagra_checker::model::TermInstance;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    VelocityVerlet,
    SymplecticEuler,
    Yoshida4,
    Rk4,
    Boris,
    Rattle,
    ActionDescent,
    SequentialImpulses,
    Avbd,
}

/// The settings a `solver` block may give beyond dt and the run length, each read by the
/// integrators that iterate inside a step (`Integrator::settings`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Relative tolerance of the iteration (RATTLE: of each constraint; action descent: of the
    /// window's discrete Euler–Lagrange residual).
    pub tol: f64,
    /// Iteration cap (sweeps over the constraints; descent steps per window).
    pub iterations: u32,
    /// Steps per action window.
    pub window: u32,
    /// Substeps of a contact step (the contacts found once, solved at each).
    pub substeps: u32,
}

impl Integrator {
    pub const ALL: [Integrator; 9] = [
        Integrator::VelocityVerlet,
        Integrator::SymplecticEuler,
        Integrator::Yoshida4,
        Integrator::Rk4,
        Integrator::Boris,
        Integrator::Rattle,
        Integrator::ActionDescent,
        Integrator::SequentialImpulses,
        Integrator::Avbd,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::VelocityVerlet => "velocity_verlet",
            Integrator::SymplecticEuler => "symplectic_euler",
            Integrator::Yoshida4 => "yoshida4",
            Integrator::Rk4 => "rk4",
            Integrator::Boris => "boris",
            Integrator::Rattle => "rattle",
            Integrator::ActionDescent => "action_descent",
            Integrator::SequentialImpulses => "sequential_impulses",
            Integrator::Avbd => "avbd",
        }
    }

    pub fn from_name(s: &str) -> Option<Integrator> {
        Integrator::ALL.into_iter().find(|i| i.name() == s)
    }

    /// One line for `lagra run --help` and the language reference.
    pub fn about(self) -> &'static str {
        match self {
            Integrator::VelocityVerlet => "second order, symplectic; the default",
            Integrator::SymplecticEuler => "first order, symplectic (kick, then drift)",
            Integrator::Yoshida4 => "fourth order, symplectic (three Verlet steps)",
            Integrator::Rk4 => "fourth order, not symplectic (the baseline)",
            Integrator::Boris => "second order; rotates velocities in magnetic fields (|v| kept exactly)",
            Integrator::Rattle => "velocity Verlet keeping distance constraints (SHAKE/RATTLE)",
            Integrator::ActionDescent => "the discrete action over a window, made stationary by descent",
            Integrator::SequentialImpulses => {
                "contact and friction by sequential impulses; the default where solids touch and the scene claims energy or momentum"
            }
            Integrator::Avbd => {
                "contact and friction by augmented vertex block descent (implicit Euler, per-body Newton); the default where solids touch"
            }
        }
    }

    /// The order of the error in dt, as the theory gives it (`lagra bench precision` measures it).
    pub fn order(self) -> u32 {
        match self {
            Integrator::SymplecticEuler | Integrator::SequentialImpulses | Integrator::Avbd => 1,
            Integrator::Yoshida4 | Integrator::Rk4 => 4,
            _ => 2,
        }
    }

    /// The `solver` fields this integrator reads beyond `integrator`, `dt`, `steps`,
    /// `duration` and `steps_per_frame`.
    pub fn settings(self) -> &'static [&'static str] {
        match self {
            Integrator::Rattle => &["tol", "iterations"],
            Integrator::ActionDescent => &["window", "iterations", "tol"],
            Integrator::SequentialImpulses => &["iterations", "substeps"],
            Integrator::Avbd => &["iterations"],
            _ => &[],
        }
    }

    /// The settings it uses when the scene gives none.
    pub fn defaults(self) -> Settings {
        match self {
            Integrator::ActionDescent => Settings { tol: 1e-12, iterations: 1000, window: 16, substeps: 1 },
            Integrator::SequentialImpulses => Settings { tol: 0.0, iterations: 10, window: 1, substeps: 4 },
            Integrator::Avbd => Settings { tol: 0.0, iterations: 10, window: 1, substeps: 1 },
            _ => Settings { tol: 1e-10, iterations: 1000, window: 1, substeps: 1 },
        }
    }

    /// The integrator a scene gets when its solver block names none: one that handles it
    /// (`touching`: solids can touch — a rigid floor, or two rigid bodies). Where solids touch,
    /// AVBD (on the 1,000-block stack three times as fast as sequential impulses a step, and at
    /// rest where they are not: docs/bench), unless the scene claims what AVBD does not keep
    /// (`conserves`: energy, momentum or angular momentum, or Noether's claims): it is implicit
    /// Euler, which dissipates, and it keeps momentum across contacts between bodies only as far
    /// as its sweeps converge, where sequential impulses push equally and oppositely.
    pub fn default_for(constrained: bool, touching: bool, conserves: bool) -> Integrator {
        if touching && conserves {
            Integrator::SequentialImpulses
        } else if touching {
            Integrator::Avbd
        } else if constrained {
            Integrator::Rattle
        } else {
            Integrator::VelocityVerlet
        }
    }

    /// Whether it keeps solids from passing through each other and the floor.
    pub fn keeps_apart(self) -> bool {
        matches!(self, Integrator::SequentialImpulses | Integrator::Avbd)
    }

    /// Whether this integrator can advance a model of these terms (and constraints, if
    /// `constrained`): constraints need RATTLE; Boris rotates by the gyroscopic terms but kicks
    /// with the rest, so no other may depend on velocities; the discrete action here is that of
    /// L = T − V. `Err` names the term that cannot be handled (by its index), or none for the
    /// constraints.
    pub fn handles(
        self,
        terms: &[TermInstance],
        constrained: bool,
        touching: bool,
    ) -> Result<(), (Option<usize>, String)> {
        let name = self.name();
        if touching && constrained {
            return Err((None, "no solver keeps both distance constraints and contacts yet".into()));
        }
        if touching && !self.keeps_apart() {
            return Err((
                None,
                format!(
                    "{name} lets solids pass through each other and the floor: use `sequential_impulses` or `avbd`"
                ),
            ));
        }
        if constrained && self != Integrator::Rattle {
            return Err((None, format!("{name} cannot keep constraints: use `rattle`")));
        }
        let gyroscopic = |t: &TermInstance| {
            let site = lagra_checker::terms::Site { x: [0.0; 3], v: [0.0; 3], m: 1.0, q: 1.0, colour: [0.0; 2] };
            let sites = vec![&site; t.kind.spec().shape.arity()];
            t.kind.gyroscopic(&t.params, &sites).is_some()
        };
        for (n, t) in terms.iter().enumerate() {
            let kind = t.kind.spec().keyword;
            match self {
                Integrator::Boris if t.dissipates() => {
                    return Err((
                        Some(n),
                        format!("boris rotates velocities only for magnetic fields; `{kind}` is dissipative: use velocity_verlet"),
                    ))
                }
                Integrator::ActionDescent if t.dissipates() || gyroscopic(t) => {
                    return Err((
                        Some(n),
                        format!("action_descent makes the action of L = T − V stationary; `{kind}` depends on velocities: use velocity_verlet"),
                    ))
                }
                _ => {}
            }
        }
        Ok(())
    }
}
