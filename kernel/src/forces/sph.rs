//! SPH's fast force (the definition: `lagra_checker::terms::sph`). Two passes over the pairs
//! within the kernel's support, found once per evaluation by the cell list (`traverse::pairs`:
//! the order depends on the positions alone, so any thread count and any restart give the same
//! bits): the densities, then each body's P/ρ², then the pressure and viscous forces of each pair.
//!
//! On threads, each pass is two: every pair's share (W, or the force along d) on its own, then
//! every body's sum of its pairs' shares in the pairs' order (`Incidence`) — the very additions
//! a loop over the pairs makes, so the bits are those of one thread. The search is cut into
//! parts of the cell order whose number follows the bodies, and its lists joined in that order.

use super::density_derivative::{DensityDerivative, Near};
use super::derivative::{Adjoint, Direction, Wanted};
use super::groups::OVERFLOW;
use super::{stride_alone, Force, Frame, Parts, Pool, Singularity};
use crate::spread;
use crate::step::Stride;
use crate::sum::Sum;
use crate::traverse::{self, Binned};
use incidence::{chunked, gathered, Incidence, BODIES};
use lagra_checker::model::{Cell, Model, TermInstance};
use lagra_checker::terms::sph::SUPPORT;
use lagra_checker::terms::Kind;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::sync::{Mutex, MutexGuard};

mod incidence;

/// Pairs a thread takes at once in a pass over the pairs.
const PAIRS: usize = 1024;

/// Bodies to a part of the search. A fluid's body has tens of pairs: from `SPREAD_FROM` bodies
/// (tens of thousands of pairs, ~1 ms a pass on one thread) the passes spread over the pool,
/// where waking it costs tens of µs.
const PART: usize = 64;
const SPREAD_FROM: usize = 512;

/// Threads from which the passes spread. On threads a pass is two, the pairs' shares and the
/// bodies' sums, and costs ~1.6× the CPU time of the one-thread loop (the dam break, 200 steps
/// on one CPU: 2.05 against 1.2 s); on two vCPUs the run took 1.62–1.66 s against 1.44–1.58 s
/// on one thread. From four threads the shares' work is divided by more than it grows by
/// (a projection: no machine with four cores or more was at hand to measure it).
const SPREAD_THREADS: usize = 4;

/// The smoothing kernel W (`lagra_checker::terms::smoothing`).
#[derive(Clone, Copy, PartialEq)]
enum Smoothing {
    WendlandC2,
    CubicSpline,
}

/// One instance's constants.
#[derive(Clone, Copy)]
struct Row {
    smoothing: Smoothing,
    h: f64,
    rho0: f64,
    c0: f64,
    gamma: f64,
    alpha: f64,
    beta: f64,
    /// Tait's B = ρ₀c₀²/γ.
    b: f64,
    /// W(0): 21/(16πh³) for Wendland's C², 1/(πh³) for the cubic spline.
    w0: f64,
    reach2: f64,
}

impl Row {
    fn new(kind: Kind, p: &[f64]) -> Row {
        let (h, rho0, c0, gamma) = (p[0], p[1], p[2], p[3]);
        let reach = SUPPORT * h;
        let (smoothing, w0) = match kind {
            Kind::Sph => (Smoothing::WendlandC2, 21.0 / (16.0 * std::f64::consts::PI * h * h * h)),
            Kind::SphCubicSpline => (Smoothing::CubicSpline, 1.0 / (std::f64::consts::PI * h * h * h)),
            other => unreachable!("{other:?} is not a fluid"),
        };
        Row {
            smoothing,
            h,
            rho0,
            c0,
            gamma,
            alpha: p[4],
            beta: p[5],
            b: rho0 * c0 * c0 / gamma,
            w0,
            reach2: reach * reach,
        }
    }

    /// W(r) and g = −W′(r)/r at r² < reach².
    #[inline(always)]
    fn kernel(&self, r2: f64) -> (f64, f64) {
        let q = r2.sqrt() / self.h;
        let k = self.w0 / (self.h * self.h);
        match self.smoothing {
            Smoothing::WendlandC2 => {
                let t = 1.0 - 0.5 * q;
                let t3 = t * t * t;
                (self.w0 * t3 * t * (2.0 * q + 1.0), 5.0 * k * t3)
            }
            Smoothing::CubicSpline if q < 1.0 => (self.w0 * (1.0 - q * q * (1.5 - 0.75 * q)), k * (3.0 - 2.25 * q)),
            Smoothing::CubicSpline => {
                let t = 2.0 - q;
                (self.w0 * 0.25 * t * t * t, k * 0.75 * t * t / q)
            }
        }
    }

