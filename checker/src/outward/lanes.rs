//! Sixteen enclosures side by side: a term's definition evaluated at sixteen pairs at once.
//!
//! Why it is sound: every operation on `Lanes` is the `Outward` operation applied to each lane
//! (`zip`, `map`), so lane k holds exactly the bits one `Outward` evaluation at pair k gives.
//! `Outward`'s operations choose values rather than branch on them, so the sixteen copies become
//! vector instructions. The one place the lanes can disagree is a comparison (`lt`, the
//! cutoff): when they do, `lt` says "undecided" and keeps each lane's answer for the `hull`
//! that `select` then takes, which gives each lane what `select` would have given it alone.

use super::{down, up, Outward};
use crate::real::{Real, Vec3};
use crate::terms::{Reads, Site};
use std::array::from_fn;
use std::cell::RefCell;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Pairs at a time. Sixteen rather than four: the checks a group makes once (that every lane is
/// positive, that every lane is inside the cutoff) and the call into the definition cost a
/// quarter as much a pair; a 32,000-atom checkpoint on one CPU took 15% less time (44 against
/// 49–52 ms; eight lanes 45–48 ms), and small scenes, where a group is mostly padding, no more.
pub const WIDTH: usize = 16;

#[derive(Clone, Copy, Debug)]
pub struct Lanes {
    lo: [f64; WIDTH],
    hi: [f64; WIDTH],
}

impl Lanes {
    #[inline(always)]
    pub fn of(each: [Outward; WIDTH]) -> Lanes {
        Lanes { lo: each.map(|o| o.lo), hi: each.map(|o| o.hi) }
    }

    #[inline(always)]
    pub fn lanes(self) -> [Outward; WIDTH] {
        from_fn(|k| self.lane(k))
    }

    #[inline(always)]
    fn lane(&self, k: usize) -> Outward {
        Outward { lo: self.lo[k], hi: self.hi[k] }
    }

    #[inline(always)]
    fn map(self, f: impl Fn(Outward) -> Outward) -> Lanes {
        self.zip(self, |a, _| f(a))
    }

    /// `f` lane by lane: written as a loop over arrays (not through `lanes` and `of`) so that the
    /// compiler sees `WIDTH` copies of one straight-line code and makes them vector instructions.
    #[inline(always)]
    fn zip(self, o: Lanes, f: impl Fn(Outward, Outward) -> Outward) -> Lanes {
        let mut r = self;
        for k in 0..WIDTH {
            let v = f(self.lane(k), o.lane(k));
            (r.lo[k], r.hi[k]) = (v.lo, v.hi);
        }
        r
    }
}

impl Site<Lanes> {
    /// Sites with every field `[c, c]` in every lane.
    pub fn filled(c: Outward) -> Site<Lanes> {
        let l = Lanes::of([c; WIDTH]);
        Site { x: [l; 3], v: [l; 3], m: l, q: l, colour: [l; 2] }
    }

    /// Site `s` at position `x` (its own, or a periodic image of it) into lane `k`, with the
    /// fields in `reads` (the others are left as they are: filled with NaN, a definition that
    /// read them would know nothing).
    #[inline(always)]
    pub fn put(&mut self, k: usize, x: &Vec3<Outward>, s: &Site<Outward>, reads: Reads) {
        let set = |l: &mut Lanes, o: &Outward| (l.lo[k], l.hi[k]) = (o.lo, o.hi);
        self.x.iter_mut().zip(x).for_each(|(l, o)| set(l, o));
        if reads.v {
            self.v.iter_mut().zip(&s.v).for_each(|(l, o)| set(l, o));
        }
        if reads.m {
            set(&mut self.m, &s.m);
        }
        if reads.q {
            set(&mut self.q, &s.q);
        }
        if reads.colour {
            self.colour.iter_mut().zip(&s.colour).for_each(|(l, o)| set(l, o));
        }
    }
}

macro_rules! lane_wise {
    ($($op:ident $f:ident),*) => {
        $(impl $op for Lanes {
            type Output = Lanes;
            #[inline(always)]
            fn $f(self, o: Lanes) -> Lanes {
                self.zip(o, Outward::$f)
            }
        })*
    };
}
lane_wise!(Add add, Sub sub);

impl Lanes {
    /// Whether every lane is an interval of positive reals with a finite top (so none is NaN,
    /// and no endpoint quotient is ∞/∞ nor product 0·∞).
    #[inline(always)]
    fn positive(&self) -> bool {
        let low = self.lo.iter().fold(true, |all, &l| all & (l > 0.0));
        low & self.hi.iter().fold(true, |all, &h| all & (h < f64::INFINITY))
    }

    /// Whether every lane has ordered ends (so none is NaN).
    #[inline(always)]
    fn ordered(&self) -> bool {
        self.lo.iter().zip(&self.hi).fold(true, |all, (l, h)| all & (l <= h))
    }
}

/// `f(k)` for every lane k, as a loop that inlines (`from_fn` at sixteen lanes did not).
#[inline(always)]
fn each(f: impl Fn(usize) -> f64) -> [f64; WIDTH] {
    let mut r = [0.0; WIDTH];
    for (k, v) in r.iter_mut().enumerate() {
        *v = f(k);
    }
    r
}

/// × and ÷ of positive intervals (distances, their powers: most of a pair term's products)
/// without the hull of four: rounding to nearest is monotone, so of the four endpoint results
/// the least is lo·lo (lo/hi) and the greatest hi·hi (hi/lo), the bits `Outward`'s hull
/// picks. A positive interval times any ordered one (a strength times an energy of either
/// sign) likewise: the least is lo·b.lo if b.lo ≥ 0, else hi·b.lo, the greatest hi·b.hi if
/// b.hi ≥ 0, else lo·b.hi (a positive finite factor makes no 0·∞). One branch for all the
/// lanes, which the lanes of a pair term almost always take.
impl Mul for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn mul(self, o: Lanes) -> Lanes {
        let times = |a: &Lanes, b: &Lanes| Lanes {
            lo: each(|k| down(if b.lo[k] >= 0.0 { a.lo[k] * b.lo[k] } else { a.hi[k] * b.lo[k] })),
            hi: each(|k| up(if b.hi[k] >= 0.0 { a.hi[k] * b.hi[k] } else { a.lo[k] * b.hi[k] })),
        };
        match (self.positive(), o.positive()) {
            (true, b) if b || o.ordered() => times(&self, &o),
            (false, true) if self.ordered() => times(&o, &self),
            _ => self.zip(o, Outward::mul),
        }
    }
}

