//! A pair term's sum over its pairs: in the double loop's order in chunks of bodies (the same
//! bits on any number of threads), or, for `Outward`, sixteen pairs at a time in `Lanes` added
//! exactly in any order; and the reaches the broad phase is asked for.

use super::Lifted;
use crate::broad_phase::{Foreseen, Near, Neighbourhood};
use crate::enclosure::Enclosure;
use crate::exact_sum::ExactSum;
use crate::helpers::in_order;
use crate::model::{Model, Snapshot, TermInstance};
use crate::mpfi::Mpfi;
use crate::outward::lanes::{Lanes, WIDTH};
use crate::outward::Outward;
use crate::real::Real;
use crate::terms::{Kind, Reads, Shape, Site};
use rug::float::Round;

impl<R: PairSum> Lifted<R> {
    /// `pairs` for `sum`, in the double loop's order: those of the first `CHUNK` bodies added to
    /// the running sum, those of each later `CHUNK` bodies summed alone (`chunk(n, zero,
    /// pairs)`) and then added, so that the chunks can be listed and summed on `threads` threads
    /// and the bits do not depend on how many.
    pub(super) fn in_chunks<'s, T: Clone + Send + Sync + 's>(
        &'s self,
        (zero, add): (T, impl Fn(T, T) -> T + 's),
        chunk: impl Fn(usize, T, &[Near]) -> T + Sync + 's,
    ) -> impl Fn(usize, T, &Neighbourhood) -> T + 's {
        move |n, acc, near| {
            let bodies = self.x.len();
            let sums = in_order(bodies.div_ceil(CHUNK), self.threads, |k| {
                let start = if k == 0 { acc.clone() } else { zero.clone() };
                chunk(n, start, &near.of(k * CHUNK..((k + 1) * CHUNK).min(bodies)))
            });
            sums.into_iter().reduce(&add).unwrap_or(acc)
        }
    }

    /// A chunk of pairs for `in_chunks`: `term` at each pair in turn, added to the running sum.
    pub(super) fn one_by_one<'s, T: 's>(
        &'s self,
        term: &'s (impl Fn(usize, &[&Site<R>]) -> Option<T> + Sync),
        add: impl Fn(T, T) -> T + Sync + 's,
    ) -> impl Fn(usize, T, &[Near]) -> T + Sync + 's {
        move |n, acc, pairs| {
            pairs.iter().map(|p| self.sites_of(p)).filter_map(|(a, b)| term(n, &[a, &b])).fold(acc, &add)
        }
    }
}

/// How a pair term's potentials at all its pairs are added up: one pair after another in the
/// double loop's order, or, for `Outward`, sixteen pairs at a time in `Lanes` (each pair gets the
/// same bits as alone) and added exactly in any order (`ExactSum`).
pub trait PairSum: Real + Send + Sync {
    /// Σ `each(site)` over `l`'s sites, K sums in one pass: one after another, or for
    /// `Outward` exactly, in pieces on up to `l.threads` of the helpers (an exact sum has no
    /// order: the same bits).
    fn sum_over<const K: usize>(l: &Lifted<Self>, each: impl Fn(&Site<Self>) -> [Self; K] + Sync) -> [Self; K] {
        let mut sums = std::array::from_fn(|_| l.zero.clone());
        for e in l.sites.iter().map(each) {
            sums.iter_mut().zip(e).for_each(|(s, e)| *s = s.clone() + e);
        }
        sums
    }

    /// `acc` + the potential of instance `n` (of `kind`) at each pair `near` holds.
    fn add_potentials(l: &Lifted<Self>, acc: Self, kind: Kind, n: usize, near: &Neighbourhood) -> Self {
        let p = &l.params[n];
        let chunk = |_, acc, pairs: &[Near]| {
            pairs.iter().map(|q| l.sites_of(q)).fold(acc, |acc, (a, b)| acc + kind.potential(p, &[a, &b]))
        };
        l.in_chunks((l.zero.clone(), Self::add), chunk)(n, acc, near)
    }

