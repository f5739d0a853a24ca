//! The three loops every term runs in: over listed bodies, over all pairs, over each body.

use super::{stride_alone, sub, Bonded, Field, Force, Frame, Paired, Parts, Pool, Singularity};
use crate::neighbours::{Neighbours, Pair};
use crate::step::Stride;
use crate::sum::Sum;
use crate::traverse;
use lagra_checker::model::{Cell, Images, Model, TermInstance};
use lagra_checker::terms::Kind;
use rayon::prelude::*;
use std::marker::PhantomData;
use std::ops::Range;
use std::sync::Mutex;

/// A term's result must be finite: where its formula overflows binary64 (bodies closer than its
/// singularity allows) that is a clear error, never a NaN handed to the solver. The energy is
/// checked where it is wanted (`energy`); a step no one sees hands the solver its forces only.
trait Finite: Sized {
    fn finite(self, energy: bool) -> Result<Self, &'static str>;
}

const OVERFLOW: &str = "so close to a singular configuration that the force overflows binary64";
const FAR: &str = "so far apart that their separation overflows binary64 (beyond 1.8e308): no force can be computed";

/// Whether a displacement between two bodies overflowed (bodies near ±1e308 on opposite sides).
fn overflowed(d: &[f64; 3]) -> bool {
    !d.iter().all(|c| c.is_finite())
}

/// Whether a force's coordinates, and its energy if it counts, are finite.
fn all_finite(force: &[f64], e: f64, energy: bool) -> Result<(), &'static str> {
    if (!energy || e.is_finite()) && force.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(OVERFLOW)
    }
}

impl<const N: usize> Finite for ([[f64; 3]; N], f64) {
    fn finite(self, energy: bool) -> Result<Self, &'static str> {
        all_finite(self.0.as_flattened(), self.1, energy).map(|()| self)
    }
}

impl Finite for ([f64; 3], f64) {
    fn finite(self, energy: bool) -> Result<Self, &'static str> {
        all_finite(&self.0, self.1, energy).map(|()| self)
    }
}

/// Each instance's parameters, flattened: row k is `params[k*w .. (k+1)*w]`.
struct Rows {
    params: Vec<f64>,
    w: usize,
    n: usize,
}

impl Rows {
    fn new(kind: Kind, t: &[&TermInstance]) -> Rows {
        Rows { params: t.iter().flat_map(|t| t.params.iter().copied()).collect(), w: kind.spec().width(), n: t.len() }
    }
    fn iter(&self) -> impl Iterator<Item = &[f64]> {
        (0..self.n).map(|k| self.row(k))
    }
    fn row(&self, k: usize) -> &[f64] {
        &self.params[k * self.w..(k + 1) * self.w]
    }
}

pub struct Bonds<T, const N: usize> {
    name: &'static str,
    sites: Vec<[usize; N]>,
    rows: Rows,
    /// In a periodic cell, its image rule.
    images: Option<Images>,
    velocity: bool,
    term: PhantomData<T>,
}

impl<T: Bonded<N> + Send + Sync + 'static, const N: usize> Bonds<T, N> {
    pub fn boxed(kind: Kind, t: &[&TermInstance], m: &Model) -> Box<dyn Force> {
        let rows = Rows::new(kind, t);
        let velocity = (0..t.len()).any(|k| T::velocity_dependent(rows.row(k)));
        let sites = t.iter().map(|t| std::array::from_fn(|i| t.sites[i])).collect();
        let images = m.cell.map(|c| Images::of(&Some(c)));
        Box::new(Bonds::<T, N> { name: kind.name(), sites, rows, images, velocity, term: PhantomData })
    }
}