    /// A visit of the search that keeps the pairs within reach in `near`.
    fn keeping<'a>(&'a self, near: &'a mut Vec<Near>) -> impl FnMut(usize, usize, [f64; 3]) -> Result<(), ()> + 'a {
        move |i, j, d| {
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            if r2 < self.reach2 {
                near.push((i as u32, j as u32, d, r2));
            }
            Ok(())
        }
    }

    /// u(ρ) and P/ρ²: Tait's pressure above ρ₀, none below.
    #[inline(always)]
    fn state(&self, rho: f64) -> (f64, f64) {
        if rho <= self.rho0 {
            return (0.0, 0.0);
        }
        let power = (rho / self.rho0).powf(self.gamma - 1.0);
        let u = self.b / self.rho0 * (power - 1.0) / (self.gamma - 1.0) + self.b * (1.0 / rho - 1.0 / self.rho0);
        let pressure = self.b * (power * rho / self.rho0 - 1.0);
        (u, pressure / (rho * rho))
    }
}

/// What one instance found at the positions `at`: its pairs within reach, each body's P/ρ² and
/// the energy Σ m u(ρ). A velocity-dependent force is evaluated again at the same positions
/// (the solver's implicit closing kick), and then only the force pass is redone.
#[derive(Default)]
struct Found {
    near: Vec<Near>,
    /// The search's parts' lists, joined into `near` (their memory kept for the next search).
    parts: Vec<Vec<Near>>,
    incidence: Incidence,
    /// On threads, what each pair gives its two bodies: the density pass's m_b W and mₐ W, the
    /// force pass's force on the first.
    share: Vec<[f64; 3]>,
    rho: Vec<f64>,
    /// Each body's u(ρ) and P/ρ².
    state: Vec<(f64, f64)>,
    /// Each pair's pressure force along d per unit d and its viscosity's k₁ and k₂: what a
    /// force pass finds the same at every velocity, and the solver's closing kick evaluates the
    /// forces at the same positions round after round until the velocities settle.
    fixed: Vec<[f64; 3]>,
    energy: f64,
}

#[derive(Default)]
struct Scratch {
    at: Vec<[f64; 3]>,
    found: Vec<Found>,
}

pub struct Fluid {
    kind: Kind,
    rows: Vec<Row>,
    /// Each row's place in the model and its parameters, for the derivatives.
    instances: Vec<(usize, Vec<f64>)>,
    cell: Option<Cell>,
    pool: Pool,
    /// What the last evaluation found, kept between evaluations.
    scratch: Mutex<Scratch>,
}

impl Fluid {
    pub fn boxed(kind: Kind, t: &[(usize, &TermInstance)], m: &Model, pool: &Pool) -> Box<dyn Force> {
        let rows = t.iter().map(|t| Row::new(kind, &t.1.params)).collect();
        let instances = t.iter().map(|t| (t.0, t.1.params.clone())).collect();
        Box::new(Fluid { kind, rows, instances, cell: m.cell, pool: pool.clone(), scratch: Mutex::default() })
    }

    /// The pool, for a system large enough to spread (`SPREAD_FROM`) on threads enough to gain
    /// (`SPREAD_THREADS`).
    fn pool(&self, s: &Frame) -> Option<&ThreadPool> {
        self.pool.as_deref().filter(|p| s.x.len() >= SPREAD_FROM && p.current_num_threads() >= SPREAD_THREADS)
    }

    /// The pairs within `row`'s reach at `s`'s positions, in the cell list's order: in parts of
    /// `PART` bodies on the pool's threads, their lists joined in order, where there is a pool.
    fn search(&self, row: &Row, s: &Frame, near: &mut Vec<Near>, parts: &mut Vec<Vec<Near>>) {
        let reach = row.reach2.sqrt();
        let (Some(pool), Some(binned)) = (self.pool(s), Binned::new(s.x, &self.cell, reach)) else {
            near.clear();
            return traverse::pairs(s.x, &self.cell, Some(reach), row.keeping(near)).expect("the visit never fails");
        };
        let cells = binned.split(s.x.len().div_ceil(PART));
        parts.resize_with(cells.len(), Vec::new);
        spread::pass(|| {
            pool.install(|| {
                parts.par_iter_mut().zip(cells).for_each(|(part, cells)| {
                    part.clear();
                    traverse::pairs_in(s.x, &self.cell, &binned, cells, row.keeping(part))
                        .expect("the visit never fails");
                });
                // the list keeps its memory from the search before: only a longer one is filled
                near.resize(parts.iter().map(Vec::len).sum(), (0, 0, [0.0; 3], 0.0));
                let mut rest = &mut near[..];
                let into: Vec<&mut [Near]> = parts
                    .iter()
                    .map(|p| {
                        let (head, tail) = std::mem::take(&mut rest).split_at_mut(p.len());
                        rest = tail;
                        head
                    })
                    .collect();
                into.into_par_iter().zip(&*parts).for_each(|(into, part)| into.copy_from_slice(part));
            })
        });
    }

