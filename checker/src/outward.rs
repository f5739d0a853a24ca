//! The checker's fast enclosure: binary64 intervals whose every endpoint is computed in the
//! default rounding (to nearest) and then stepped outward past its neighbour.
//!
//! Why it is sound: IEEE 754 rounds + − × ÷ √ correctly, so the computed r = RN(x) is a
//! binary64 value nearest the exact x. Then pred(r) ≤ x ≤ succ(r): were x above succ(r), succ(r)
//! would be nearer to x than r (and symmetrically below); at the ends of the range succ(MAX) =
//! +∞ and pred(+∞) = MAX, which an overflowing x ≥ MAX + ulp/2 still lies above. Each upper
//! endpoint is then taken to `up(r)`, a binary64 value above r and so at or above succ(r), each
//! lower one to `down(r)`, and every exact value of the operation on the enclosed reals lies in
//! between. Rust evaluates these operations in the default rounding mode and never contracts
//! them into fused operations; the step outward is one explicit fused multiply-add, rounded
//! once (`mul_add`: the FMA instruction, with `+fma` in .cargo/config.toml). z3 proves both steps over every binary64 operand in its IEEE
//! model, the first for + − × ÷ (`checker/proofs/outward.smt2`); the tests below hold every
//! operation to MPFR over random and extreme operands.
//!
//! Why not inari for this: inari rounds each operation outward by switching the CPU's rounding
//! mode around it, twice per operation, which made a 32,000-atom checkpoint several times
//! slower. The price here is up to two ulps more width per operation. The functions beyond √
//! (exp, ln, the trigonometric ones) are not correctly rounded in binary64 libraries, so they go
//! through inari. The operations choose values rather than branch on their operands
//! (`pick`, `either`), so that four of them side by side (`lanes`) run as vector instructions.
//! An enclosure nothing is known of (a NaN anywhere, √ of a negative interval, an inner end
//! that overflowed) is `NAN`: every bound it reports is NaN, which the decision never takes
//! for a PASS.

use crate::enclosure::Enclosure;
use crate::real::Real;
use inari::Interval;
use std::ops::{Add, Div, Mul, Neg, Sub};

pub mod lanes;

/// The reals in `[lo, hi]`; both NaN when nothing is known.
#[derive(Clone, Copy, Debug)]
pub struct Outward {
    lo: f64,
    hi: f64,
}

impl Outward {
    pub const NAN: Outward = Outward { lo: f64::NAN, hi: f64::NAN };
    const ENTIRE: Outward = Outward { lo: f64::NEG_INFINITY, hi: f64::INFINITY };

    /// `[c, c]`, exact (a NaN or an infinity gives `NAN`).
    pub fn point(c: f64) -> Outward {
        Outward::from_bounds(c, c)
    }

    /// The reals from `lo` to `hi`, bounds already known to enclose (rounded outward or exact):
    /// `NAN` unless lo ≤ hi, lo below +∞ and hi above −∞.
    #[inline(always)]
    pub fn from_bounds(lo: f64, hi: f64) -> Outward {
        Outward::either(lo <= hi && lo < f64::INFINITY && hi > f64::NEG_INFINITY, Outward { lo, hi }, Outward::NAN)
    }

    /// The bounds of a correctly rounded result, stepped outward past their neighbours
    /// (`down`, `up`). The callers round monotone results of ordered operands, so lo ≤ hi unless
    /// a NaN came in; `down` never gives +∞ nor `up` −∞.
    #[inline(always)]
    fn rounded(lo: f64, hi: f64) -> Outward {
        Outward { lo: down(lo), hi: up(hi) }
    }

    #[inline(always)]
    fn is_nan(&self) -> bool {
        self.lo.is_nan() | self.hi.is_nan()
    }

    /// Through inari, for the functions binary64 libraries do not round correctly.
    fn via_inari(self, f: impl Fn(Interval) -> Interval) -> Outward {
        match Interval::try_from((self.lo, self.hi)).map(f) {
            Ok(r) => Outward::from_bounds(r.inf(), r.sup()), // empty: inf > sup, so NAN
            Err(_) => Outward::NAN,
        }
    }

