//! Pair terms: over all pairs of a few bodies, or over a Verlet list of clusters cut into
//! pieces by the system's size (`pieces`), so the sums are the same bits on any number of
//! threads.

use super::clusters;
use super::derivative::{coincident, Adjoint, Direction, PairDerivative, Wanted};
use super::groups::{overflowed, Finite, Rows, FAR, OVERFLOW};
use super::{stride_alone, Force, Frame, Paired, Parts, Pool, Singularity};
use crate::lanes::F64x4;
use crate::neighbours::{Cluster, Neighbours, Pair, EMPTY, LANES};
use crate::spread;
use crate::step::{Stride, BLOCK};
use crate::sum::Sum;
use crate::traverse;
use lagra_checker::model::{Cell, Model, TermInstance};
use lagra_checker::terms::Kind;
use rayon::prelude::*;
use std::marker::PhantomData;
use std::sync::Mutex;
use std::time::{Duration, Instant};

pub struct Pairs<T: Paired> {
    name: &'static str,
    kind: Kind,
    /// Each instance's place in the model, and its parameters as written (the derivatives
    /// evaluate the definition on them).
    terms: Vec<usize>,
    params: Rows,
    /// Each instance's constants (`Paired::row`).
    rows: Vec<T::Row>,
    cell: Option<Cell>,
    /// The farthest any row reaches, if every row's reach is finite (then a cell list applies).
    reach: Option<f64>,
    /// For a finite reach on enough bodies in a big enough box: the Verlet list, kept between
    /// steps (a lock, since forces are evaluated through a shared reference).
    list: Option<Mutex<Neighbours>>,
    /// The pieces' buffers and their sums by cluster, kept between steps (fresh ones would be
    /// fresh pages each step).
    output: Mutex<Output>,
    pool: Pool,
    term: PhantomData<T>,
}

#[derive(Default)]
struct Output {
    buffers: Vec<Vec<Cluster>>,
    summed: Vec<Cluster>,
    /// Wall time in the pieces' work and in their sums by cluster (`--explain`).
    worked: Duration,
    gathered: Duration,
}

/// Below this many bodies a pair term loops over every pair: as fast, and nothing to keep.
const LIST_FROM: usize = 64;