    /// `acc` + the power instance `n` (of `kind`, a dissipating one) dissipates at each pair
    /// `near` holds.
    fn add_powers(l: &Lifted<Self>, acc: Self, kind: Kind, n: usize, near: &Neighbourhood) -> Self {
        let term = |n: usize, s: &[&Site<Self>]| kind.power(&l.params[n], s);
        let pairs = l.in_chunks((l.zero.clone(), Self::add), l.one_by_one(&term, Self::add));
        pairs(n, acc, near)
    }
}

/// What a sum over pairs in `Lanes` evaluates at each: a definition's potential, or the power
/// its dissipation function removes.
#[derive(Clone, Copy)]
pub(super) enum Summed {
    Potential,
    Power,
}

impl PairSum for f64 {}
#[cfg(test)]
impl PairSum for rug::Float {}
impl PairSum for Mpfi {}

impl PairSum for Outward {
    /// A piece is `SUMMED_APART` terms or more: handing one out costs what summing a few
    /// thousand does (at 256,000 bodies the kinetic energy and momentum, ~15 ms on one thread,
    /// were most of what the last checkpoint left to one thread).
    fn sum_over<const K: usize>(l: &Lifted<Self>, each: impl Fn(&Site<Self>) -> [Self; K] + Sync) -> [Self; K] {
        let (n, threads) = (l.sites.len(), l.threads);
        let pieces = (4 * threads).min(n / SUMMED_APART).max(1);
        let piece = |k: usize| &l.sites[n * k / pieces..n * (k + 1) / pieces];
        let sums = in_order(pieces, threads, |k| exact_bounds(piece(k).iter().map(&each)));
        std::array::from_fn(|c| l.zero + outward(&merged(sums.iter().map(|s| &s[c]))))
    }

    /// Σ lo and Σ hi over the pairs, each exact (`ExactSum`) and rounded once outward: they
    /// bound the exact sum of the pairs' exact potentials, and their bits do not depend on the
    /// order the pairs come in, so the broad phase lists them in whatever order is fastest
    /// (`each_unordered`) and in parts on `threads` threads.
    fn add_potentials(l: &Lifted<Self>, acc: Self, kind: Kind, n: usize, near: &Neighbourhood) -> Self {
        let [sums] = l.exact_lane_sums((kind, Summed::Potential), n, near, |_| Some(0));
        acc + outward(&sums)
    }

    /// As the potentials: sixteen pairs at a time, Σ lo and Σ hi exact and rounded once.
    fn add_powers(l: &Lifted<Self>, acc: Self, kind: Kind, n: usize, near: &Neighbourhood) -> Self {
        let [sums] = l.exact_lane_sums((kind, Summed::Power), n, near, |_| Some(0));
        acc + outward(&sums)
    }
}

impl Lifted<Outward> {
    /// Σ lo and Σ hi, each exact, of the potential (or the power, `Summed`) of instance `n` (of
    /// `kind`) at the pairs `near` holds, sixteen pairs at a time in `Lanes`, in `C` classes:
    /// `class` puts a pair in one or leaves it out. Listed in parts on the threads in whatever
    /// order is fastest: exact sums do not depend on it.
    pub(super) fn exact_lane_sums<const C: usize>(
        &self,
        (kind, summed): (Kind, Summed),
        n: usize,
        near: &Neighbourhood,
        class: impl Fn(&Near) -> Option<usize> + Sync,
    ) -> [(ExactSum, ExactSum); C] {
        let wide: Vec<Lanes> = self.params[n].iter().map(|c| Lanes::of([*c; WIDTH])).collect();
        let parts = near.parts();
        let pieces = (4 * self.threads).min(parts.max(1));
        let sums = in_order(pieces, self.threads, |k| {
            let mut sums: [(ExactSum, ExactSum); C] = std::array::from_fn(|_| Default::default());
            // a power reads the velocities (`reads` says what the potential reads)
            let reads = match summed {
                Summed::Potential => kind.reads(),
                Summed::Power => Reads { v: true, ..kind.reads() },
            };
            let mut sites = [Site::filled(Outward::NAN), Site::filled(Outward::NAN)];
            // the pairs kept, put into the lanes as they come, evaluated sixteen at a time; the
            // lanes past a short last group hold the group before's sites (or NaN) and are
            // dropped by the zip
            let (mut classes, mut held) = ([0; WIDTH], 0);
            let mut evaluate = |classes: &[usize], sites: &[Site<Lanes>; 2]| {
                let pair = [&sites[0], &sites[1]];
                let each = match summed {
                    Summed::Potential => kind.potential(&wide, &pair),
                    Summed::Power => kind.power(&wide, &pair).unwrap_or_else(|| wide[0].lift(0.0)),
                };
                for (e, c) in each.lanes().iter().zip(classes) {
                    let (a, b) = e.bounds();
                    sums[*c].0.add(a);
                    sums[*c].1.add(b);
                }
            };
            near.each_unordered(parts * k / pieces..parts * (k + 1) / pieces, |pairs| {
                for q in pairs {
                    let Some(c) = class(q) else { continue };
                    let (a, b) = (&self.sites[q.i], &self.sites[q.j]);
                    sites[0].put(held, &a.x, a, reads);
                    sites[1].put(held, &self.image_of(q.i, q.j).unwrap_or(b.x), b, reads);
                    classes[held] = c;
                    held += 1;
                    if held == WIDTH {
                        evaluate(&classes, &sites);
                        held = 0;
                    }
                }
            });
            if held > 0 {
                evaluate(&classes[..held], &sites);
            }
            sums
        });
        std::array::from_fn(|c| merged(sums.iter().map(|s| &s[c])))
    }
}

