//! Forward mode: tangents carried along the run, one sweep per parameter (the cross-check of
//! reverse mode, and the cheaper one for a parameter or two).

use super::{failed, settled, Growth, Objective, Outcome, Run};
use lagra_kernel::forces::derivative::{Adjoint, Direction};
use lagra_kernel::solvers::Stepper;
use lagra_lang::integrator::Integrator;
use lagra_lang::params::{Named, Param};

/// Forward mode: one tangent sweep per parameter.
pub(super) fn forward(
    run: &Run,
    objective: &Objective,
    wrt: &[Named],
    tell: &mut dyn FnMut(&str, u64, u64),
) -> Result<Outcome, String> {
    let mut out = vec![];
    let (mut value, mut largest) = (0.0, 1.0f64);
    for (k, named) in wrt.iter().enumerate() {
        let (v, d, grew) = sweep(run, objective, named.param, &mut |done, of| {
            tell(&named.name, done + k as u64 * of, of * wrt.len() as u64)
        })?;
        (value, largest) = (v, largest.max(grew));
        out.push((named.name.clone(), d));
    }
    Ok((value, out, Growth::over(largest, run.steps as f64 * run.dt), 1))
}

/// The tangent of the state and parameters along one parameter, at the start.
struct Tangent {
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    m: Vec<f64>,
    q: Vec<f64>,
    params: Vec<Vec<f64>>,
}

impl Tangent {
    fn dir(&self) -> Direction<'_> {
        Direction { x: &self.x, v: &self.v, m: &self.m, q: &self.q, params: &self.params }
    }

    /// ⟨∇, tangent⟩ for a gradient gathered in an adjoint.
    fn dot(&self, a: &Adjoint) -> f64 {
        let d3 = |p: &[[f64; 3]], q: &[[f64; 3]]| -> f64 {
            p.iter().zip(q).map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).sum()
        };
        let d = |p: &[f64], q: &[f64]| -> f64 { p.iter().zip(q).map(|(p, q)| p * q).sum() };
        d3(&self.x, &a.x)
            + d3(&self.v, &a.v)
            + d(&self.m, &a.m)
            + d(&self.q, &a.q)
            + self.params.iter().zip(&a.params).map(|(p, q)| d(p, q)).sum::<f64>()
    }
}

/// One tangent sweep: the objective, its derivative along `p`, and how much the tangent grew.
fn sweep(
    run: &Run,
    objective: &Objective,
    p: Param,
    tell: &mut dyn FnMut(u64, u64),
) -> Result<(f64, f64, f64), String> {
    let (g, n, dt) = (&run.graph, run.steps, run.dt);
    let h = 0.5 * dt;
    let bodies = run.scene.x0.len();
    let mut t = Tangent {
        x: vec![[0.0; 3]; bodies],
        v: vec![[0.0; 3]; bodies],
        m: vec![0.0; bodies],
        q: vec![0.0; bodies],
        params: run.scene.model.terms.iter().map(|t| vec![0.0; t.params.len()]).collect(),
    };
    match p {
        Param::Term { term, index } => t.params[term][index] = 1.0,
        Param::Mass(i) => t.m[i] = 1.0,
        Param::Charge(i) => t.q[i] = 1.0,
        Param::Position(i, c) => t.x[i][c] = 1.0,
        Param::Velocity(i, c) => t.v[i][c] = 1.0,
    }
    let mut s = run.start();
    let mut st =
        Stepper::new(Integrator::VelocityVerlet, run.scene.solver.settings, g, &s).map_err(|e| e.to_string())?;
    let mut df = vec![[0.0; 3]; bodies];
    g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
    let size = |t: &Tangent| t.x.iter().chain(&t.v).flatten().map(|c| c * c).sum::<f64>().sqrt();
    let (start, mut largest) = (size(&t).max(1.0), 1.0f64);
    let (mut value, mut derivative) = (0.0, 0.0);
    loop {
        value += run.value(objective, &s, st.potential());
        if run.reads.binary_search(&s.step).is_ok() {
            let mut grad = run.zero();
            run.objective_gradient(objective, &s, &mut grad)?;
            derivative += t.dot(&grad);
        }
        if s.step == n {
            break;
        }
        // the opening kick and drift of the tangent, with the forces and their tangent here
        let f0 = st.evaluated().f.clone();
        let half: Vec<[f64; 3]> = (0..bodies)
            .map(|i| {
                let (w, dw) = (g.inverse_masses[i], -t.m[i] * g.inverse_masses[i] * g.inverse_masses[i]);
                std::array::from_fn(|c| t.v[i][c] + h * (w * df[i][c] + dw * f0[i][c]))
            })
            .collect();
        for (x, v) in t.x.iter_mut().zip(&half) {
            (0..3).for_each(|c| x[c] += dt * v[c]);
        }
        st.step(g, &mut s, dt).map_err(failed(s.step + 1))?;
        // the closing kick: δv₁ = δv½ + (h/m)δF(x₁, v₁) − (h δm/m²)F₁, a fixed point in δv₁ if
        // the forces depend on velocities
        let f1 = &st.evaluated().f;
        t.v = half.clone();
        for round in 0..64 {
            g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
            let next: Vec<[f64; 3]> = (0..bodies)
                .map(|i| {
                    let (w, dw) = (g.inverse_masses[i], -t.m[i] * g.inverse_masses[i] * g.inverse_masses[i]);
                    std::array::from_fn(|c| half[i][c] + h * (w * df[i][c] + dw * f1[i][c]))
                })
                .collect();
            let done = settled(&next, &t.v);
            t.v = next;
            if !g.velocity_dependent() || done {
                break;
            }
            if round == 63 {
                return Err(format!("the tangent of the implicit closing kick at step {} did not converge", s.step));
            }
        }
        if g.velocity_dependent() {
            g.tangent(&s, &t.dir(), &mut df).map_err(|e| e.to_string())?;
        }
        largest = largest.max(size(&t) / start);
        tell(s.step, n);
    }
    Ok((value, derivative, largest))
}