    /// The pairs, densities and pressures of `row` at `s`'s positions.
    fn find(&self, row: &Row, s: &Frame, found: &mut Found) {
        let Found { near, parts, incidence, share, rho, state, fixed, energy } = found;
        self.search(row, s, near, parts);
        let (pool, n) = (self.pool(s), s.x.len());
        rho.clear();
        rho.extend(s.m.iter().map(|m| m * row.w0));
        let given = |&(i, j, _, r2): &Near| {
            let (w, _) = row.kernel(r2);
            [s.m[j as usize] * w, s.m[i as usize] * w, 0.0]
        };
        match pool {
            None => {
                for p in near.iter() {
                    let [to_i, to_j, _] = given(p);
                    rho[p.0 as usize] += to_i;
                    rho[p.1 as usize] += to_j;
                }
            }
            Some(pool) => {
                incidence.of(near, n);
                share.resize(near.len(), [0.0; 3]);
                chunked(Some(pool), PAIRS, share, |first, share| {
                    share.iter_mut().zip(&near[first..]).for_each(|(share, p)| *share = given(p))
                });
                gathered(pool, incidence, rho, |rho, p, second| *rho += share[p][second as usize]);
            }
        }
        state.resize(n, (0.0, 0.0));
        chunked(pool, BODIES, state, |first, state| {
            state.iter_mut().zip(&rho[first..]).for_each(|(u, rho)| *u = row.state(*rho))
        });
        fixed.resize(near.len(), [0.0; 3]);
        chunked(pool, PAIRS, fixed, |first, fixed| {
            for (fixed, &(i, j, _, r2)) in fixed.iter_mut().zip(&near[first..]) {
                let (i, j) = (i as usize, j as usize);
                let (_, g) = row.kernel(r2);
                let mm = s.m[i] * s.m[j];
                let dd = r2 + 0.01 * row.h * row.h;
                let k = mm * g / row.rho0;
                let k1 = k * row.alpha * row.c0 * row.h / dd;
                let k2 = k * row.beta * row.h * row.h / (dd * dd);
                *fixed = [-mm * (state[i].1 + state[j].1) * g, k1, k2];
            }
        });
        let mut sum = Sum::default();
        for (m, (u, _)) in s.m.iter().zip(state.iter()) {
            sum.add(m * u);
        }
        *energy = sum.value();
    }