impl Div for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn div(self, o: Lanes) -> Lanes {
        match self.positive() & o.positive() {
            true => Lanes { lo: each(|k| down(self.lo[k] / o.hi[k])), hi: each(|k| up(self.hi[k] / o.lo[k])) },
            false => self.zip(o, Outward::div),
        }
    }
}

impl Neg for Lanes {
    type Output = Lanes;
    #[inline(always)]
    fn neg(self) -> Lanes {
        self.map(Outward::neg)
    }
}

/// The `Real` functions of one argument, lane by lane.
macro_rules! each_lane {
    ($($f:ident),*) => {
        $(fn $f(self) -> Self {
            self.map(Outward::$f)
        })*
    };
}

thread_local! {
    /// Each lane's answer to the comparisons the lanes disagreed on, latest last.
    static UNDECIDED: RefCell<Vec<[Option<bool>; WIDTH]>> = const { RefCell::new(Vec::new()) };
}

impl Real for Lanes {
    #[inline(always)]
    fn lift(&self, c: f64) -> Self {
        Lanes::of([Outward::point(c); WIDTH])
    }
    each_lane!(sqrt, exp, ln, acos, cos, sin);
    #[inline(always)]
    fn powi(self, n: i32) -> Self {
        // the steps of `Outward::powi`, on all lanes at once
        let p = super::ladder(self, n.unsigned_abs(), self.lift(1.0), &|x: Lanes| x.map(Outward::sqr));
        if n < 0 {
            self.lift(1.0) / p
        } else {
            p
        }
    }
    fn atan2(self, x: Self) -> Self {
        self.zip(x, Outward::atan2)
    }
    /// The lanes' common answer; if they differ (or none is decided), "undecided", each lane's
    /// answer kept for the `hull` that follows.
    #[inline(always)]
    fn lt(&self, bound: &Self) -> Option<bool> {
        // the common case first, with no branch per lane: every lane decided alike
        let all = |f: &dyn Fn(usize) -> bool| (0..WIDTH).fold(true, |all, k| all & f(k));
        if all(&|k| self.hi[k] < bound.lo[k]) {
            return Some(true);
        }
        if all(&|k| self.lo[k] >= bound.hi[k]) {
            return Some(false);
        }
        let (a, b) = (self.lanes(), bound.lanes());
        let each: [Option<bool>; WIDTH] = from_fn(|k| a[k].lt(&b[k]));
        if each[0].is_some() && each.iter().all(|c| *c == each[0]) {
            return each[0];
        }
        UNDECIDED.with(|u| u.borrow_mut().push(each));
        None
    }
    /// Lane by lane, what `select` gives one enclosure: `self` (the "yes") where the lane's
    /// comparison held, `o` where it did not, their hull where it was undecided.
    fn hull(self, o: Self) -> Self {
        let each = UNDECIDED.with(|u| u.borrow_mut().pop()).expect("hull follows an undecided lt");
        let (yes, no) = (self.lanes(), o.lanes());
        Lanes::of(from_fn(|k| crate::real::select(each[k], || yes[k], || no[k])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::Kind;
    use proptest::prelude::*;

    fn bits(o: Outward) -> (u64, u64) {
        (o.lo.to_bits(), o.hi.to_bits())
    }

    fn site(x: [f64; 3], q: f64) -> Site<Outward> {
        let p = Outward::point;
        Site { x: x.map(p), v: [p(0.5), p(-1.0), p(2.0)], m: p(1.5), q: p(q), colour: [p(0.25), p(-0.5)] }
    }

    proptest! {
        /// × and ÷ of lanes are the bits of `Outward`'s hull of four in each lane, from tiny to
        /// huge endpoints, zeros and infinities: both factors positive, one of them, or neither.
        #[test]
        fn positive_products_and_quotients_are_the_hull_of_four(
            ends in prop::collection::vec(prop::array::uniform4(prop_oneof![
                1e-310f64..1e-300, 1e-3f64..1e3, 1e300f64..1e308, -1.0f64..1.0, -1e3f64..-1e-3,
                Just(0.0), Just(-0.0), Just(f64::INFINITY), Just(f64::NEG_INFINITY)
            ]), WIDTH),
            positive in any::<[bool; 2]>(),
        ) {
            let lanes = |a: usize| Lanes::of(from_fn(|k| {
                let end = |e: f64| if positive[a / 2] { e.abs().clamp(1e-310, f64::MAX) } else { e };
                let (x, y) = (end(ends[k][a]), end(ends[k][a + 1]));
                Outward::from_bounds(x.min(y), x.max(y))
            }));
            let (a, b) = (lanes(0), lanes(2));
            for (got, op) in [(a * b, Outward::mul as fn(Outward, Outward) -> Outward), (a / b, Outward::div)] {
                for k in 0..WIDTH {
                    prop_assert_eq!(bits(got.lanes()[k]), bits(op(a.lanes()[k], b.lanes()[k])));
                }
            }
        }

        /// Every pair term's potential at `WIDTH` pairs in lanes is, lane by lane, the same bits
        /// as at each pair alone: pairs within and beyond the cutoff, and at it, mixed.
        #[test]
        fn lanes_give_each_pair_its_own_bits(
            d in prop::collection::vec(prop::array::uniform3(prop_oneof![-3.0f64..3.0, Just(0.0), Just(2.5)]), WIDTH),
            q in prop::collection::vec(-2.0f64..2.0, WIDTH),
            at_zero in any::<bool>(),
        ) {
            // from the origin, a pair 2.5 apart straddles a 2.5 cutoff once rounded: undecided
            let origin = site(if at_zero { [0.0; 3] } else { [0.1, -0.2, 0.3] }, 1.0);
            let others: Vec<Site<Outward>> = (0..WIDTH).map(|k| site(d[k], q[k])).collect();
            for kind in Kind::ALL.iter().filter(|k| k.spec().shape == crate::terms::Shape::Pairwise) {
                let params: Vec<Outward> =
                    (0..kind.spec().width()).map(|k| Outward::point([1.0, 1.2, 2.5, 0.7][k % 4])).collect();
                let wide: Vec<Lanes> = params.iter().map(|p| Lanes::of([*p; WIDTH])).collect();
                let mut sites = [Site::filled(Outward::NAN), Site::filled(Outward::NAN)];
                for (k, other) in others.iter().enumerate() {
                    sites[0].put(k, &origin.x, &origin, kind.reads());
                    sites[1].put(k, &other.x, other, kind.reads());
                }
                let at = kind.potential(&wide, &[&sites[0], &sites[1]]);
                for (k, lane) in at.lanes().into_iter().enumerate() {
                    let alone = kind.potential(&params, &[&origin, &others[k]]);
                    prop_assert_eq!(bits(lane), bits(alone), "{:?}, lane {}", kind, k);
                }
                prop_assert!(UNDECIDED.with(|u| u.borrow().is_empty()));
            }
        }
    }
}