    /// x², tight across zero (x² ≥ 0 is known, x·x would not know it): from the square of the
    /// point nearest zero, max(lo, −hi, 0), to the greater endpoint square.
    #[inline(always)]
    fn sqr(self) -> Outward {
        let nearest = most(most(self.lo, -self.hi), 0.0);
        let r = Outward::rounded(nearest * nearest, most(self.lo * self.lo, self.hi * self.hi));
        // x² ≥ 0 (a NaN stays NaN above)
        Outward { lo: most(r.lo, 0.0), ..r }
    }

    /// xᵏ: squares tight across zero, the squares and cubes the definitions use written out.
    fn power(self, k: u32) -> Outward {
        ladder(self, k, Outward::point(1.0), &Outward::sqr)
    }

    /// The hull of four endpoint results, rounded outward. A NaN among them without a NaN
    /// operand is 0·∞ or ∞/∞ (or ∞ − ∞): the whole line, which is sound.
    #[inline(always)]
    fn of_four(p: [f64; 4], operands_nan: bool) -> Outward {
        let nan = p[0].is_nan() | p[1].is_nan() | p[2].is_nan() | p[3].is_nan();
        let r = Outward::rounded(least(least(p[0], p[1]), least(p[2], p[3])), most(most(p[0], p[1]), most(p[2], p[3])));
        let unknown = Outward::either(operands_nan, Outward::NAN, Outward::ENTIRE);
        Outward::either(nan, unknown, r)
    }

    /// `a` if `c`, else `b`: a choice of values, so that no operation branches on its operands
    /// and several lanes of them run as one vector instruction (`Lanes`).
    #[inline(always)]
    fn either(c: bool, a: Outward, b: Outward) -> Outward {
        Outward { lo: pick(c, a.lo, b.lo), hi: pick(c, a.hi, b.hi) }
    }
}

/// xᵏ by squaring and multiplying, for one enclosure or for lanes of them (the same steps, so
/// the same bits in each lane): k's bits from the highest down, a square for each and a
/// product with x for each set one. A loop, not a recursion, so that it inlines into a
/// definition and unrolls for its constant k (a call per power was a sixth of a checkpoint).
#[inline(always)]
fn ladder<T: Copy + Mul<Output = T>>(x: T, k: u32, one: T, sqr: &impl Fn(T) -> T) -> T {
    if k == 0 {
        return one;
    }
    let mut p = x;
    for bit in (0..k.ilog2()).rev() {
        p = sqr(p);
        if k >> bit & 1 == 1 {
            p = p * x;
        }
    }
    p
}

/// `a` if `c`, else `b` (a select, not a branch).
#[inline(always)]
fn pick(c: bool, a: f64, b: f64) -> f64 {
    if c {
        a
    } else {
        b
    }
}

/// The lesser of `a` and `b`, and the greater; `b` when either is NaN (a maximum with 0 thus
/// drops a NaN: `sqr` and `sqrt` rely on that for a lower end, the other callers set NaN cases
/// apart).
#[inline(always)]
fn least(a: f64, b: f64) -> f64 {
    pick(a < b, a, b)
}

#[inline(always)]
fn most(a: f64, b: f64) -> f64 {
    pick(a > b, a, b)
}

/// The least step outward, 2⁻⁵¹¹: its square is the least normal binary64 value, 2⁻¹⁰²².
const FLOOR: f64 = f64::from_bits(0x2000_0000_0000_0000);