impl<T: Bonded<N> + Send + Sync, const N: usize> Force for Bonds<T, N> {
    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity> {
        stride_alone(self, stride, parts)
    }
    #[inline(always)]
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity> {
        let mut sum = Sum::default();
        for (k, b) in self.sites.iter().enumerate() {
            // positions relative to the first body, by minimum image in a periodic cell
            let x: [[f64; 3]; N] = match &self.images {
                None => std::array::from_fn(|i| s.x[b[i]]),
                Some(images) => {
                    let x0 = s.x[b[0]];
                    std::array::from_fn(|i| {
                        let d = images.image(sub(&s.x[b[i]], &x0));
                        [x0[0] + d[0], x0[1] + d[1], x0[2] + d[2]]
                    })
                }
            };
            // velocities only for a group that reads them (`Bonded::velocity_dependent`)
            let v: [[f64; 3]; N] = if self.velocity { std::array::from_fn(|i| s.v[b[i]]) } else { [[0.0; 3]; N] };
            let (fs, e) = T::eval(self.rows.row(k), &x, &v).and_then(|r| r.finite(energy)).map_err(|what| {
                let far = x.iter().any(|xi| overflowed(&sub(xi, &x[0])));
                Singularity { term: self.name, bodies: b.to_vec(), what: if far { FAR } else { what } }
            })?;
            for (i, fi) in b.iter().zip(fs) {
                for c in 0..3 {
                    f[*i][c] += fi[c];
                }
            }
            if energy {
                sum.add(e);
            }
        }
        Ok(sum.value())
    }
    fn velocity_dependent(&self) -> bool {
        self.velocity
    }
    fn plan(&self) -> String {
        format!("{} listed instance(s), in order", self.sites.len())
    }
}

pub struct Pairs<T: Paired> {
    name: &'static str,
    /// Each instance's constants (`Paired::row`).
    rows: Vec<T::Row>,
    cell: Option<Cell>,
    /// The farthest any row reaches, if every row's reach is finite (then a cell list applies).
    reach: Option<f64>,
    /// For a finite reach on enough bodies in a big enough box: the Verlet list, kept between
    /// steps (a lock, since forces are evaluated through a shared reference).
    list: Option<Mutex<Neighbours>>,
    pool: Pool,
    term: PhantomData<T>,
}

/// Below this many bodies a pair term loops over every pair: as fast, and nothing to keep.
const LIST_FROM: usize = 64;

/// From this many bodies the listed pairs are split into `CHUNKS` parts by body, each summing
/// its forces into its own buffer, the buffers then added in order: the same bits for any number
/// of threads, since the split depends on the list alone.
const SPLIT_FROM: usize = 4096;
const CHUNKS: usize = 4;

