//! The cluster kernel on AVX-512: a cluster pair's sixteen body pairs in two registers of eight
//! lanes (rows 0 and 1 of `clusters::rows`'s four, then rows 2 and 3), each cluster pair's
//! formula evaluated one cluster pair ahead of its forces.
//!
//! Why ahead: a cluster pair's work is one long chain — loads, separations, r², the formula's
//! division (some twenty cycles' latency, by instruction tables), its products, the forces that
//! need them — and, as far as timings can tell without performance counters, the CPU's
//! scheduler holds too few waiting instructions to overlap two chains: twice the lanes in a
//! register gained 2%, a shorter-throughput division by reciprocal and Newton steps lost. With
//! the formula of pair q + 1 issued before the forces of pair q, the forces find their inputs
//! ready while the next division runs: 300 steps of lj_32k 1.51 → 1.32 s on one thread (Intel
//! Xeon, 2026-12-07), the divider now the bound (two eight-lane divisions a cluster pair).
//!
//! The same bits as `clusters::portable`: every lane is its pair's formula, the lanes outside
//! the reach are +0 as the portable kernel masks them, and the forces and sums are added in the
//! portable kernel's order — cluster pairs in list order; within one, the j-forces and sums of
//! even rows and odd rows apart, then together. A test holds the two equal, bit for bit.

use super::clusters::{Pulled, Traits, ENERGY, FORCES_ONLY, OWNED_ENERGY, OWNED_VIRIAL, VIRIAL};
use super::{Jet, Paired};
use crate::lanes::{norm2, F64x4, Lane};
use crate::lanes8::F64x8;
use crate::neighbours::{Cluster, Neighbours, Pair, CENTRE};
use crate::sum::Sum;
use std::ops::Range;

/// On a cluster's pairs with itself, body a meets only the slots after it (`clusters::after`),
/// for rows 0 and 1, then rows 2 and 3.
const AFTER: [u8; 2] = [0b1100_1110, 0b0000_1000];

/// `clusters::kernel` for a CPU with AVX-512: the same arguments, the same result, bit for bit.
///
/// # Safety
/// The CPU must have AVX-512F (and AVX2 and FMA, which every CPU with it has).
#[target_feature(enable = "avx2,fma,avx512f")]
#[inline(never)]
pub(super) unsafe fn kernel<T: Paired, const SUM: u8>(
    l: &Neighbours,
    row: &T::Row,
    (traits, shares): (&[Traits], &[F64x4]),
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> Sum {
    let zero = F64x8::splat(0.0);
    let mut energy = Sum::default();
    let base = range.start;
    for ic in range {
        let xi = &l.x[ic];
        let xi = [0, 2].map(|a| [0, 1, 2].map(|c| F64x8::rows(xi[c], a)));
        let i = I { ic, xi: &xi, traits };
        let mut fi = [[zero; 3]; 2];
        let mut e = zero;
        let listed = l.start[ic]..l.start[ic + 1];
        let (pairs, place) = (&l.pairs[listed.clone()], &place[listed]);
        if let Some(first) = pairs.first() {
            let mut next = i.evaluate::<T>(l, row, first);
            for (q, (p, &at)) in pairs.iter().zip(place).enumerate() {
                let now = next;
                if let Some(after) = pairs.get(q + 1) {
                    next = i.evaluate::<T>(l, row, after);
                }
                let mut fj = [zero; 3];
                for h in 0..2 {
                    for c in 0..3 {
                        fi[h][c] = now.d[h][c].mul_add(now.s[h], fi[h][c]);
                        fj[c] = now.d[h][c].mul_neg_add(now.s[h], fj[c]);
                    }
                    // (a share of 1 rounds as the plain sums do: a domain owning every body gives their bits)
                    let share = || (F64x8::rows(shares[ic], 2 * h) + F64x8::twice(shares[p.j()])) * 0.5;
                    match SUM {
                        ENERGY => e = e + now.v[h],
                        VIRIAL => e = e + now.s[h] * now.r2[h],
                        OWNED_ENERGY => e = now.v[h].mul_add(share(), e),
                        OWNED_VIRIAL => e = (now.s[h] * now.r2[h]).mul_add(share(), e),
                        _ => {}
                    }
                }
                add_j(&fj, &mut f[at as usize]);
            }
        }
        add_i(&fi, &mut f[ic - base]);
        if SUM != FORCES_ONLY {
            let [even, odd] = e.halves();
            energy.add((even + odd).sum());
        }
    }
    energy
}

/// One cluster pair's separations (j minus i, rows 0 and 1, then rows 2 and 3, by axis), r²,
/// and the formula's V and s there, +0 outside the reach.
#[derive(Clone, Copy)]
struct Evaluated {
    d: [[F64x8; 3]; 2],
    r2: [F64x8; 2],
    v: [F64x8; 2],
    s: [F64x8; 2],
}

/// The i-cluster: its index, its bodies in rows (`F64x8::rows`), and the bodies' traits.
struct I<'a> {
    ic: usize,
    xi: &'a [[F64x8; 3]; 2],
    traits: &'a [Traits],
}