impl<T: Paired + Send + Sync + 'static> Pairs<T> {
    pub fn boxed(kind: Kind, t: &[(usize, &TermInstance)], m: &Model, pool: &Pool) -> Box<dyn Force> {
        let reach = Some(t.iter().map(|t| kind.reach(&t.1.params)).fold(0.0f64, f64::max)).filter(|r| r.is_finite());
        let list = reach
            .filter(|_| (LIST_FROM..Pair::CLUSTERS).contains(&m.bodies.len()))
            .and_then(|r| Neighbours::new(&m.cell, r))
            .map(Mutex::new);
        let rows = t.iter().map(|t| T::row(&t.1.params)).collect();
        Box::new(Pairs::<T> {
            name: kind.name(),
            kind,
            terms: t.iter().map(|t| t.0).collect(),
            params: Rows::new(kind, t),
            rows,
            cell: m.cell,
            reach,
            list,
            output: Mutex::default(),
            pool: pool.clone(),
            term: PhantomData,
        })
    }

    /// The virial −Σ d·F over the listed pairs within the cutoff, in list order (each pair's
    /// eval gives zero beyond it), compensated.
    fn listed_virial(&self, l: &Neighbours, s: &Frame) -> Result<f64, Singularity> {
        let mut w = Sum::default();
        for p in &self.rows {
            l.each_pair(|i, j, d| {
                let (a, _) = T::eval(p, d, bodies::<T>(s, i, j), colour::<T>(s, i, j))
                    .map_err(|what| Singularity::pair(self.name, i, j, what, &d))?;
                w.add(-(d[0] * a[0] + d[1] * a[1] + d[2] * a[2]));
                Ok(())
            })?;
        }
        Ok(w.value())
    }

    /// Through the cluster-pair list (`clusters::kernel`), piece by piece (`on_pieces`). The cut
    /// depends on the list alone: the same bits on any number of threads.
    fn through_list<const SUM: u8>(
        &self,
        l: &Neighbours,
        s: &Frame,
        f: &mut [[f64; 3]],
        shares: &[F64x4],
    ) -> Result<f64, Singularity> {
        let pieces = &l.pieces;
        let traits = clusters::traits::<T>(l, s);
        let bodies = (&traits[..], shares);
        // (two bodies at one point make the forces non-finite: `accumulate` then names them)
        let sums = self.on_pieces(l, f, |k, buffer| {
            let mut sum = Sum::default();
            for row in &self.rows {
                sum.merge(clusters::kernel::<T, SUM>(l, row, bodies, pieces.own(k), &pieces.place, buffer));
            }
            sum
        });
        let mut energy = Sum::default();
        for part in sums {
            energy.merge(part);
        }
        Ok(energy.value())
    }

    /// `work(k, buffer)` on each piece k (`pieces`), on the pool's threads if any, with a zeroed
    /// buffer of the piece's own clusters and halo; then each cluster's parts added in piece
    /// order and given back to its bodies in `f`. What each piece returned, in piece order.
    fn on_pieces<S: Send>(
        &self,
        l: &Neighbours,
        f: &mut [[f64; 3]],
        work: impl Fn(usize, &mut Vec<Cluster>) -> S + Sync,
    ) -> Vec<S> {
        let pieces = &l.pieces;
        let zeroed = |(k, buffer): (usize, &mut Vec<Cluster>)| {
            buffer.clear();
            buffer.resize(pieces.size(k), [F64x4::default(); 3]);
            work(k, buffer)
        };
        let add = |a: Cluster, b: Cluster| -> Cluster { std::array::from_fn(|c| a[c] + b[c]) };
        let give_back = |(b, fb): (usize, &mut [f64; 3]), summed: &[Cluster]| {
            let slot = l.slot[b] as usize;
            if slot != EMPTY as usize {
                for c in 0..3 {
                    fb[c] += summed[slot / LANES][c].lane(slot % LANES);
                }
            }
        };
        let mut output = self.output.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let Output { buffers, summed, worked, gathered } = &mut *output;
        buffers.resize_with(pieces.count(), Vec::new);
        summed.resize(l.clusters(), [F64x4::default(); 3]);
        let working = Instant::now();
        let mut gathering = working;
        let done = spread::pass_if(pieces.count() > 1, || match &self.pool {
            Some(pool) if pieces.count() > 1 => pool.install(|| {
                let done = buffers.par_iter_mut().enumerate().map(zeroed).collect();
                gathering = Instant::now();
                summed
                    .par_iter_mut()
                    .enumerate()
                    .with_min_len(256)
                    .for_each(|(c, s)| *s = pieces.gather(c, buffers, add));
                f.par_iter_mut().enumerate().with_min_len(1024).for_each(|bf| give_back(bf, summed));
                done
            }),
            _ => {
                let done = buffers.iter_mut().enumerate().map(zeroed).collect();
                gathering = Instant::now();
                summed.iter_mut().enumerate().for_each(|(c, s)| *s = pieces.gather(c, buffers, add));
                f.iter_mut().enumerate().for_each(|bf| give_back(bf, summed));
                done
            }
        });
        *worked += gathering - working;
        *gathered += gathering.elapsed();
        done
    }

    /// Each instance's derivative, gathering what `wanted` names.
    fn derivatives_for(&self, wanted: &Wanted) -> Vec<PairDerivative<'_>> {
        (0..self.terms.len())
            .map(|k| {
                let t = self.terms[k];
                PairDerivative::new(self.kind, self.params.row(k), t, wanted.of(t))
            })
            .collect()
    }

    fn derivatives(&self, w: (&[usize], bool, bool)) -> Vec<PairDerivative<'_>> {
        (0..self.terms.len()).map(|k| PairDerivative::new(self.kind, self.params.row(k), self.terms[k], w)).collect()
    }

    /// Whether every instance has a hand-derived jet (and the term reads no masses or charges,
    /// whose derivatives jets leave out).
    fn jets_everywhere(&self, each: &[PairDerivative]) -> bool {
        !T::BODIES
            && !T::COLOUR
            && each.iter().enumerate().all(|(k, pd)| T::jet(&self.rows[k], pd.p, 0.25 * pd.reach2.min(1e300)).is_some())
    }

    /// The pullback through the cluster-pair list with the hand-derived jets, four pairs at a
    /// time (`clusters::pullback`), piece by piece like the forces (`on_pieces`): each
    /// instance's parameters' adjoints summed in piece order, the positions' through the
    /// pieces' buffers. The same bits on any number of threads. With g, the forces' pullback
    /// of g; without, the gradient of the energy.
    fn listed_pullback(&self, l: &Neighbours, g: Option<&[[f64; 3]]>, each: &[PairDerivative], out: &mut Adjoint) {
        let (pieces, potential) = (&l.pieces, g.is_none());
        // g by cluster, as the kernel reads positions (zeros in empty slots): on the pool where
        // the bodies are many (each cluster its own, the same values on any count), since at
        // every step of a gradient's backward pass this gather was its serial part
        let g: Vec<Cluster> = match g {
            None => vec![],
            Some(g) => {
                let one = |c: usize| -> Cluster {
                    let at = |a: usize, k: usize| match l.bodies[LANES * c + a] {
                        EMPTY => 0.0,
                        b => g[b as usize][k],
                    };
                    std::array::from_fn(|k| F64x4::new(std::array::from_fn(|a| at(a, k))))
                };
                spread::over(self.pool.as_deref(), g.len(), |on_pool| match on_pool {
                    true => (0..l.clusters()).into_par_iter().with_min_len(BLOCK / LANES).map(one).collect(),
                    false => (0..l.clusters()).map(one).collect(),
                })
            }
        };
        let wanted: Vec<Vec<usize>> =
            each.iter().map(|pd| pd.which().iter().copied().filter(|&w| w < pd.p.len()).collect()).collect();
        let params: Vec<Vec<[Sum; 3]>> = self.on_pieces(l, &mut out.x, |k, buffer| {
            (each.iter().enumerate())
                .map(|(n, pd)| {
                    let at =
                        clusters::Pulled { row: &self.rows[n], p: pd.p, reach2: pd.reach2, wanted: &wanted[n], g: &g };
                    match potential {
                        true => clusters::pullback::<T, true>(l, &at, pieces.own(k), &pieces.place, buffer),
                        false => clusters::pullback::<T, false>(l, &at, pieces.own(k), &pieces.place, buffer),
                    }
                })
                .collect()
        });
        for (n, pd) in each.iter().enumerate() {
            for &w in &wanted[n] {
                let mut total = Sum::default();
                params.iter().for_each(|piece| total.merge(piece[n][w]));
                out.params[pd.term][w] += total.value();
            }
        }
    }

    /// Instance k's hand-derived jet at d, for a term that reads neither masses nor charges
    /// (whose jets say nothing of them) and a pair inside its own reach.
    #[inline]
    fn jet(&self, k: usize, d: &[f64; 3], reach2: f64) -> Option<super::Jet> {
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if T::BODIES || T::COLOUR || r2 >= reach2 {
            return None;
        }
        T::jet(&self.rows[k], self.params.row(k), r2)
    }

    /// Each pair within reach, as the force loop sees it — through the Verlet list when there is
    /// one (brought up to date), else every pair or a cell list — with its displacement.
    fn within_reach(
        &self,
        s: &Frame,
        mut visit: impl FnMut(usize, usize, [f64; 3]) -> Result<(), Singularity>,
    ) -> Result<(), Singularity> {
        let near = |d: &[f64; 3]| {
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            self.reach.is_none_or(|r| r2 <= r * r)
        };
        let Some(list) = &self.list else {
            return traverse::pairs(
                s.x,
                &self.cell,
                self.reach,
                |i, j, d| if near(&d) { visit(i, j, d) } else { Ok(()) },
            );
        };
        let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        l.update(s.x, &self.cell, self.pool.as_deref());
        l.each_pair(|i, j, d| if near(&d) { visit(i, j, d) } else { Ok(()) })
    }

    /// Every pair a traversal visits (all pairs, or a cell list rebuilt now), each result
    /// checked finite as it comes.
    fn traversed(&self, s: &Frame, f: &mut [[f64; 3]]) -> Result<f64, Singularity> {
        let mut energy = Sum::default();
        traverse::pairs(s.x, &self.cell, self.reach, |i, j, d| {
            if overflowed(&d) {
                return Err(Singularity::located(self.name, &[i, j], FAR, s.x));
            }
            let (mq, colour) = (bodies::<T>(s, i, j), colour::<T>(s, i, j));
            for p in &self.rows {
                let (a, e) = T::eval(p, d, mq, colour)
                    .and_then(|r| r.finite(true))
                    .map_err(|what| Singularity::pair(self.name, i, j, what, &d))?;
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
    fn leave_out_pairs_among(&self, first: usize) {
        if let Some(l) = &self.list {
            l.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).leave_out_pairs_among(first);
        }
    }

    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity> {
        stride_alone(self, stride, parts)
    }
    /// Through a Verlet list, the energy only if asked (it is a fifth of a pair's arithmetic).
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity> {
        let Some(list) = &self.list else { return self.traversed(s, f) };
        let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        l.update(s.x, &self.cell, self.pool.as_deref());
        let energy = match energy {
            true => self.through_list::<{ clusters::ENERGY }>(&l, s, f, &[])?,
            false => self.through_list::<{ clusters::FORCES_ONLY }>(&l, s, f, &[])?,
        };
        let finite = |b: &[f64; 3]| b.iter().all(|c| c.is_finite());
        let all_finite = spread::over(self.pool.as_deref(), f.len(), |on_pool| match on_pool {
            true => f.par_iter().with_min_len(BLOCK).all(finite),
            false => f.iter().all(finite),
        });
        if energy.is_finite() && all_finite {
            return Ok(energy);
        }
        // Rare: find the pair that overflowed, by the checked traversal.
        let mut scratch = vec![[0.0; 3]; f.len()];
        self.traversed(s, &mut scratch)?;
        Err(Singularity { term: self.name, bodies: vec![], what: OVERFLOW, seen: None })
    }
    fn virial(&self, s: &Frame) -> Option<Result<f64, Singularity>> {
        if let Some(list) = &self.list {
            let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            l.update(s.x, &self.cell, self.pool.as_deref());
            // through the force kernel, on the pool (its forces dropped); where a pair is
            // singular, the pair by pair sum names it
            let mut f = vec![[0.0; 3]; s.x.len()];
            return Some(match self.through_list::<{ clusters::VIRIAL }>(&l, s, &mut f, &[]) {
                Ok(w) if w.is_finite() => Ok(-w),
                _ => self.listed_virial(&l, s),
            });
        }
        let mut w = Sum::default();
        let visited = self.within_reach(s, |i, j, d| {
            for p in &self.rows {
                let (a, _) = T::eval(p, d, bodies::<T>(s, i, j), colour::<T>(s, i, j))
                    .map_err(|what| Singularity::pair(self.name, i, j, what, &d))?;
                w.add(-(d[0] * a[0] + d[1] * a[1] + d[2] * a[2]));
            }
            Ok(())
        });
        Some(visited.map(|_| w.value()))
    }
    fn owned_sums(&self, s: &Frame, owned: usize) -> Option<Result<[f64; 2], Singularity>> {
        let share = |i: usize, j: usize| 0.5 * (f64::from(u8::from(i < owned)) + f64::from(u8::from(j < owned)));
        let Some(list) = &self.list else {
            let (mut e, mut w) = (Sum::default(), Sum::default());
            let visited = self.within_reach(s, |i, j, d| {
                for p in &self.rows {
                    let (a, v) = T::eval(p, d, bodies::<T>(s, i, j), colour::<T>(s, i, j))
                        .map_err(|what| Singularity::pair(self.name, i, j, what, &d))?;
                    e.add(share(i, j) * v);
                    w.add(-share(i, j) * (d[0] * a[0] + d[1] * a[1] + d[2] * a[2]));
                }
                Ok(())
            });
            return Some(visited.map(|_| [e.value(), w.value()]));
        };
        let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        l.update(s.x, &self.cell, self.pool.as_deref());
        let (shares, mut f) = (clusters::shares(&l, owned), vec![[0.0; 3]; s.x.len()]);
        let sums = self
            .through_list::<{ clusters::OWNED_ENERGY }>(&l, s, &mut f, &shares)
            .and_then(|e| Ok([e, -self.through_list::<{ clusters::OWNED_VIRIAL }>(&l, s, &mut f, &shares)?]));
        Some(sums.and_then(|sums| match sums.iter().all(|x| x.is_finite()) {
            true => Ok(sums),
            false => Err(Singularity { term: self.name, bodies: vec![], what: OVERFLOW, seen: None }),
        }))
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
                let o = self.output.lock().unwrap_or_else(|p| p.into_inner());
                let s = |d: Duration| d.as_secs_f64();
                format!(
                    "cluster-pair list ({LANES}×{LANES}, half: Newton's third law), {reach} + skin {:.3}, {} builds, {} cluster pairs over {} clusters; {} piece(s) by size (halos: {:.2} buffer places a cluster) on {threads} thread(s); time: builds {:.3} s, updates {:.3} s, pieces {:.3} s, sums {:.3} s",
                    l.skin,
                    l.builds,
                    l.count(),
                    l.clusters(),
                    l.pieces.count(),
                    l.pieces.spread(),
                    s(l.spent.builds),
                    s(l.spent.updates),
                    s(o.worked),
                    s(o.gathered),
                )
            }
        }
    }
    fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity> {
        let each = self.derivatives((&[], false, false));
        self.within_reach(s, |i, j, d| {
            if d == [0.0; 3] {
                return Err(coincident(self.name, i, j));
            }
            for (k, pd) in each.iter().enumerate() {
                let f = pd.tangent(self.jet(k, &d, pd.reach2), s, dir, i, j, d);
                for c in 0..3 {
                    df[i][c] += f[c];
                    df[j][c] -= f[c];
                }
            }
            Ok(())
        })
    }
    fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        let each = self.derivatives_for(wanted);
        if let Some(list) = self.list.as_ref().filter(|_| self.jets_everywhere(&each)) {
            let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            l.update(s.x, &self.cell, self.pool.as_deref());
            self.listed_pullback(&l, Some(g), &each, out);
            return Ok(());
        }
        self.within_reach(s, |i, j, d| {
            if d == [0.0; 3] {
                return Err(coincident(self.name, i, j));
            }
            for (k, pd) in each.iter().enumerate() {
                pd.pullback(self.jet(k, &d, pd.reach2), s, g, i, j, d, out);
            }
            Ok(())
        })
    }
    fn potential_pullback(&self, s: &Frame, wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity> {
        let each = self.derivatives_for(wanted);
        if let Some(list) = self.list.as_ref().filter(|_| self.jets_everywhere(&each)) {
            let mut l = list.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            l.update(s.x, &self.cell, self.pool.as_deref());
            self.listed_pullback(&l, None, &each, out);
            return Ok(());
        }
        self.within_reach(s, |i, j, d| {
            if d == [0.0; 3] {
                return Err(coincident(self.name, i, j));
            }
            each.iter().for_each(|pd| pd.potential_pullback(s, i, j, d, out));
            Ok(())
        })
    }
    fn save(&self) -> Option<super::Kept> {
        let l = self.list.as_ref()?;
        Some(Box::new(l.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).copied(self.pool.as_deref())))
    }
    fn restore(&self, kept: &super::Kept) {
        if let (Some(l), Some(saved)) = (&self.list, kept.downcast_ref::<Neighbours>()) {
            l.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).copy_from(saved, self.pool.as_deref());
        }
    }
    fn built_at(&self) -> Option<Vec<[f64; 3]>> {
        let l = self.list.as_ref()?.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        (!l.built_at().is_empty()).then(|| l.built_at().to_vec())
    }
    fn build_at(&self, x: &[[f64; 3]]) {
        if let Some(l) = &self.list {
            l.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).build(x, &self.cell, self.pool.as_deref());
        }
    }
    fn builds(&self) -> u64 {
        self.list.as_ref().map_or(0, |l| l.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).builds)
    }
}