impl<T: Paired + Send + Sync + 'static> Pairs<T> {
    pub fn boxed(kind: Kind, t: &[&TermInstance], m: &Model, pool: &Pool) -> Box<dyn Force> {
        let reach = t.iter().map(|t| kind.reach(&t.params)).try_fold(0.0f64, |r, t| t.map(|t| r.max(t)));
        let list = reach
            .filter(|_| (LIST_FROM..Pair::BODIES).contains(&m.bodies.len()))
            .and_then(|r| Neighbours::new(&m.cell, r))
            .map(Mutex::new);
        let rows = t.iter().map(|t| T::row(&t.params)).collect();
        Box::new(Pairs::<T> {
            name: kind.name(),
            rows,
            cell: m.cell,
            reach,
            list,
            pool: pool.clone(),
            term: PhantomData,
        })
    }

    /// The pairs of the positions `blocks` of the list: forces into `f`, by position, the energy
    /// returned. Rows are the outer loop so that each one's constants stay in registers through
    /// the pair loop.
    fn listed<const ENERGY: bool>(
        &self,
        l: &Neighbours,
        s: &Frame,
        blocks: Range<usize>,
        f: &mut [[f64; 3]],
    ) -> Result<Sum, Singularity> {
        let x = &l.wrapped;
        let body = |b: usize| l.bodies[b] as usize;
        let mut energy = Sum::default();
        for p in &self.rows {
            for i in blocks.clone() {
                let xi = x[i];
                let mut fi = [0.0; 3];
                // plain within a body's few dozen pairs, compensated across bodies
                let mut ei = 0.0;
                for pair in &l.pairs[l.start[i]..l.start[i + 1]] {
                    let j = pair.j();
                    let sh = &l.shifts[pair.image()];
                    let d = [x[j][0] - xi[0] + sh[0], x[j][1] - xi[1] + sh[1], x[j][2] - xi[2] + sh[2]];
                    let (mq, colour) = if T::BODIES || T::COLOUR {
                        (bodies::<T>(s, body(i), body(j)), colour::<T>(s, body(i), body(j)))
                    } else {
                        ([0.0; 4], 0.0)
                    };
                    let (a, e) = T::eval(p, d, mq, colour).map_err(|what| Singularity {
                        term: self.name,
                        bodies: vec![body(i), body(j)],
                        what,
                    })?;
                    for c in 0..3 {
                        fi[c] += a[c];
                        f[j][c] -= a[c];
                    }
                    if ENERGY {
                        ei += e;
                    }
                }
                for c in 0..3 {
                    f[i][c] += fi[c];
                }
                energy.add(ei);
            }
        }
        Ok(energy)
    }

    /// Through the Verlet list, split by positions into chunks of about equal pair counts, each
    /// summing into its own buffer (by position); the buffers are added in order and then given
    /// back to the bodies.
    fn through_list(&self, l: &Neighbours, s: &Frame, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity> {
        let n = s.x.len();
        let chunks = if n >= SPLIT_FROM { CHUNKS } else { 1 };
        let total = l.count();
        let bounds: Vec<usize> = (0..=chunks)
            .map(|c| if c == chunks { n } else { l.start.partition_point(|&k| k < total * c / chunks) })
            .collect();
        let mut buffers = vec![vec![[0.0; 3]; n]; chunks];
        let work = |(c, t): (usize, &mut Vec<[f64; 3]>)| match energy {
            true => self.listed::<true>(l, s, bounds[c]..bounds[c + 1], t),
            false => self.listed::<false>(l, s, bounds[c]..bounds[c + 1], t),
        };
        let sums: Vec<Result<Sum, Singularity>> = match &self.pool {
            Some(pool) if chunks > 1 => pool.install(|| buffers.par_iter_mut().enumerate().map(work).collect()),
            _ => buffers.iter_mut().enumerate().map(work).collect(),
        };
        let (first, rest) = buffers.split_first_mut().expect("one chunk at least");
        for b in rest {
            for (fi, bi) in first.iter_mut().zip(b.iter()) {
                for c in 0..3 {
                    fi[c] += bi[c];
                }
            }
        }
        for (&i, fb) in l.bodies.iter().zip(first.iter()) {
            for c in 0..3 {
                f[i as usize][c] += fb[c];
            }
        }
        let mut energy = Sum::default();
        for part in sums {
            energy.merge(part?);
        }
        Ok(energy.value())
    }

    /// Every pair a traversal visits (all pairs, or a cell list rebuilt now), each result
    /// checked finite as it comes.
    fn traversed(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        traverse::pairs(s.x, &self.cell, self.reach, |i, j, d| {
            if overflowed(&d) {
                return Err(Singularity { term: self.name, bodies: vec![i, j], what: FAR });
            }
            let (mq, colour) = (bodies::<T>(s, i, j), colour::<T>(s, i, j));
            for p in &self.rows {
                let (a, e) = T::eval(p, d, mq, colour).and_then(|r| r.finite(true)).map_err(|what| Singularity {
                    term: self.name,
                    bodies: vec![i, j],
                    what,
                })?;
                // applied so that the two are exactly opposite
                for c in 0..3 {
                    f[i][c] += a[c];
                    f[j][c] -= a[c];
                }
                energy.add(e);
            }
            Ok(())
        })?;
        Ok(energy.value())
    }
}

/// [mᵢ, mⱼ, qᵢ, qⱼ] if the term reads them, else zeros (and no loads).
#[inline(always)]
fn bodies<T: Paired>(s: &Frame, i: usize, j: usize) -> [f64; 4] {
    if T::BODIES {
        [s.m[i], s.m[j], s.q[i], s.q[j]]
    } else {
        [0.0; 4]
    }
}

/// cᵢ·cⱼ if the term reads it, else zero.
#[inline(always)]
fn colour<T: Paired>(s: &Frame, i: usize, j: usize) -> f64 {
    if T::COLOUR {
        s.c[i][0] * s.c[j][0] + s.c[i][1] * s.c[j][1]
    } else {
        0.0
    }
}

