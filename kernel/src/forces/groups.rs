//! The loops terms run in besides the pairs (`pairs`): over listed bodies, over each body.

use super::derivative::{bond_positions, Adjoint, Direction, Instance, Wanted};
use super::{length, shown, stride_alone, sub, Bonded, Field, Force, Frame, Parts, Singularity};
use crate::step::Stride;
use crate::sum::Sum;
use lagra_checker::model::{Images, Model, TermInstance};
use lagra_checker::terms::Kind;
use std::marker::PhantomData;

/// A term's result must be finite: where its formula overflows binary64 (bodies closer than its
/// singularity allows) that is a clear error, never a NaN handed to the solver. The energy is
/// checked where it is wanted (`energy`); a step no one sees hands the solver its forces only.
pub(super) trait Finite: Sized {
    fn finite(self, energy: bool) -> Result<Self, &'static str>;
}

pub(super) const OVERFLOW: &str = "its force or energy overflows binary64 (beyond ±1.8e308)";
pub(super) const FAR: &str =
    "so far apart that their separation overflows binary64 (beyond 1.8e308): no force can be computed";

/// The coordinates of `bodies`, for a message about them.
#[cold]
pub(super) fn at(x: &[[f64; 3]], bodies: &[usize]) -> Option<String> {
    let one = |&i: &usize| format!("x{i} = [{}, {}, {}]", shown(x[i][0]), shown(x[i][1]), shown(x[i][2]));
    Some(bodies.iter().map(one).collect::<Vec<_>>().join(", "))
}

/// Whether a displacement between two bodies overflowed (bodies near ±1e308 on opposite sides).
pub(super) fn overflowed(d: &[f64; 3]) -> bool {
    !d.iter().all(|c| c.is_finite())
}

/// Whether a force's coordinates, and its energy if it counts, are finite.
pub(super) fn all_finite(force: &[f64], e: f64, energy: bool) -> Result<(), &'static str> {
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
pub(super) struct Rows {
    params: Vec<f64>,
    w: usize,
    n: usize,
}

impl Rows {
    pub(super) fn new(kind: Kind, t: &[(usize, &TermInstance)]) -> Rows {
        Rows { params: t.iter().flat_map(|t| t.1.params.iter().copied()).collect(), w: kind.spec().width(), n: t.len() }
    }
    fn iter(&self) -> impl Iterator<Item = &[f64]> {
        (0..self.n).map(|k| self.row(k))
    }
    pub(super) fn row(&self, k: usize) -> &[f64] {
        &self.params[k * self.w..(k + 1) * self.w]
    }
}

pub struct Bonds<T, const N: usize> {
    name: &'static str,
    kind: Kind,
    /// Each instance's place in the model.
    terms: Vec<usize>,
    sites: Vec<[usize; N]>,
    rows: Rows,
    /// In a periodic cell, its image rule.
    images: Option<Images>,
    velocity: bool,
    term: PhantomData<T>,
}

impl<T: Bonded<N> + Send + Sync + 'static, const N: usize> Bonds<T, N> {
    pub fn boxed(kind: Kind, t: &[(usize, &TermInstance)], m: &Model) -> Box<dyn Force> {
        let rows = Rows::new(kind, t);
        let velocity = (0..t.len()).any(|k| T::velocity_dependent(rows.row(k)));
        let sites = t.iter().map(|t| std::array::from_fn(|i| t.1.sites[i])).collect();
        let images = m.cell.map(|c| Images::of(&Some(c)));
        let terms = t.iter().map(|t| t.0).collect();
        Box::new(Bonds::<T, N> { name: kind.name(), kind, terms, sites, rows, images, velocity, term: PhantomData })
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
            let (_, fs, e) = self.one(k, s, energy)?;
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
    fn virial(&self, s: &Frame) -> Option<Result<f64, Singularity>> {
        let each = |k| {
            let (x, fs, _) = self.one(k, s, false)?;
            Ok((0..N).map(|i| (0..3).map(|c| (x[i][c] - x[0][c]) * fs[i][c]).sum::<f64>()).sum::<f64>())
        };
        Some((0..self.sites.len()).map(each).collect::<Result<Sum, _>>().map(|w| w.value()))
    }
    fn owned_sums(&self, s: &Frame, owned: usize) -> Option<Result<[f64; 2], Singularity>> {
        let (mut e, mut w) = (Sum::default(), Sum::default());
        for (k, b) in self.sites.iter().enumerate() {
            let share = b.iter().filter(|&&i| i < owned).count() as f64 / N as f64;
            let (x, fs, energy) = match self.one(k, s, true) {
                Ok(one) => one,
                Err(e) => return Some(Err(e)),
            };
            e.add(share * energy);
            w.add(share * (0..N).map(|i| (0..3).map(|c| (x[i][c] - x[0][c]) * fs[i][c]).sum::<f64>()).sum::<f64>());
        }
        Some(Ok([e.value(), w.value()]))
    }
    fn plan(&self) -> String {
        format!("{} listed instance(s), in order", self.sites.len())
    }
    fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity> {
        (0..self.sites.len()).for_each(|k| self.instance(k, s).tangent(s, dir, df));
        Ok(())
    }
    fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        for k in 0..self.sites.len() {
            self.instance(k, s).pullback(s, g, wanted.of(self.terms[k]), out);
        }
        Ok(())
    }
    fn potential_pullback(&self, s: &Frame, wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        for k in 0..self.sites.len() {
            self.instance(k, s).potential_pullback(s, wanted.of(self.terms[k]), out);
        }
        Ok(())
    }
}