/// A binary64 value above r: r + |r|·2⁻⁵² + 2⁻⁵¹¹ (`FLOOR`), rounded once (one fused
/// multiply-add after r + 2⁻⁵¹¹), a few neighbours or 2⁻⁵¹⁰ up at most. |r|·2⁻⁵² is at least
/// r's ulp, and 2⁻⁵¹¹ at least the gap to a neighbour near zero, so the exact sum is above
/// succ(r) and rounds to a value at or above it: z3 proves up(r) > r for every finite binary64
/// r (`checker/proofs/outward.smt2`). From 2⁻⁴⁵⁷ in magnitude up, r + 2⁻⁵¹¹ rounds to r (at
/// most half of half an ulp away, or a tie that rounds to r) and the floor moves no bit.
/// +∞ stays; −∞ gives NaN (∞ − ∞), so an upper end that overflowed to −∞ makes the enclosure
/// unknown rather than −MAX: sound, and no branch, where `f64::next_up` tests for NaN, ∞, zero
/// and sign. Three instructions (|r|, the addition of the floor, the FMA), half of what a
/// floor applied by a compare and the infinities by a test cost, and the operations of a pair
/// term are mostly these steps. Why the floor is 2⁻⁵¹¹ and not less: Intel cores take a
/// microcode assist of ~40 ns for a subnormal operand and for a result that underflows (the
/// step `|r|·2⁻⁵² + 2⁻¹⁰⁷⁴` once put a subnormal into every operation, and made the checker four
/// times slower there than on AMD). A coordinate difference or a speed that is exactly zero
/// (bodies on a lattice, in a plane, at rest) steps out to ±2⁻⁵¹¹, not ±2⁻¹⁰²², whose square
/// underflowed; so near zero every end the arithmetic makes is 0 or about 2⁻⁵¹¹ or more, and
/// their products stay normal (`tests/end_to_end/subnormal.rs` reads the CPU's flags over every scene).
#[inline(always)]
fn up(r: f64) -> f64 {
    r.abs().mul_add(f64::EPSILON, r + FLOOR)
}

/// A binary64 value below r: −up(−r), a few neighbours or 2⁻⁵¹⁰ down at most (−∞ stays, +∞
/// gives NaN).
#[inline(always)]
fn down(r: f64) -> f64 {
    -r.abs().mul_add(f64::EPSILON, FLOOR - r)
}

impl Add for Outward {
    type Output = Outward;
    #[inline(always)]
    fn add(self, o: Outward) -> Outward {
        Outward::rounded(self.lo + o.lo, self.hi + o.hi)
    }
}

impl Sub for Outward {
    type Output = Outward;
    #[inline(always)]
    fn sub(self, o: Outward) -> Outward {
        Outward::rounded(self.lo - o.hi, self.hi - o.lo)
    }
}

impl Neg for Outward {
    type Output = Outward;
    #[inline(always)]
    fn neg(self) -> Outward {
        Outward { lo: -self.hi, hi: -self.lo }
    }
}

impl Mul for Outward {
    type Output = Outward;
    #[inline(always)]
    fn mul(self, o: Outward) -> Outward {
        let (a, b) = (self, o);
        Outward::of_four([a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi], a.is_nan() | b.is_nan())
    }
}

impl Div for Outward {
    type Output = Outward;
    #[inline(always)]
    fn div(self, o: Outward) -> Outward {
        let (a, b) = (self, o);
        let quotient = Outward::of_four([a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi], false);
        // a divisor that may be zero: nothing is known of the quotient's size
        let nan = a.is_nan() | b.is_nan();
        let unknown = Outward::either(nan, Outward::NAN, Outward::ENTIRE);
        Outward::either(nan | (b.lo <= 0.0 && b.hi >= 0.0), unknown, quotient)
    }
}

impl Real for Outward {
    #[inline(always)]
    fn lift(&self, c: f64) -> Self {
        Outward::point(c)
    }
    /// √ of the non-negative part; `NAN` if there is none.
    #[inline(always)]
    fn sqrt(self) -> Self {
        let lo = pick(self.lo > 0.0, most(down(self.lo.sqrt()), 0.0), 0.0);
        Outward::either(self.hi >= 0.0, Outward { lo, hi: up(self.hi.sqrt()) }, Outward::NAN)
    }
    /// By squaring and multiplying, each step rounded outward.
    #[inline(always)]
    fn powi(self, n: i32) -> Self {
        let p = self.power(n.unsigned_abs());
        if n < 0 {
            Outward::point(1.0) / p
        } else {
            p
        }
    }
    fn exp(self) -> Self {
        self.via_inari(Interval::exp)
    }
    fn ln(self) -> Self {
        self.via_inari(Interval::ln)
    }
    fn acos(self) -> Self {
        self.via_inari(Interval::acos)
    }
    fn cos(self) -> Self {
        self.via_inari(Interval::cos)
    }
    fn sin(self) -> Self {
        self.via_inari(Interval::sin)
    }
    fn atan2(self, x: Self) -> Self {
        match Interval::try_from((x.lo, x.hi)) {
            Ok(x) => self.via_inari(|y| y.atan2(x)),
            Err(_) => Outward::NAN,
        }
    }
    #[inline(always)]
    fn lt(&self, bound: &Self) -> Option<bool> {
        if self.hi < bound.lo {
            Some(true)
        } else if self.lo >= bound.hi {
            Some(false)
        } else {
            None // straddling, or a NaN
        }
    }
    #[inline(always)]
    fn hull(self, o: Self) -> Self {
        let r = Outward { lo: least(self.lo, o.lo), hi: most(self.hi, o.hi) };
        Outward::either(self.is_nan() | o.is_nan(), Outward::NAN, r)
    }
}

