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
use lagra_checker::model::{Cell, Model, TermInstance};
use lagra_checker::terms::sph::SUPPORT;
use lagra_checker::terms::Kind;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::sync::{Mutex, MutexGuard};

/// Pairs a thread takes at once in a pass over the pairs; bodies, over the bodies (tens of
/// pairs each).
const PAIRS: usize = 1024;
const BODIES: usize = 32;

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

/// Each body's pairs in the pairs' order: `entries[start[b]..start[b + 1]]`, each a pair's
/// index times two, plus one where the body is the pair's second.
#[derive(Default)]
struct Incidence {
    start: Vec<usize>,
    entries: Vec<usize>,
    next: Vec<usize>,
}

impl Incidence {
    /// The bodies' pairs of `near` among `n` bodies (a counting sort, in the pairs' order).
    fn of(&mut self, near: &[Near], n: usize) {
        let Incidence { start, entries, next } = self;
        start.clear();
        start.resize(n + 1, 0);
        for &(i, j, ..) in near {
            start[i as usize + 1] += 1;
            start[j as usize + 1] += 1;
        }
        for b in 0..n {
            start[b + 1] += start[b];
        }
        next.clear();
        next.extend_from_slice(&start[..n]);
        entries.clear();
        entries.resize(2 * near.len(), 0);
        for (p, &(i, j, ..)) in near.iter().enumerate() {
            for (side, b) in [i, j].into_iter().enumerate() {
                entries[next[b as usize]] = 2 * p + side;
                next[b as usize] += 1;
            }
        }
    }

    /// Body `b`'s pairs: (pair, whether b is its second body).
    fn pairs_of(&self, b: usize) -> impl Iterator<Item = (usize, bool)> + '_ {
        self.entries[self.start[b]..self.start[b + 1]].iter().map(|&e| (e / 2, e % 2 == 1))
    }
}

/// `each(first, items)` over `items` in chunks of `chunk` on the pool's threads, `first` the
/// index of a chunk's first item; on this thread without a pool. Each item is its own, so the
/// bits are the same.
fn chunked<T: Send>(
    pool: Option<&ThreadPool>,
    chunk: usize,
    items: &mut [T],
    each: impl Fn(usize, &mut [T]) + Sync + Send,
) {
    match pool {
        Some(pool) => spread::pass(|| {
            pool.install(|| items.par_chunks_mut(chunk).enumerate().for_each(|(k, c)| each(k * chunk, c)))
        }),
        None => each(0, items),
    }
}