/// Σ lo and Σ hi of the enclosures, each exact, for each of K sums.
fn exact_bounds<const K: usize>(each: impl Iterator<Item = [Outward; K]>) -> [(ExactSum, ExactSum); K] {
    let mut sums: [(ExactSum, ExactSum); K] = std::array::from_fn(|_| Default::default());
    for (c, e) in each.flat_map(|e| e.into_iter().enumerate()) {
        sums[c].0.add(e.bounds().0);
        sums[c].1.add(e.bounds().1);
    }
    sums
}

/// Exact sums of lows and highs added together.
fn merged<'a>(sums: impl IntoIterator<Item = &'a (ExactSum, ExactSum)>) -> (ExactSum, ExactSum) {
    let mut total = (ExactSum::default(), ExactSum::default());
    for (lo, hi) in sums {
        total.0.merge(lo);
        total.1.merge(hi);
    }
    total
}

/// The enclosure of exact sums of lows and highs, each rounded once outward.
fn outward((lo, hi): &(ExactSum, ExactSum)) -> Outward {
    Outward::from_bounds(lo.total(Round::Down), hi.total(Round::Up))
}

/// Σ of enclosures as Σ lo and Σ hi, each exact (`ExactSum`) and rounded once outward: its
/// width is that of the terms alone, where adding one after another widens the sum by an ulp of
/// each partial sum (at 256,000 atoms more than the momentum's round-off budget), and its bits
/// do not depend on the order of the terms.
pub fn sum_exactly(each: impl Iterator<Item = Outward>) -> Outward {
    outward(&exact_bounds(each.map(|e| [e]))[0])
}

/// The reach a pair term's broad phase is asked for: the term's, with a relative margin of
/// 1e-6 on top (`None`: unbounded).
pub fn asked_reach(t: &TermInstance) -> Option<f64> {
    let r = t.kind.reach(&t.params) * (1.0 + 1e-6);
    r.is_finite().then_some(r)
}

/// The distinct reaches the model's pair terms ask their broad phase for (`asked_reach`; a pair
/// term without one is summed over every pair and needs no list).
pub fn pair_reaches(model: &Model) -> Vec<f64> {
    let mut reaches: Vec<f64> = vec![];
    for t in model.terms.iter().filter(|t| matches!(t.kind.spec().shape, Shape::Pairwise | Shape::Density)) {
        if let Some(r) = asked_reach(t).filter(|r| !reaches.contains(r)) {
            reaches.push(r);
        }
    }
    reaches
}

/// The pair lists the pair terms with a reach will want a few steps after state `s`
/// (`Foreseen`), made on up to `threads` of the helpers: one per reach, none where a grid would
/// not be used.
pub fn foresee(model: &Model, s: &Snapshot, threads: usize) -> Vec<Foreseen> {
    pair_reaches(model).into_iter().filter_map(|r| Foreseen::new(s.x, &model.cell, r, threads)).collect()
}