impl Enclosure for Outward {
    fn abs(self) -> Self {
        if self.lo >= 0.0 || self.is_nan() {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Outward { lo: 0.0, hi: self.hi.max(-self.lo) }
        }
    }
    fn max(self, o: Self) -> Self {
        if self.is_nan() || o.is_nan() {
            return Outward::NAN;
        }
        Outward { lo: self.lo.max(o.lo), hi: self.hi.max(o.hi) }
    }
    fn bounds(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rug::float::Round;
    use rug::Float;

    /// Exact for sums, differences and products of binary64 values (2,200 bits span every
    /// exponent); quotients and roots are enclosed by rounding down and up at the same width.
    const WIDE: u32 = 2200;

    fn exact(x: f64) -> Float {
        Float::with_val(WIDE, x)
    }

    /// [lo, hi] holds every value between `down` and `up` (the exact result rounded both ways),
    /// or nothing is known (NaN) and an inner end overflowed: `down` above MAX (the lower end
    /// rounded to +∞, one step down from which is NaN) or `up` below −MAX.
    fn holds(r: Outward, down: &Float, up: &Float) -> bool {
        let overflowed = *down > f64::MAX || *up < -f64::MAX;
        match r.is_nan() {
            true => overflowed,
            false => Float::with_val(WIDE, r.lo) <= *down && *up <= Float::with_val(WIDE, r.hi),
        }
    }

    /// The four endpoint combinations of a binary operation, exact or rounded both ways.
    fn corners(a: Outward, b: Outward, op: impl Fn(&Float, &Float, Round) -> Float) -> (Float, Float) {
        let mut lo = Float::with_val(WIDE, f64::INFINITY);
        let mut hi = Float::with_val(WIDE, f64::NEG_INFINITY);
        for x in [a.lo, a.hi] {
            for y in [b.lo, b.hi] {
                lo = lo.min(&op(&exact(x), &exact(y), Round::Down));
                hi = hi.max(&op(&exact(x), &exact(y), Round::Up));
            }
        }
        (lo, hi)
    }

    /// `up(r)` is above r's neighbour, and no farther than three neighbours or 2⁻⁵¹⁰.
    fn passes_up(r: f64) -> bool {
        let near = r.next_up().next_up().next_up().max(r + 2.0 * FLOOR);
        up(r) >= r.next_up() && up(r) <= near
    }

    /// `down` mirrors `up`.
    fn passes_down(r: f64) -> bool {
        passes_up(-r) && -down(r) == up(-r)
    }

    /// A zero steps out to ±2⁻⁵¹¹, and what an enclosure of zero leads to by products, squares
    /// and sums has ends that are 0 or normal, never subnormal: no operation on them underflows
    /// (the CPU's own flags for that are read over every scene in `tests/end_to_end/subnormal.rs`).
    #[test]
    fn a_zero_steps_out_to_ends_whose_products_stay_normal() {
        assert_eq!(FLOOR * FLOOR, f64::MIN_POSITIVE);
        let zero = Outward::point(1.5) - Outward::point(1.5);
        assert_eq!((zero.lo, zero.hi), (-FLOOR, FLOOR));
        let normal_or_zero = |o: Outward| [o.lo, o.hi].iter().all(|e| *e == 0.0 || e.is_normal());
        let quarter = Outward::point(0.25);
        for o in [zero.powi(2), zero * zero, zero.powi(3), zero.powi(4), zero.powi(2) * zero, zero * quarter] {
            assert!(normal_or_zero(o) && normal_or_zero(o + zero.powi(2)), "{o:?}");
        }
    }

    proptest! {
        /// From 2⁻⁴⁵⁷ in magnitude up the floor moves no bit of a step outward: there r + 2⁻⁵¹¹
        /// rounds to r, and the step is r ± |r|·2⁻⁵² rounded once. (At 2⁻⁴⁵⁸ it does: 2⁻⁵¹¹ is
        /// half an ulp there, and a tie can round away from r.)
        #[test]
        fn the_floor_moves_no_bit_above_its_scale(m in 1.0f64..2.0, e in -457i32..1023, negative in any::<bool>()) {
            let unmoved = |r: f64| up(r) == r.abs().mul_add(f64::EPSILON, r) && down(r) == -r.abs().mul_add(f64::EPSILON, -r);
            let sign = if negative { -1.0 } else { 1.0 };
            prop_assert!(unmoved(sign * m * 2f64.powi(e)));
            // the edges of the scale, exactly
            for m in [1.0, 1.0 + f64::EPSILON, 2.0 - f64::EPSILON] {
                prop_assert!(unmoved(sign * m * 2f64.powi(-457)));
                prop_assert!(!unmoved(sign * (1.0 + f64::EPSILON) * 2f64.powi(-458)));
            }
        }
    }

    /// A binary64 value: any bits (every exponent, subnormals, infinities), or a moderate one.
    fn value() -> impl Strategy<Value = f64> {
        prop_oneof![any::<u64>().prop_map(f64::from_bits).prop_filter("not NaN", |x| !x.is_nan()), -1e3f64..1e3]
    }

    fn interval() -> impl Strategy<Value = Outward> {
        (value(), value()).prop_map(|(a, b)| Outward::from_bounds(a.min(b), a.max(b)))
    }

    fn arith(op: char) -> impl Fn(&Float, &Float, Round) -> Float {
        move |x, y, r| {
            let mut out = Float::new(WIDE);
            let _ = match op {
                '+' => out.assign_round(x + y, r),
                '-' => out.assign_round(x - y, r),
                '*' => out.assign_round(x * y, r),
                _ => out.assign_round(x / y, r),
            };
            out
        }
    }

    use rug::ops::AssignRound;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        /// Every operation's result holds the exact results at its operands' endpoints (for +, −,
        /// × and ÷ on intervals the extremes are at the endpoints), over all binary64 values:
        /// subnormals, overflow and the infinities included.
        #[test]
        fn arithmetic_encloses_the_exact_result(a in interval(), b in interval()) {
            let finite = |r: &Outward| r.lo.is_finite() && r.hi.is_finite();
            prop_assume!(finite(&a) && finite(&b));
            for (op, r) in [('+', a + b), ('-', a - b), ('*', a * b)] {
                let (lo, hi) = corners(a, b, arith(op));
                prop_assert!(holds(r, &lo, &hi), "{a:?} {op} {b:?} = {r:?}");
            }
            if !(b.lo <= 0.0 && b.hi >= 0.0) {
                let (lo, hi) = corners(a, b, arith('/'));
                prop_assert!(holds(a / b, &lo, &hi), "{a:?} / {b:?} = {:?}", a / b);
            }
        }

        /// √, squares and powers enclose the exact values at the endpoints (both monotone on
        /// the non-negative reals, where these intervals live).
        #[test]
        fn roots_and_powers_enclose(a in interval(), n in -7i32..=12) {
            let a = Outward::from_bounds(a.lo.abs().min(a.hi.abs()), a.lo.abs().max(a.hi.abs()));
            prop_assume!(a.hi.is_finite() && (n >= 0 || a.lo > 0.0));
            let root = |x: f64, r| Float::with_val_round(WIDE, exact(x).sqrt_ref(), r).0;
            prop_assert!(holds(a.sqrt(), &root(a.lo, Round::Down), &root(a.hi, Round::Up)));
            let pow = |x: f64, n: i32, r| Float::with_val_round(WIDE, rug::ops::Pow::pow(&exact(x), n), r).0;
            let (lo, hi) = if n >= 0 { (a.lo, a.hi) } else { (a.hi, a.lo) };
            let p = a.powi(n);
            // a negative power divides by the positive one, whose lower end may overflow
            let divisor_overflowed = n < 0 && pow(a.lo, -n, Round::Down) > f64::MAX;
            prop_assert!(
                holds(p, &pow(lo, n, Round::Down), &pow(hi, n, Round::Up)) || (p.is_nan() && divisor_overflowed),
                "{a:?}^{n} = {p:?}"
            );
        }

        /// `up` and `down` pass a value's neighbours, by a few steps, or by at most 2⁻⁵¹⁰ near
        /// zero.
        #[test]
        fn up_and_down_pass_the_neighbours(r in value().prop_filter("finite", |r| r.is_finite())) {
            prop_assert!(passes_up(r), "{r:e}: {:e}", up(r));
            prop_assert!(passes_down(r), "{r:e}: {:e}", down(r));
        }

        /// A square across zero starts at zero, and is never below it.
        #[test]
        fn squares_are_non_negative(a in interval()) {
            let s = a.powi(2);
            prop_assert!(s.lo >= 0.0);
            if a.lo <= 0.0 && a.hi >= 0.0 { prop_assert_eq!(s.lo, 0.0); }
        }
    }