impl I<'_> {
    /// The formula on the sixteen pairs of the i-cluster with listed pair `p`'s j-cluster.
    #[inline(always)]
    fn evaluate<T: Paired>(&self, l: &Neighbours, row: &T::Row, p: &Pair) -> Evaluated {
        let (d, r2, inside) = self.near(l, p, T::reach2(row));
        // Masked lanes may hold an infinity or a NaN (a slot against itself): `keep` clears
        // them. An unmasked one (two bodies at one point) makes the forces non-finite, which
        // the caller finds and names.
        let (mq0, c0) = self.pair_traits::<T>(p.j(), 0);
        let (mq1, c1) = self.pair_traits::<T>(p.j(), 2);
        let (v0, s0) = T::radial(row, r2[0], mq0, c0);
        let (v1, s1) = T::radial(row, r2[1], mq1, c1);
        let (v, s) = ([v0.keep(inside[0]), v1.keep(inside[1])], [s0.keep(inside[0]), s1.keep(inside[1])]);
        Evaluated { d, r2, v, s }
    }

    /// `clusters::pair_traits` for rows a and a + 1 against cluster `jc`: [mᵢ, mⱼ, qᵢ, qⱼ] and
    /// cᵢ·cⱼ, zeros (and no loads) if the term reads none.
    #[inline(always)]
    fn pair_traits<T: Paired>(&self, jc: usize, a: usize) -> ([F64x8; 4], F64x8) {
        let zero = F64x8::splat(0.0);
        if !(T::BODIES || T::COLOUR) {
            return ([zero; 4], zero);
        }
        let (i, j) = (&self.traits[self.ic], &self.traits[jc]);
        let mq = [F64x8::rows(i.m, a), F64x8::twice(j.m), F64x8::rows(i.q, a), F64x8::twice(j.q)];
        (mq, F64x8::twice(j.c[0]) * F64x8::rows(i.c[0], a) + F64x8::twice(j.c[1]) * F64x8::rows(i.c[1], a))
    }
}

impl I<'_> {
    /// The separations (j minus i, rows 0 and 1, then rows 2 and 3, by axis) of the i-cluster's
    /// bodies from listed pair `p`'s j-cluster, their r², and the lanes within `reach2` (on a
    /// cluster's pairs with itself, only the slots after each body). Loops, not arrays' `map`:
    /// a closure outside the AVX-512 function calls every intrinsic in it (300 steps of lj_32k
    /// 1.37 -> 1.52 s when this and `add_i` had them).
    #[inline(always)]
    fn near(&self, l: &Neighbours, p: &Pair, reach2: f64) -> ([[F64x8; 3]; 2], [F64x8; 2], [u8; 2]) {
        let (xj, sh) = (&l.x[p.j()], &l.shifts[p.image()]);
        let (mut d, mut r2, mut inside) = ([[F64x8::splat(0.0); 3]; 2], [F64x8::splat(0.0); 2], [0; 2]);
        // (empty slots sit beyond every cutoff: `Neighbours::x`)
        let diagonal = p.j() == self.ic && p.image() == CENTRE;
        let reach2 = F64x8::splat(reach2);
        let xs = [F64x8::twice(xj[0] + sh[0]), F64x8::twice(xj[1] + sh[1]), F64x8::twice(xj[2] + sh[2])];
        for h in 0..2 {
            for c in 0..3 {
                d[h][c] = xs[c] - self.xi[h][c];
            }
            r2[h] = norm2(&d[h]);
            inside[h] = r2[h].below(reach2) & if diagonal { AFTER[h] } else { u8::MAX };
        }
        (d, r2, inside)
    }
}

/// Adds a j-cluster's sums (rows 0 and 1, then rows 2 and 3, by axis) to its forces: even rows
/// and odd rows apart, then together, the portable kernel's order.
#[inline(always)]
fn add_j(w: &[F64x8; 3], out: &mut Cluster) {
    for c in 0..3 {
        let [even, odd] = w[c].halves();
        out[c] = out[c] + (even + odd);
    }
}

/// Adds the i-cluster's sums to its forces, row a's lanes being half a % 2 of register a / 2,
/// each row summed as `F64x4::sum` sums it.
#[inline(always)]
fn add_i(fi: &[[F64x8; 3]; 2], out: &mut Cluster) {
    for c in 0..3 {
        let ([r0, r1], [r2, r3]) = (fi[0][c].halves(), fi[1][c].halves());
        out[c] = out[c] + F64x4::new([r0.sum(), r1.sum(), r2.sum(), r3.sum()]);
    }
}