impl<T: Paired + Send + Sync + 'static> Force for Pairs<T> {
    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity> {
        stride_alone(self, stride, parts)
    }
    /// Through a Verlet list, the energy only if asked (it is a fifth of a pair's arithmetic).
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity> {
        let Some(list) = &self.list else { return self.traversed(s, f) };
        let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        l.update(s.x, &self.cell, self.pool.as_deref());
        let energy = self.through_list(&l, s, f, energy)?;
        if energy.is_finite() && f.iter().flatten().all(|c| c.is_finite()) {
            return Ok(energy);
        }
        // Rare: find the pair that overflowed, by the checked traversal.
        let mut scratch = vec![[0.0; 3]; f.len()];
        self.traversed(s, &mut scratch)?;
        Err(Singularity { term: self.name, bodies: vec![], what: OVERFLOW })
    }
    fn velocity_dependent(&self) -> bool {
        false
    }
    fn plan(&self) -> String {
        let reach = self.reach.map_or("infinite reach".to_string(), |r| format!("reach {r}"));
        match &self.list {
            None if self.reach.is_none() => format!("every pair each step ({reach})"),
            None => format!("every pair, through a cell list rebuilt each step when there are at least 64 bodies ({reach}; no Verlet list: too few bodies, or a box shorter than twice reach + skin)"),
            Some(l) => {
                let l = l.lock().unwrap_or_else(|p| p.into_inner());
                let threads = self.pool.as_ref().map_or(1, |p| p.current_num_threads());
                format!(
                    "Verlet list, half (Newton's third law), {reach} + skin {:.3}, built from a cell list, {} builds, {} pairs; {} on {threads} thread(s)",
                    l.skin,
                    l.builds,
                    l.count(),
                    if l.start.len() > SPLIT_FROM { format!("{CHUNKS} fixed chunks") } else { "one chunk".into() }
                )
            }
        }
    }
}

pub struct Fields<T> {
    name: &'static str,
    rows: Rows,
    /// Per instance, the bodies it acts on (empty: every body).
    on: Vec<Vec<usize>>,
    velocity: bool,
    term: PhantomData<T>,
}

impl<T: Field + Send + Sync + 'static> Fields<T> {
    pub fn boxed(kind: Kind, t: &[&TermInstance]) -> Box<dyn Force> {
        let rows = Rows::new(kind, t);
        let velocity = rows.iter().any(T::velocity_dependent);
        let on = t.iter().map(|t| t.sites.clone()).collect();
        Box::new(Fields::<T> { name: kind.name(), rows, on, velocity, term: PhantomData })
    }
}

impl<T: Field + Send + Sync> Force for Fields<T> {
    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity> {
        stride_alone(self, stride, parts)
    }
    /// (One term per body: the energy is always summed.)
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], _energy: bool) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        for (p, on) in self.rows.iter().zip(&self.on) {
            let mut one = |i: usize| -> Result<(), Singularity> {
                let (a, e) = T::eval(p, &s.x[i], &s.v[i], s.m[i], s.q[i])
                    .and_then(|r| r.finite(true))
                    .map_err(|what| Singularity { term: self.name, bodies: vec![i], what })?;
                for c in 0..3 {
                    f[i][c] += a[c];
                }
                energy.add(e);
                Ok(())
            };
            if on.is_empty() {
                (0..s.x.len()).try_for_each(&mut one)?;
            } else {
                on.iter().try_for_each(|&i| one(i))?;
            }
        }
        Ok(energy.value())
    }
    fn velocity_dependent(&self) -> bool {
        self.velocity
    }
    fn gyroscopic(&self) -> bool {
        T::GYROSCOPIC
    }
    fn gyration(&self, s: &Frame, w: &mut [[f64; 3]]) {
        if !T::GYROSCOPIC {
            return;
        }
        for (p, on) in self.rows.iter().zip(&self.on) {
            let mut one = |i: usize| {
                let o = T::gyration(p, &s.x[i], s.m[i], s.q[i]);
                (0..3).for_each(|c| w[i][c] += o[c]);
            };
            if on.is_empty() {
                (0..s.x.len()).for_each(&mut one);
            } else {
                on.iter().for_each(|&i| one(i));
            }
        }
    }
    fn plan(&self) -> String {
        format!("{} instance(s), each on its bodies in order", self.on.len())
    }
}