    #[test]
    fn overflow_and_underflow_stay_enclosed() {
        let max = Outward::point(f64::MAX);
        assert_eq!((max + Outward::point(-1.0)).bounds(), (f64::MAX.next_down().next_down(), f64::INFINITY));
        // the lower end overflowed too: nothing is known of the sum (sound, if not tight)
        assert!((max + max).is_nan());
        assert!((-max - max).is_nan() && (max * max).is_nan());
        let tiny = Outward::point(f64::from_bits(1));
        let t2 = tiny * tiny;
        assert!(t2.lo < 0.0 && t2.hi > 0.0, "{t2:?}");
    }

    #[test]
    fn nothing_known_is_never_a_bound() {
        for r in [
            Outward::NAN + Outward::point(1.0),
            Outward::point(-1.0).sqrt(),
            Outward::NAN * Outward::point(0.0),
            Outward::point(1.0) / Outward::NAN,
            Outward::point(f64::NAN),
            Outward::NAN.abs().max(Outward::point(2.0)),
            Outward::point(2.0).hull(Outward::NAN),
        ] {
            let (lo, hi) = r.bounds();
            assert!(lo.is_nan() && hi.is_nan(), "{r:?}");
        }
        assert_eq!(Outward::NAN.lt(&Outward::point(1.0)), None);
    }