impl<T: Bonded<N>, const N: usize> Bonds<T, N> {
    /// Instance `k`: its bodies' positions (relative to the first, by minimum image in a
    /// periodic cell), forces and energy.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn one(&self, k: usize, s: &Frame, energy: bool) -> Result<([[f64; 3]; N], [[f64; 3]; N], f64), Singularity> {
        let b = &self.sites[k];
        let x = self.positions(k, s);
        // velocities only for a group that reads them (`Bonded::velocity_dependent`)
        let v: [[f64; 3]; N] = if self.velocity { std::array::from_fn(|i| s.v[b[i]]) } else { [[0.0; 3]; N] };
        // the error gathers the positions again: a closure that held them kept the loop's
        // registers from them (the oscillator's step 31 → 38 ns)
        let (fs, e) = T::eval(self.rows.row(k), &x, &v)
            .and_then(|r| r.finite(energy))
            .map_err(|what| self.singular(k, s, what))?;
        Ok((x, fs, e))
    }

    /// Instance `k`'s bodies' positions, relative to the first by minimum image in a periodic
    /// cell.
    #[inline(always)]
    fn positions(&self, k: usize, s: &Frame) -> [[f64; 3]; N] {
        let b = &self.sites[k];
        match &self.images {
            None => std::array::from_fn(|i| s.x[b[i]]),
            Some(images) => {
                let x0 = s.x[b[0]];
                std::array::from_fn(|i| {
                    let d = images.image(sub(&s.x[b[i]], &x0));
                    [x0[0] + d[0], x0[1] + d[1], x0[2] + d[2]]
                })
            }
        }
    }

    #[cold]
    #[inline(never)]
    fn singular(&self, k: usize, s: &Frame, what: &'static str) -> Singularity {
        bond_singularity(self.name, &self.sites[k], &self.positions(k, s), s.x, what)
    }
}

/// A bond's error with the numbers: how far apart its bodies are, or where they are when even
/// that overflows. Cold and out of line, so that the loops it is written in stay as tight as
/// they were without it.
#[cold]
#[inline(never)]
fn bond_singularity(
    term: &'static str,
    b: &[usize],
    x: &[[f64; 3]],
    all: &[[f64; 3]],
    what: &'static str,
) -> Singularity {
    let widest = x.iter().map(|xi| length(&sub(xi, &x[0]))).fold(0.0, f64::max);
    let (what, seen) = match x.iter().any(|xi| overflowed(&sub(xi, &x[0]))) {
        true => (FAR, at(all, b)),
        false if widest == 0.0 => (what, None),
        false if b.len() == 2 => (what, Some(format!("the bodies {} apart", shown(widest)))),
        false => (what, Some(format!("the bodies up to {} from body {}", shown(widest), b[0]))),
    };
    Singularity { term, bodies: b.to_vec(), what, seen }
}

impl<T, const N: usize> Bonds<T, N> {
    /// Instance k as its definition sees it (the bodies at their nearest images).
    fn instance<'a>(&'a self, k: usize, s: &Frame) -> Instance<'a> {
        let x = bond_positions(s.x, &self.sites[k], &self.images);
        Instance { kind: self.kind, p: self.rows.row(k), bodies: &self.sites[k], x, term: self.terms[k] }
    }
}

pub struct Fields<T> {
    name: &'static str,
    kind: Kind,
    /// Each instance's place in the model.
    terms: Vec<usize>,
    rows: Rows,
    /// Per instance, the bodies it acts on (empty: every body).
    on: Vec<Vec<usize>>,
    velocity: bool,
    term: PhantomData<T>,
}

impl<T: Field + Send + Sync + 'static> Fields<T> {
    pub fn boxed(kind: Kind, t: &[(usize, &TermInstance)]) -> Box<dyn Force> {
        let rows = Rows::new(kind, t);
        let velocity = rows.iter().any(T::velocity_dependent);
        let on = t.iter().map(|t| t.1.sites.clone()).collect();
        let terms = t.iter().map(|t| t.0).collect();
        Box::new(Fields::<T> { name: kind.name(), kind, terms, rows, on, velocity, term: PhantomData })
    }
}

impl<T> Fields<T> {
    /// Each instance on each body it acts on, as its definition sees it.
    fn each_instance(&self, s: &Frame, mut f: impl FnMut(Instance)) {
        for k in 0..self.on.len() {
            for i in self.bodies_of(k, s.x.len()) {
                let bodies = std::slice::from_ref(&i);
                f(Instance { kind: self.kind, p: self.rows.row(k), bodies, x: vec![s.x[i]], term: self.terms[k] });
            }
        }
    }

    /// The bodies instance k acts on.
    fn bodies_of(&self, k: usize, n: usize) -> Vec<usize> {
        if self.on[k].is_empty() {
            (0..n).collect()
        } else {
            self.on[k].clone()
        }
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
                    .map_err(|what| Singularity::located(self.name, &[i], what, s.x))?;
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
    fn virial(&self, _s: &Frame) -> Option<Result<f64, Singularity>> {
        None
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
    fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity> {
        self.each_instance(s, |one| one.tangent(s, dir, df));
        Ok(())
    }
    fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        self.each_instance(s, |one| one.pullback(s, g, wanted.of(one.term), out));
        Ok(())
    }
    fn potential_pullback(&self, s: &Frame, wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        self.each_instance(s, |one| one.potential_pullback(s, wanted.of(one.term), out));
        Ok(())
    }
}