/// `clusters::pullback` for a CPU with AVX-512, the jet of each cluster pair taken one pair ahead
/// of its products with g: the same arguments, the same result, bit for bit. A row with no
/// pair inside the reach adds nothing, as in the portable pullback, which skips it: here its
/// lanes are left out of every sum by a mask.
///
/// # Safety
/// The CPU must have AVX-512F (and AVX2 and FMA, which every CPU with it has).
#[target_feature(enable = "avx2,fma,avx512f")]
#[inline(never)]
pub(super) unsafe fn pullback<T: Paired, const POTENTIAL: bool>(
    l: &Neighbours,
    at: &Pulled<T::Row>,
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> [Sum; 3] {
    let zero = F64x8::splat(0.0);
    let mut params = [Sum::default(), Sum::default(), Sum::default()];
    let base = range.start;
    // the wanted parameters as flags over a fixed three, so that their sums stay in registers
    // (indexed by the list `wanted`, they lived on the stack; a gradient of lj_32k 1.97 -> 1.89 s)
    let want: [bool; 3] = std::array::from_fn(|w| at.wanted.contains(&w));
    for ic in range {
        let xi = &l.x[ic];
        let xi = [0, 2].map(|a| [0, 1, 2].map(|c| F64x8::rows(xi[c], a)));
        let i = I { ic, xi: &xi, traits: &[] };
        let mut fi = [[zero; 3]; 2];
        let mut dp = [zero; 3];
        let listed = l.start[ic]..l.start[ic + 1];
        let (pairs, place) = (&l.pairs[listed.clone()], &place[listed]);
        if let Some(first) = pairs.first() {
            let mut next = i.jets::<T>(l, at, first);
            for (q, (p, &slot)) in pairs.iter().zip(place).enumerate() {
                let now = next;
                if let Some(after) = pairs.get(q + 1) {
                    next = i.jets::<T>(l, at, after);
                }
                let mut wj = [zero; 3];
                for h in 0..2 {
                    let (d, jet, inside, on) = (&now.d[h], &now.jet[h], now.inside[h], now.rows[h]);
                    let s = jet.s.keep(inside);
                    if POTENTIAL {
                        for c in 0..3 {
                            wj[c] = wj[c].mul_add_on(on, s, d[c]);
                            fi[h][c] = fi[h][c].mul_sub_on(on, d[c], s);
                        }
                        for w in 0..3 {
                            if want[w] {
                                dp[w] = dp[w].add_on(on, jet.dv[w].keep(inside));
                            }
                        }
                        continue;
                    }
                    let (gi, gj) = (&at.g[ic], &at.g[p.j()]);
                    let dg = [0, 1, 2].map(|c| F64x8::rows(gi[c], 2 * h) - F64x8::twice(gj[c]));
                    let along = dg[2].mul_add(d[2], dg[1].mul_add(d[1], dg[0] * d[0]));
                    let sa = jet.s_r.keep(inside) * along;
                    for c in 0..3 {
                        let w = s.mul_add(dg[c], sa * d[c]);
                        wj[c] = wj[c].add_on(on, w);
                        fi[h][c] = fi[h][c].sub_on(on, w);
                    }
                    for w in 0..3 {
                        if want[w] {
                            dp[w] = dp[w].mul_add_on(on, jet.ds[w].keep(inside), along);
                        }
                    }
                }
                add_j(&wj, &mut f[slot as usize]);
            }
        }
        add_i(&fi, &mut f[ic - base]);
        for &w in at.wanted {
            let [even, odd] = dp[w].halves();
            params[w].add((even + odd).sum());
        }
    }
    params
}

/// One cluster pair's separations and jets (rows 0 and 1, then rows 2 and 3), the lanes inside
/// the reach, and the lanes of the rows with a pair inside (a whole row of four, or none).
#[derive(Clone, Copy)]
struct Jets {
    d: [[F64x8; 3]; 2],
    jet: [Jet<F64x8>; 2],
    inside: [u8; 2],
    rows: [u8; 2],
}

impl I<'_> {
    /// The jets of the sixteen pairs of the i-cluster with listed pair `p`'s j-cluster.
    #[inline(always)]
    fn jets<T: Paired>(&self, l: &Neighbours, at: &Pulled<T::Row>, p: &Pair) -> Jets {
        let (d, r2, inside) = self.near(l, p, at.reach2);
        let row = |m: u8, half: u8| if m & half != 0 { half } else { 0 };
        let rows = inside.map(|m| row(m, 0x0f) | row(m, 0xf0));
        let jet0 = T::jet(at.row, at.p, r2[0]).expect("a jet for every instance");
        let jet1 = T::jet(at.row, at.p, r2[1]).expect("a jet for every instance");
        Jets { d, jet: [jet0, jet1], inside, rows }
    }
}