/// Bodies whose pairs are summed alone before their sum joins the total (see `Lifted::sum`).
const CHUNK: usize = 128;

/// The fewest terms of a piece of `sum_over` (summing 4,096 bodies' kinetic energy exactly takes
/// ~0.1 ms).
const SUMMED_APART: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Body, Cell, UnitSystem};
    use rug::Float;
    use std::sync::Arc;

    /// 2,197 LJ atoms in a periodic box: ~50,000 pairs, a dozen chunks.
    fn liquid() -> (Model, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let body = Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
        let model = Model {
            units: UnitSystem::Reduced,
            cell: Some(Cell { size: [14.3; 3], periodic: [true; 3] }),
            bodies: vec![body; 2197],
            terms: vec![TermInstance { kind: Kind::LennardJonesShifted, sites: vec![], params: vec![1.0, 1.0, 2.5] }],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        let jitter = |k: usize| ((k * 7919 % 1000) as f64 / 1000.0 - 0.5) * 0.2;
        let x = (0..2197).map(|k| [k % 13, k / 13 % 13, k / 169].map(|c| c as f64 * 1.1 + jitter(k + c))).collect();
        let v = (0..2197).map(|k| [jitter(k), jitter(k + 1), jitter(k + 2)]).collect();
        (model, x, v)
    }

    /// The chunked pair sum is the same bits on 1, 2 and 3 threads, spans several chunks, and
    /// encloses the 256-bit MPFR value.
    #[test]
    fn pair_sums_are_the_same_bits_on_any_thread_count() {
        let (m, x, v) = liquid();
        let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
        let on = |n| Lifted::new(&m, &s, &Outward::NAN).on_threads(n).energy(&m);
        let one = on(1);
        assert!(x.len() > 4 * CHUNK, "several chunks");
        for n in [2, 3] {
            let bits = |(lo, hi): (f64, f64)| (lo.to_bits(), hi.to_bits());
            assert_eq!(bits(on(n).bounds()), bits(one.bounds()));
        }
        let exact = Lifted::new(&m, &s, &Float::new(256)).on_threads(2).energy(&m);
        let (lo, hi) = one.bounds();
        assert!(Float::with_val(256, lo) <= exact && exact <= Float::with_val(256, hi), "{one:?}");
        assert!(hi - lo <= 1e-11 * hi.abs().max(lo.abs()), "{one:?}");
    }

    /// The kinetic energy and the momenta, summed in pieces on the helpers (`sum_over`), are the
    /// same bits on any number of threads, and those of the bodies' enclosures added exactly in
    /// order (`sum_exactly`): 10,000 bodies, two pieces or more.
    #[test]
    fn sums_over_the_bodies_are_the_same_bits_on_any_thread_count() {
        let (one, _, _) = liquid();
        let n = 10_000;
        assert!(n >= 2 * SUMMED_APART, "in pieces");
        let m = Model { bodies: vec![one.bodies[0].clone(); n], ..one };
        let wobble = |k: usize, c: usize| ((k * 7919 + c * 104_729) % 1000) as f64 / 1000.0 - 0.5;
        let x: Vec<[f64; 3]> = (0..n).map(|k| [k as f64 * 0.37, wobble(k, 1) * 9.0, wobble(k, 2) * 5.0]).collect();
        let v: Vec<[f64; 3]> = (0..n).map(|k| std::array::from_fn(|c| wobble(k, c) * 1e3 + 1e-9 * k as f64)).collect();
        let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
        let bits = |e: &Outward| (e.bounds().0.to_bits(), e.bounds().1.to_bits());
        let all = |q: &Lifted<Outward>| {
            let (p, l) = (q.momentum(&m), q.angular_momentum(&m));
            [q.kinetic(), p[0], p[1], p[2], l[0], l[1], l[2]].map(|e| bits(&e))
        };
        let one = Lifted::new(&m, &s, &Outward::NAN).on_threads(1);
        let half = one.zero.lift(0.5);
        let kinetic = sum_exactly(one.sites.iter().map(|b| half * b.m * crate::real::norm2(&b.v)));
        assert_eq!(all(&one)[0], bits(&(one.zero + kinetic)));
        let py = sum_exactly(one.sites.iter().map(|b| b.m * b.v[1]));
        assert_eq!(all(&one)[2], bits(&(one.zero + py)));
        for threads in [2, 3, 7] {
            assert_eq!(all(&Lifted::new(&m, &s, &Outward::NAN).on_threads(threads)), all(&one), "{threads} threads");
        }
    }

    /// A state lifted into the memory of another (`reusing`, as the monitor does from one
    /// checkpoint to the next) is the same bits as one lifted fresh: from another state of the
    /// same bodies, and from the sites of more bodies than it has.
    #[test]
    fn a_state_lifted_into_reused_memory_is_the_same_bits() {
        let (m, x, v) = liquid();
        let at = |x: &[[f64; 3]]| {
            Lifted::new(&m, &Snapshot { step: 0, t: 0.0, x, v: &v, chain: &[], spin: &[] }, &Outward::NAN)
        };
        let moved: Vec<[f64; 3]> = x.iter().map(|p| p.map(|c| c * 1.001)).collect();
        let bits = |e: Outward| (e.bounds().0.to_bits(), e.bounds().1.to_bits());
        let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
        let reused = Lifted::reusing(at(&moved).into_sites(), &m, &s, &Outward::NAN);
        assert_eq!(bits(reused.energy(&m)), bits(at(&x).energy(&m)));
        assert_ne!(bits(at(&moved).energy(&m)), bits(at(&x).energy(&m)), "the states differ");
        let few = Model { bodies: m.bodies[..100].to_vec(), ..m.clone() };
        let s = Snapshot { step: 0, t: 0.0, x: &x[..100], v: &v[..100], chain: &[], spin: &[] };
        let reused = Lifted::reusing(at(&x).into_sites(), &few, &s, &Outward::NAN);
        assert_eq!(reused.sites.len(), 100);
        assert_eq!(bits(reused.energy(&few)), bits(Lifted::new(&few, &s, &Outward::NAN).energy(&few)));
    }

    /// Sixteen pairs at a time (`PairSum` for `Outward`), listed in any order and in parts, give
    /// the bits of each pair's own enclosure (evaluated alone, in the double loop's order) added
    /// exactly and rounded once — whatever the number of pairs modulo sixteen, by the grid and by
    /// the double loop (under 64 bodies) — and never a wider sum than adding them one by one.
    #[test]
    fn pairs_in_lanes_add_up_to_the_exact_sum_of_each_alone() {
        let (all, x, v) = liquid();
        for n in [2, 5, 63, 64, 97, 500, 2197] {
            let m = Model { bodies: all.bodies[..n].to_vec(), ..all.clone() };
            let s = Snapshot { step: 0, t: 0.0, x: &x[..n], v: &v[..n], chain: &[], spin: &[] };
            let q = Lifted::new(&m, &s, &Outward::NAN);
            let (t, p) = (&m.terms[0], &q.params[0]);
            let pairs = crate::broad_phase::within(&x[..n], &m.cell, asked_reach(t));
            let start = Outward::point(-1.5);
            let (mut lo, mut hi, mut one_by_one) = (ExactSum::default(), ExactSum::default(), start);
            for (a, b) in pairs.iter().map(|p| q.sites_of(p)) {
                let e = t.kind.potential(p, &[a, &b]);
                (lo.add(e.bounds().0), hi.add(e.bounds().1));
                one_by_one = one_by_one + e;
            }
            let want = start + Outward::from_bounds(lo.total(Round::Down), hi.total(Round::Up));
            let near = Neighbourhood::new(&x[..n], &m.cell, asked_reach(t), &[]);
            for threads in [1, 3] {
                let on = Lifted::new(&m, &s, &Outward::NAN).on_threads(threads);
                let got = Outward::add_potentials(&on, start, t.kind, 0, &near);
                let bits = |e: Outward| (e.bounds().0.to_bits(), e.bounds().1.to_bits());
                assert_eq!(bits(got), bits(want), "{n} bodies, {} pairs, {threads} threads", pairs.len());
                assert!(got.bounds().0 >= one_by_one.bounds().0 && got.bounds().1 <= one_by_one.bounds().1);
            }
        }
    }

    /// The power a viscous fluid dissipates, sixteen pairs at a time: the bits of each pair's
    /// own enclosure added exactly and rounded once, on one thread and on three, holding the
    /// 256-bit value; pairs approaching and moving apart are both in every group of sixteen.
    #[test]
    fn powers_in_lanes_add_up_to_the_exact_sum_of_each_alone() {
        let (liquid, x, _) = liquid();
        // velocities of their own (the liquid's repeat its positions' jitter: every pair closes)
        let v: Vec<[f64; 3]> =
            (0..x.len()).map(|k| [7 * k % 13, 11 * k % 17, 5 * k % 19].map(|c| c as f64 / 9.0 - 0.9)).collect();
        let fluid = TermInstance { kind: Kind::Sph, sites: vec![], params: vec![0.6, 0.5, 3.0, 7.0, 0.5, 1.0] };
        for n in [5, 97, 2197] {
            let m = Model { bodies: liquid.bodies[..n].to_vec(), terms: vec![fluid.clone()], ..liquid.clone() };
            let s = Snapshot { step: 0, t: 0.0, x: &x[..n], v: &v[..n], chain: &[], spin: &[] };
            let q = Lifted::new(&m, &s, &Outward::NAN);
            let pairs = crate::broad_phase::within(&x[..n], &m.cell, asked_reach(&fluid));
            let (mut lo, mut hi, mut approaching) = (ExactSum::default(), ExactSum::default(), 0);
            for (a, b) in pairs.iter().map(|p| q.sites_of(p)) {
                let e = Kind::Sph.power(&q.params[0], &[a, &b]).unwrap();
                (lo.add(e.bounds().0), hi.add(e.bounds().1));
                approaching += usize::from(e.bounds().0 > 0.0);
            }
            assert!(
                n < 97 || (approaching > pairs.len() / 4 && approaching < 3 * pairs.len() / 4),
                "{approaching} of {}",
                pairs.len()
            );
            let want = Outward::from_bounds(lo.total(Round::Down), hi.total(Round::Up));
            let bits = |e: Outward| (e.bounds().0.to_bits(), e.bounds().1.to_bits());
            for threads in [1, 3] {
                let got = Lifted::new(&m, &s, &Outward::NAN).on_threads(threads).dissipated_power(&m);
                assert_eq!(
                    bits(got),
                    bits(Outward::point(0.0) + want),
                    "{n} bodies, {} pairs, {threads} threads",
                    pairs.len()
                );
            }
            let exact = Lifted::new(&m, &s, &Float::new(256)).dissipated_power(&m);
            let (lo, hi) = want.bounds();
            assert!(Float::with_val(256, lo) <= exact && exact <= Float::with_val(256, hi), "{want:?} against {exact}");
        }
    }

    /// Pair lists made a little earlier (`foresee`) change no bit of the energy, and a state
    /// that moved too far falls back to the grid, with the same bits too.
    #[test]
    fn lists_made_ahead_change_no_bit() {
        let (m, x, v) = liquid();
        let earlier: Vec<[f64; 3]> =
            x.iter().zip(&v).map(|(p, u)| std::array::from_fn(|a| p[a] - 0.5 * u[a])).collect();
        let ahead: Arc<[Foreseen]> =
            foresee(&m, &Snapshot { step: 0, t: 0.0, x: &earlier, v: &v, chain: &[], spin: &[] }, 2).into();
        assert_eq!(ahead.len(), 1);
        let bits = |x: &[[f64; 3]], ahead: Arc<[Foreseen]>| {
            let e = Lifted::new(&m, &Snapshot { step: 0, t: 0.0, x, v: &v, chain: &[], spin: &[] }, &Outward::NAN)
                .foreseeing(ahead)
                .energy(&m);
            (e.bounds().0.to_bits(), e.bounds().1.to_bits())
        };
        assert_eq!(bits(&x, ahead.clone()), bits(&x, Arc::default()));
        let mut far = x.clone();
        far[7][1] += 0.4;
        assert_eq!(bits(&far, ahead), bits(&far, Arc::default()));
    }
}