    /// What each row finds at `s`'s positions: kept from the last evaluation if they are the
    /// same bits (−0.0 and 0.0 may give forces of another sign), found again if not.
    fn found(&self, s: &Frame) -> MutexGuard<'_, Scratch> {
        let mut scratch = self.scratch.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let Scratch { at, found } = &mut *scratch;
        let moved =
            at.len() != s.x.len() || at.iter().zip(s.x).any(|(a, b)| a.map(f64::to_bits) != b.map(f64::to_bits));
        if moved || found.len() != self.rows.len() {
            found.resize_with(self.rows.len(), Found::default);
            for (row, found) in self.rows.iter().zip(found.iter_mut()) {
                self.find(row, s, found);
            }
            at.clear();
            at.extend_from_slice(s.x);
        }
        scratch
    }

    /// Each row's derivatives, over the pairs it finds at `s`.
    fn derivatives(&self, s: &Frame, mut each: impl FnMut(&DensityDerivative)) {
        let scratch = self.found(s);
        for ((term, p), found) in self.instances.iter().zip(&scratch.found) {
            each(&DensityDerivative { kind: self.kind, p, term: *term, near: &found.near });
        }
    }

    /// The forces added to `f`, and the energy Σ m u(ρ); with `virial`, the virial −Σ d·F over
    /// the pairs too (else 0). On one thread a loop over the pairs adds each pair's force to
    /// both its bodies; on threads each body adds its pairs' in the same order.
    fn pass(&self, s: &Frame, f: &mut [[f64; 3]], virial: bool) -> Result<(f64, f64), Singularity> {
        let mut scratch = self.found(s);
        let pool = self.pool(s);
        let (mut energy, mut w) = (Sum::default(), Sum::default());
        for (row, Found { near, incidence, share, fixed, energy: e, .. }) in self.rows.iter().zip(&mut scratch.found) {
            energy.add(*e);
            let viscous = row.alpha != 0.0 || row.beta != 0.0;
            // the force on the pair's first body along d, per unit d
            let along = |&(i, j, d, _): &Near, &[pressure, k1, k2]: &[f64; 3]| {
                let (i, j) = (i as usize, j as usize);
                let mut along = pressure;
                if viscous {
                    let closing = -((s.v[i][0] - s.v[j][0]) * d[0]
                        + (s.v[i][1] - s.v[j][1]) * d[1]
                        + (s.v[i][2] - s.v[j][2]) * d[2]);
                    // a pair moving apart adds k₁·(−0) − k₂·0 = −0 (k₁, k₂ ≥ 0 and finite), which
                    // leaves any sum as it was: the bits of a branch, without the branch that
                    // half the pairs would send the wrong way
                    let closing = if closing < 0.0 { closing } else { -0.0 };
                    along += k1 * closing - k2 * closing * closing;
                }
                along
            };
            match pool {
                None => {
                    for (p, fixed) in near.iter().zip(fixed.iter()) {
                        let (a, (i, j, d, r2)) = (along(p, fixed), *p);
                        for c in 0..3 {
                            f[i as usize][c] += a * d[c];
                            f[j as usize][c] -= a * d[c];
                        }
                        if virial {
                            w.add(-a * r2);
                        }
                    }
                }
                Some(pool) => {
                    chunked(Some(pool), PAIRS, share, |first, share| {
                        for ((share, p), fixed) in share.iter_mut().zip(&near[first..]).zip(&fixed[first..]) {
                            let a = along(p, fixed);
                            *share = p.2.map(|d| a * d);
                        }
                    });
                    let share = &*share;
                    gathered(pool, incidence, f, |f, p, second| {
                        for c in 0..3 {
                            match second {
                                false => f[c] += share[p][c],
                                true => f[c] -= share[p][c],
                            }
                        }
                    });
                    if virial {
                        near.iter().zip(fixed.iter()).for_each(|(p, fixed)| w.add(-along(p, fixed) * p.3));
                    }
                }
            }
        }
        let (e, w) = (energy.value(), w.value());
        if e.is_finite() && w.is_finite() && f.iter().flatten().all(|c| c.is_finite()) {
            Ok((e, w))
        } else {
            Err(Singularity { term: self.kind.name(), bodies: vec![], what: OVERFLOW, seen: None })
        }
    }
}

impl Force for Fluid {
    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity> {
        stride_alone(self, stride, parts)
    }
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], _energy: bool) -> Result<f64, Singularity> {
        self.pass(s, f, false).map(|(e, _)| e)
    }
    fn velocity_dependent(&self) -> bool {
        self.rows.iter().any(|r| r.alpha != 0.0 || r.beta != 0.0)
    }
    fn virial(&self, s: &Frame) -> Option<Result<f64, Singularity>> {
        let mut scratch = vec![[0.0; 3]; s.x.len()];
        Some(self.pass(s, &mut scratch, true).map(|(_, w)| w))
    }
    fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity> {
        self.derivatives(s, |d| d.tangent(s, dir, df));
        Ok(())
    }
    fn pullback(&self, s: &Frame, g: &[[f64; 3]], w: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        self.derivatives(s, |d| d.pullback(s, g, w.of(d.term), out));
        Ok(())
    }
    fn potential_pullback(&self, s: &Frame, w: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        self.derivatives(s, |d| d.potential_pullback(s, w.of(d.term), out));
        Ok(())
    }
    fn plan(&self) -> String {
        let reach = self.rows.iter().map(|r| r.reach2.sqrt()).fold(0.0, f64::max);
        let threads = self.pool.as_ref().map_or(1, |p| p.current_num_threads());
        format!(
            "SPH: the pairs within {reach} from a cell list each evaluation, a density pass then a force pass, with {SPREAD_FROM} bodies or more and {SPREAD_THREADS} threads or more (here {threads}) each pass on the threads, each body adding its pairs' shares in the pairs' order (the bits of one thread)"
        )
    }
}

#[cfg(test)]
mod tests;