    #[test]
    fn zero_times_infinity_and_zero_divisors_are_the_whole_line() {
        let z = Outward::point(0.0);
        let up = Outward::from_bounds(1.0, f64::INFINITY);
        assert_eq!((Outward::point(-1.0) * up * z).bounds(), (f64::NEG_INFINITY, f64::INFINITY));
        assert_eq!(
            (Outward::point(1.0) / Outward::from_bounds(-1.0, 1.0)).bounds(),
            (f64::NEG_INFINITY, f64::INFINITY)
        );
    }

    #[test]
    fn transcendental_functions_enclose_their_values() {
        let x = Outward::from_bounds(0.5, 0.75);
        let e = x.exp();
        assert!(e.lo <= 0.5f64.exp() && 0.75f64.exp() <= e.hi && e.hi - e.lo < 0.5);
        assert!(Outward::point(-1.0).ln().is_nan());
    }

    #[test]
    fn the_width_is_a_few_ulps() {
        let third = Outward::point(1.0) / Outward::point(3.0);
        assert!((2..=4).contains(&(third.hi.to_bits() - third.lo.to_bits())), "{third:?}");
    }

    #[test]
    fn up_and_down_pass_the_neighbours_of_special_values() {
        let tiny = f64::from_bits(1);
        for r in [0.0, -0.0, tiny, -tiny, f64::MIN_POSITIVE, 1.0, -1.0, 0.5 - f64::EPSILON / 4.0, f64::MAX, -f64::MAX] {
            assert!(passes_up(r), "{r:e}: {:e}", up(r));
            assert!(passes_down(r), "{r:e}: {:e}", down(r));
        }
        assert_eq!((up(0.0), down(0.0)), (FLOOR, -FLOOR));
        assert_eq!((up(f64::INFINITY), down(f64::NEG_INFINITY)), (f64::INFINITY, f64::NEG_INFINITY));
        assert!(up(f64::NEG_INFINITY).is_nan() && down(f64::INFINITY).is_nan());
        assert!(up(f64::NAN).is_nan() && down(f64::NAN).is_nan());
    }
}