/// `add(item, pair, second)` for each body's item and each of its pairs in the pairs' order
/// (`Incidence`), on the pool's threads.
fn gathered<T: Send>(
    pool: &ThreadPool,
    incidence: &Incidence,
    items: &mut [T],
    add: impl Fn(&mut T, usize, bool) + Sync + Send,
) {
    chunked(Some(pool), BODIES, items, |first, items| {
        for (b, item) in (first..).zip(items) {
            for (p, second) in incidence.pairs_of(b) {
                add(item, p, second);
            }
        }
    })
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
mod tests {
    use super::super::{group, Frame};
    use crate::forces::dual::Rng;
    use lagra_checker::model::{Body, Cell, Model, Snapshot, TermInstance, UnitSystem};
    use lagra_checker::quantities::Lifted;
    use lagra_checker::terms::Kind;
    use proptest::prelude::*;

    /// `n` bodies of random masses scattered about a cube 3h wide (jittered cubic lattice), with
    /// random velocities; ρ₀ at `squeeze` times the bodies' mean density, so that some are above
    /// it (pressed) and some below (no pressure); in a periodic box along z if `periodic`. The
    /// seed's parity picks the kernel: Wendland's C² (`Sph`) or the cubic spline.
    fn fluid(seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Fluid3 {
        block(5, seed, squeeze, alpha, beta, periodic)
    }

    /// `fluid` with `side`³ bodies.
    fn block(side: usize, seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Fluid3 {
        let mut rng = Rng::new(seed);
        let h = 0.3;
        let x: Vec<[f64; 3]> = (0..side * side * side)
            .map(|k| {
                let ijk = [k % side, (k / side) % side, k / (side * side)];
                std::array::from_fn(|c| (ijk[c] as f64 + 0.5) * 0.2 + rng.uniform(-0.06, 0.06))
            })
            .collect();
        let v = (0..x.len()).map(|_| std::array::from_fn(|_| rng.uniform(-1.0, 1.0))).collect();
        let bodies: Vec<Body> = (0..x.len())
            .map(|_| Body {
                mass: rng.uniform(0.5, 1.5) * 0.008,
                charge: 0.0,
                colour: [0.0; 2],
                moments: None,
                solid: None,
            })
            .collect();
        let rho0 = squeeze * 1.0;
        let kind = if seed % 2 == 0 { Kind::Sph } else { Kind::SphCubicSpline };
        let term = TermInstance { kind, sites: vec![], params: vec![h, rho0, 10.0, 7.0, alpha, beta] };
        // one z period holds the five layers and more than twice the reach 2h = 0.6 (the nearest image
        // is the only one within reach: a shorter period would cut pairs at its half)
        let cell = periodic.then_some(Cell { size: [10.0, 10.0, 0.25 * side as f64], periodic: [false, false, true] });
        let model = Model {
            units: UnitSystem::Reduced,
            cell,
            bodies,
            terms: vec![term],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        (model, x, v)
    }

    type Fluid3 = (Model, Vec<[f64; 3]>, Vec<[f64; 3]>);

    fn fast(model: &Model, x: &[[f64; 3]], v: &[[f64; 3]]) -> (Vec<[f64; 3]>, f64) {
        let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
        let (q, c) = (vec![0.0; x.len()], vec![[0.0; 2]; x.len()]);
        let mut f = vec![[0.0; 3]; x.len()];
        let e = group(model.terms[0].kind, &[(0, &model.terms[0])], model, &None)
            .accumulate(&Frame { x, v, m: &m, q: &q, c: &c }, &mut f, true)
            .unwrap();
        (f, e)
    }

    /// On threads each body adds its pairs' shares in the pairs' order: the forces, energy and
    /// virial are the bits of one thread's loop over the pairs, at a first evaluation and at a
    /// second at the same positions with other velocities (the pairs' fixed parts kept), for
    /// 1,000 bodies (past `SPREAD_FROM`) on pools of 4 and 7 threads (past `SPREAD_THREADS`).
    #[test]
    fn threads_give_the_bits_of_one() {
        for (seed, periodic) in [(4, false), (7, true)] {
            let (model, x, v) = block(10, seed, 0.8, 0.5, 1.0, periodic);
            let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
            let (q, c) = (vec![0.0; x.len()], vec![[0.0; 2]; x.len()]);
            let w: Vec<[f64; 3]> = v.iter().map(|v| v.map(|c| -0.5 * c)).collect();
            let on = |threads: usize| {
                let pool = (threads > 1).then(|| {
                    std::sync::Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap())
                });
                let g = group(model.terms[0].kind, &[(0, &model.terms[0])], &model, &pool);
                [&v, &w].map(|v| {
                    let s = Frame { x: &x, v, m: &m, q: &q, c: &c };
                    let mut f = vec![[0.0; 3]; x.len()];
                    let e = g.accumulate(&s, &mut f, true).unwrap();
                    let virial = g.virial(&s).unwrap().unwrap();
                    (f.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>(), e.to_bits(), virial.to_bits())
                })
            };
            let one = on(1);
            assert!(one[0].0 != one[1].0, "the velocities change the viscous forces");
            for threads in [4, 7] {
                assert!(on(threads) == one, "{threads} threads, periodic {periodic}");
            }
        }
    }

    /// A direction of the inputs: positions, velocities, masses, the six parameters.
    struct Along {
        x: Vec<[f64; 3]>,
        v: Vec<[f64; 3]>,
        m: Vec<f64>,
        p: Vec<f64>,
    }

    /// The fast forces and energy with every input moved by `h` along `d`.
    fn moved(model: &Model, x: &[[f64; 3]], v: &[[f64; 3]], d: &Along, h: f64) -> (Vec<[f64; 3]>, f64) {
        let mut model = model.clone();
        for (p, dp) in model.terms[0].params.iter_mut().zip(&d.p) {
            *p += h * dp;
        }
        for (b, dm) in model.bodies.iter_mut().zip(&d.m) {
            b.mass += h * dm;
        }
        let shift = |a: &[[f64; 3]], b: &[[f64; 3]]| -> Vec<[f64; 3]> {
            a.iter().zip(b).map(|(a, b)| std::array::from_fn(|c| a[c] + h * b[c])).collect()
        };
        fast(&model, &shift(x, &d.x), &shift(v, &d.v))
    }

    fn snapshot<'a>(x: &'a [[f64; 3]], v: &'a [[f64; 3]]) -> Snapshot<'a> {
        Snapshot { step: 0, t: 0.0, x, v, chain: &[], spin: &[] }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        /// The fast pressure forces are −∂E/∂x of the definition's energy Σ m u(ρ) (central
        /// differences), the fast energy is that energy, and the forces sum to zero.
        #[test]
        fn pressure_forces_are_minus_the_gradient_of_the_definition(seed in any::<u64>(), squeeze in 0.3f64..1.2, periodic in any::<bool>()) {
            let (model, x, v) = fluid(seed, squeeze, 0.0, 0.0, periodic);
            let energy = |x: &[[f64; 3]]| Lifted::new(&model, &snapshot(x, &v), &0.0f64).potential(&model);
            let (f, e) = fast(&model, &x, &v);
            let e0 = energy(&x);
            // u(ρ) is two terms of size (B/ρ₀)(ρ/ρ₀ − 1) that cancel to second order near ρ₀: a
            // fluid barely pressed has an energy far below their round-off, so the bound has a
            // floor at round-off of the bodies' B/ρ₀ = c₀²/γ (c₀ = 10, γ = 7 in `fluid`)
            let mass: f64 = model.bodies.iter().map(|b| b.mass).sum();
            prop_assert!((e - e0).abs() <= 1e-12 * e0.abs() + 1e-14 * mass * 100.0 / 7.0, "{e} vs {e0}");
            let scale = f.iter().flatten().fold(0.0f64, |a, c| a.max(c.abs()));
            let eps = 1e-6;
            for b in (0..x.len()).step_by(7) {
                for c in 0..3 {
                    let (mut up, mut down) = (x.clone(), x.clone());
                    up[b][c] += eps;
                    down[b][c] -= eps;
                    let fd = -(energy(&up) - energy(&down)) / (2.0 * eps);
                    prop_assert!((f[b][c] - fd).abs() <= 1e-6 * scale + 1e-12, "body {b} axis {c}: {} vs {fd}", f[b][c]);
                }
            }
            for c in 0..3 {
                let total: f64 = f.iter().map(|f| f[c]).sum();
                prop_assert!(total.abs() <= 1e-12 * scale * x.len() as f64);
            }
        }

        /// The viscous forces remove energy at the rate the definition's dissipated power gives:
        /// −Σ v·F_viscous = Σ over pairs of v·∂F/∂v (the checker's Q integrates that rate).
        #[test]
        fn viscous_forces_dissipate_the_definitions_power(seed in any::<u64>(), alpha in 0.0f64..1.0, beta in 0.0f64..2.0) {
            let (inviscid, x, v) = fluid(seed, 0.8, 0.0, 0.0, false);
            let (model, _, _) = fluid(seed, 0.8, alpha, beta, false);
            let (f_all, _) = fast(&model, &x, &v);
            let (f_pressure, _) = fast(&inviscid, &x, &v);
            let rate: f64 = (0..x.len()).map(|b| (0..3).map(|c| v[b][c] * (f_all[b][c] - f_pressure[b][c])).sum::<f64>()).sum();
            let power = Lifted::new(&model, &snapshot(&x, &v), &0.0f64).dissipated_power(&model);
            prop_assert!(power >= 0.0);
            prop_assert!((rate + power).abs() <= 1e-10 * power.abs().max(1e-300), "{rate} vs −{power}");
        }

        /// The derivatives from the definition (`density_derivative`) against the fast force.
        #[test]
        fn derivatives_are_the_fast_forces_differences_and_their_transposes(seed in any::<u64>(), squeeze in 0.5f64..1.0, alpha in 0.0f64..1.0, beta in 0.0f64..2.0, periodic in any::<bool>()) {
            derivatives_hold(seed, squeeze, alpha, beta, periodic)?;
        }
    }

    /// The tangent along a random direction of positions, velocities, masses and all six
    /// parameters is the central difference of the fast force, the pullback is its transpose
    /// (g·Ju = Jᵀg·u), and the potential's pullback is the central difference of the energy.
    /// The fast force has switches — a pair's viscosity acts only while it approaches, the
    /// pressure only above ρ₀ — where it has no derivative: a case with one within the
    /// difference's step (the differences over h and h/4 disagree) is set aside, not judged.
    fn derivatives_hold(seed: u64, squeeze: f64, alpha: f64, beta: f64, periodic: bool) -> Result<(), TestCaseError> {
        use crate::forces::derivative::{Adjoint, Direction, Wanted};
        let (model, x, v) = fluid(seed, squeeze, alpha, beta, periodic);
        let n = x.len();
        let mut rng = Rng::new(seed ^ 0x5eed);
        let mut vecs = |scale: f64| -> Vec<[f64; 3]> {
            (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-scale, scale))).collect()
        };
        let (dx, dv, g) = (vecs(0.05), vecs(1.0), vecs(1.0));
        let mut rng = Rng::new(seed ^ 0xd1);
        let dm: Vec<f64> = (0..n).map(|_| rng.uniform(-0.004, 0.004)).collect();
        let dp: Vec<f64> = [0.03, 0.2, 2.0, 1.0, 0.5, 0.5].iter().map(|s| rng.uniform(-s, *s)).collect();
        let along = Along { x: dx, v: dv, m: dm, p: dp };
        let m: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
        let (q, c) = (vec![0.0; n], vec![[0.0; 2]; n]);
        let frame = Frame { x: &x, v: &v, m: &m, q: &q, c: &c };
        let force = group(model.terms[0].kind, &[(0, &model.terms[0])], &model, &None);
        let params = vec![along.p.clone()];
        let dir = Direction { x: &along.x, v: &along.v, m: &along.m, q: &q, params: &params };
        let mut df = vec![[0.0; 3]; n];
        force.tangent(&frame, &dir, &mut df).unwrap();
        let h = 1e-6;
        let ((plus, e_plus), (minus, e_minus)) = (moved(&model, &x, &v, &along, h), moved(&model, &x, &v, &along, -h));
        let ((plus4, _), (minus4, _)) =
            (moved(&model, &x, &v, &along, h / 4.0), moved(&model, &x, &v, &along, -h / 4.0));
        let scale = df.iter().flatten().fold(1e-300f64, |a, c| a.max(c.abs()));
        for b in 0..n {
            for c in 0..3 {
                let fd = (plus[b][c] - minus[b][c]) / (2.0 * h);
                let fd4 = (plus4[b][c] - minus4[b][c]) / (h / 2.0);
                prop_assume!((fd - fd4).abs() <= 1e-6 * scale, "a switch within the difference step");
                prop_assert!(
                    (fd - df[b][c]).abs() <= 1e-5 * scale,
                    "body {b} axis {c}: tangent {} vs difference {fd}",
                    df[b][c]
                );
            }
        }
        let dot3 = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
            a.iter().zip(b).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum()
        };
        let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(a, b)| a * b).sum() };
        let wanted = Wanted { params: vec![(0..6).collect()], masses: true, charges: false };
        let mut out = Adjoint::zero(n, &model.terms);
        force.pullback(&frame, &g, &wanted, &mut out).unwrap();
        let forward = dot3(&g, &df);
        let reverse =
            dot3(&out.x, &along.x) + dot3(&out.v, &along.v) + dot(&out.m, &along.m) + dot(&out.params[0], &along.p);
        prop_assert!((forward - reverse).abs() <= 1e-10 * (forward.abs() + scale), "g·Ju {forward} vs Jᵀg·u {reverse}");
        let mut out = Adjoint::zero(n, &model.terms);
        force.potential_pullback(&frame, &wanted, &mut out).unwrap();
        let slope = dot3(&out.x, &along.x) + dot(&out.m, &along.m) + dot(&out.params[0], &along.p);
        let fd = (e_plus - e_minus) / (2.0 * h);
        prop_assert!((slope - fd).abs() <= 1e-6 * (fd.abs() + e_plus.abs()), "dU {slope} vs difference {fd}");
        Ok(())
    }

    /// The case CI's run drew on 2026-11-28 (tangent 0.6533115 against a difference of
    /// 0.6532184 at body 32, a switch within the step): set aside or held, never failed.
    #[test]
    fn the_case_ci_drew_is_not_failed() {
        let outcome =
            derivatives_hold(15674834107194876332, 0.73405433473918, 0.46391827199462843, 1.9973510973611344, false);
        assert!(!matches!(outcome, Err(TestCaseError::Fail(_))), "{outcome:?}");
    }
}
