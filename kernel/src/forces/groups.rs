//! The three loops every term runs in: over listed bodies, over all pairs, over each body.

use super::{sub, Bonded, Field, Force, Frame, Paired, Singularity};
use crate::sum::Sum;
use crate::traverse;
use lagra_checker::model::{Cell, Model, TermInstance};
use lagra_checker::terms::Kind;
use std::marker::PhantomData;

/// A term's result must be finite: where its formula overflows binary64 (bodies closer than its
/// singularity allows) that is a clear error, never a NaN handed to the solver.
trait Finite: Sized {
    fn finite(self) -> Result<Self, &'static str>;
}

const OVERFLOW: &str = "so close to a singular configuration that the force overflows binary64";

impl<const N: usize> Finite for ([[f64; 3]; N], f64) {
    fn finite(self) -> Result<Self, &'static str> {
        if self.1.is_finite() && self.0.iter().flatten().all(|c| c.is_finite()) {
            Ok(self)
        } else {
            Err(OVERFLOW)
        }
    }
}

impl Finite for ([f64; 3], f64) {
    fn finite(self) -> Result<Self, &'static str> {
        if self.1.is_finite() && self.0.iter().all(|c| c.is_finite()) {
            Ok(self)
        } else {
            Err(OVERFLOW)
        }
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
    cell: Option<Cell>,
    velocity: bool,
    term: PhantomData<T>,
}

impl<T: Bonded<N> + Send + Sync + 'static, const N: usize> Bonds<T, N> {
    pub fn boxed(kind: Kind, t: &[&TermInstance], m: &Model) -> Box<dyn Force> {
        let rows = Rows::new(kind, t);
        let velocity = (0..t.len()).any(|k| T::velocity_dependent(rows.row(k)));
        let sites = t.iter().map(|t| std::array::from_fn(|i| t.sites[i])).collect();
        Box::new(Bonds::<T, N> { name: kind.name(), sites, rows, cell: m.cell, velocity, term: PhantomData })
    }
}

impl<T: Bonded<N> + Send + Sync, const N: usize> Force for Bonds<T, N> {
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        for (k, b) in self.sites.iter().enumerate() {
            // positions relative to the first body, by minimum image in a periodic cell
            let x0 = s.x[b[0]];
            let x: [[f64; 3]; N] = std::array::from_fn(|i| {
                let d = Cell::image(&self.cell, sub(&s.x[b[i]], &x0));
                [x0[0] + d[0], x0[1] + d[1], x0[2] + d[2]]
            });
            let v: [[f64; 3]; N] = std::array::from_fn(|i| s.v[b[i]]);
            let (fs, e) = T::eval(self.rows.row(k), &x, &v).and_then(Finite::finite).map_err(|what| Singularity {
                term: self.name,
                bodies: b.to_vec(),
                what,
            })?;
            for (i, fi) in b.iter().zip(fs) {
                for c in 0..3 {
                    f[*i][c] += fi[c];
                }
            }
            energy.add(e);
        }
        Ok(energy.value())
    }
    fn velocity_dependent(&self) -> bool {
        self.velocity
    }
}

pub struct Pairs<T> {
    name: &'static str,
    rows: Rows,
    cell: Option<Cell>,
    /// The farthest any row reaches, if every row's reach is finite (then a cell list applies).
    reach: Option<f64>,
    term: PhantomData<T>,
}

impl<T: Paired + Send + Sync + 'static> Pairs<T> {
    pub fn boxed(kind: Kind, t: &[&TermInstance], m: &Model) -> Box<dyn Force> {
        let reach = t.iter().map(|t| kind.reach(&t.params)).try_fold(0.0f64, |r, t| t.map(|t| r.max(t)));
        Box::new(Pairs::<T> { name: kind.name(), rows: Rows::new(kind, t), cell: m.cell, reach, term: PhantomData })
    }
}

impl<T: Paired + Send + Sync> Force for Pairs<T> {
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        traverse::pairs(s.x, &self.cell, self.reach, |i, j, d| {
            let colour = s.c[i][0] * s.c[j][0] + s.c[i][1] * s.c[j][1];
            for p in self.rows.iter() {
                let (a, e) = T::eval(p, d, [s.m[i], s.m[j], s.q[i], s.q[j]], colour)
                    .and_then(Finite::finite)
                    .map_err(|what| Singularity { term: self.name, bodies: vec![i, j], what })?;
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
    fn velocity_dependent(&self) -> bool {
        false
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
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        for (p, on) in self.rows.iter().zip(&self.on) {
            let mut one = |i: usize| -> Result<(), Singularity> {
                let (a, e) = T::eval(p, &s.x[i], &s.v[i], s.m[i], s.q[i])
                    .and_then(Finite::finite)
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
}
