//! The cluster-pair kernel: for each listed pair of clusters (`neighbours`), the sixteen body
//! pairs as four rows of four lanes — body a of the i-cluster broadcast against the j-cluster's
//! four — through the term's one radial formula (`Paired::radial` on `F64x4`). The cutoff, the
//! empty slots and, on a cluster's pairs with itself, the lower triangle are masks, not
//! branches. A j-cluster's forces are one vector update per cluster pair; an i-body's lanes are
//! added once, after all its cluster's pairs (Newton's third law throughout).
//!
//! The order of every sum is fixed by the list, so the forces are the same bits for any number
//! of threads; lane k of every row is bit for bit the scalar formula on that pair.

use super::{Frame, Paired};
use crate::lanes::{norm2, F64x4, Lane, Mask4};
use crate::neighbours::{Cluster, Neighbours, CENTRE, EMPTY, LANES};
use crate::sum::Sum;
use std::ops::Range;

/// On a cluster's pairs with itself (zero image), body a meets only the slots after it.
fn after(a: usize) -> Mask4 {
    Mask4::new(std::array::from_fn(|b| b > a))
}

/// What a term reads of the bodies besides their positions, by cluster: masses, charges and the
/// two colour components, for the terms that read them (`Paired::BODIES`, `COLOUR`).
#[derive(Clone, Copy, Default)]
pub struct Traits {
    pub(super) m: F64x4,
    pub(super) q: F64x4,
    pub(super) c: [F64x4; 2],
}

/// Gathers the bodies' traits by cluster, if the term reads any (else nothing).
pub fn traits<T: Paired>(l: &Neighbours, s: &Frame) -> Vec<Traits> {
    if !(T::BODIES || T::COLOUR) {
        return vec![];
    }
    l.bodies
        .chunks(LANES)
        .map(|slots| {
            let of = |get: &dyn Fn(usize) -> f64| {
                F64x4::new(std::array::from_fn(|k| if slots[k] == EMPTY { 0.0 } else { get(slots[k] as usize) }))
            };
            Traits { m: of(&|b| s.m[b]), q: of(&|b| s.q[b]), c: [of(&|b| s.c[b][0]), of(&|b| s.c[b][1])] }
        })
        .collect()
}

/// What the kernel sums besides the forces (its `SUM`): nothing, the pairs' potential energy, or
/// their Σ s·r² (s the force over the distance: the virial's pair sum, −W).
pub const FORCES_ONLY: u8 = 0;
pub const ENERGY: u8 = 1;
pub const VIRIAL: u8 = 2;
/// The two sums each pair weighted by its bodies' mean share (`shares`): a rank's part of a
/// system cut into domains, owned bodies' share 1, ghosts' 0, so a pair across two ranks counts
/// half on each.
pub const OWNED_ENERGY: u8 = 3;
pub const OWNED_VIRIAL: u8 = 4;

/// Each slot's share for the `OWNED_*` sums, by cluster: 1 for a body below `owned`, 0 for the
/// others and the empty slots.
pub fn shares(l: &Neighbours, owned: usize) -> Vec<F64x4> {
    let share = |b: u32| if b != EMPTY && (b as usize) < owned { 1.0 } else { 0.0 };
    l.bodies.chunks(LANES).map(|slots| F64x4::new(std::array::from_fn(|k| share(slots[k])))).collect()
}

/// Row `row`'s forces over the i-clusters `range` added to `f`, a piece's buffer (i-cluster
/// `ic` at `ic - range.start`, listed pair q's j-cluster at `place[q]`: `pieces`), and the sum
/// `SUM` asks for: plain within an i-cluster's pairs, compensated across clusters. Where the CPU has
/// AVX-512 (detected at run time), two rows a register with each cluster pair's formula one
/// pair ahead of its forces (`pipelined::kernel`): the same bits.
pub fn kernel<T: Paired, const SUM: u8>(
    l: &Neighbours,
    row: &T::Row,
    (traits, shares): (&[Traits], &[F64x4]),
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> Sum {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has the features `pipelined::kernel` is compiled for, checked just above.
        return unsafe { super::pipelined::kernel::<T, SUM>(l, row, (traits, shares), range, place, f) };
    }
    portable::<T, SUM>(l, row, (traits, shares), range, place, f)
}

#[inline(always)]
fn portable<T: Paired, const SUM: u8>(
    l: &Neighbours,
    row: &T::Row,
    (traits, shares): (&[Traits], &[F64x4]),
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> Sum {
    let zero = F64x4::splat(0.0);
    let mut energy = Sum::default();
    let base = range.start;
    for ic in range {
        let mut fi = [[zero; 3]; LANES];
        let mut e = [zero; 2];
        let listed = l.start[ic]..l.start[ic + 1];
        for (p, &at) in l.pairs[listed.clone()].iter().zip(&place[listed]) {
            let jc = p.j();
            let fj = &mut f[at as usize];
            // a cluster with itself at the zero image: each pair once, the lower triangle masked
            // (a separate instance, so that every other pair goes without the mask)
            if jc == ic && p.image() == CENTRE {
                rows::<T, SUM, true>(l, row, (traits, shares), (ic, jc, p.image()), &mut fi, &mut e, fj);
            } else {
                rows::<T, SUM, false>(l, row, (traits, shares), (ic, jc, p.image()), &mut fi, &mut e, fj);
            }
        }
        for c in 0..3 {
            f[ic - base][c] = f[ic - base][c] + F64x4::new(std::array::from_fn(|a| fi[a][c].sum()));
        }
        if SUM != FORCES_ONLY {
            energy.add((e[0] + e[1]).sum());
        }
    }
    energy
}

/// One cluster pair's sixteen body pairs, as four rows: body a of the i-cluster against the
/// j-cluster's four lanes; its forces into `fi` and `fj`, its energy or s·r² into `e`. The
/// j-forces and the sums are accumulated by the rows' parity, even rows in one register and odd
/// in another, added at the end: the order in which the AVX-512 build (`pipelined`), holding
/// two rows a register, adds them, so that both give the same bits.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn rows<T: Paired, const SUM: u8, const DIAGONAL: bool>(
    l: &Neighbours,
    row: &T::Row,
    (traits, shares): (&[Traits], &[F64x4]),
    (ic, jc, image): (usize, usize, usize),
    fi: &mut [[F64x4; 3]; LANES],
    e: &mut [F64x4; 2],
    fj_out: &mut Cluster,
) {
    let rc2 = F64x4::splat(T::reach2(row));
    let (xi, xj, sh) = (&l.x[ic], &l.x[jc], &l.shifts[image]);
    let xs = [xj[0] + sh[0], xj[1] + sh[1], xj[2] + sh[2]];
    let mut fj = [[F64x4::splat(0.0); 3]; 2];
    for (a, fa) in fi.iter_mut().enumerate() {
        let (fj, e) = (&mut fj[a % 2], &mut e[a % 2]);
        let d = [xs[0] - xi[0].lane(a), xs[1] - xi[1].lane(a), xs[2] - xi[2].lane(a)];
        let r2 = norm2(&d);
        // (empty slots sit beyond every cutoff: `Neighbours::x`)
        let inside = if DIAGONAL { r2.lt(rc2) & after(a) } else { r2.lt(rc2) };
        // Masked lanes may hold an infinity or a NaN (a slot against itself): the mask clears
        // them. An unmasked one (two bodies at one point) makes the forces non-finite, which the
        // caller finds and names.
        let (mq, colour) = pair_traits::<T>(traits, ic, a, jc);
        let (v, s) = T::radial(row, r2, mq, colour);
        let s = inside.and(s);
        for c in 0..3 {
            fa[c] = d[c].mul_add(s, fa[c]);
            fj[c] = d[c].mul_neg_add(s, fj[c]);
        }
        // (a share of 1 rounds as the plain sums do: a domain owning every body gives their bits)
        let share = || (F64x4::splat(shares[ic].lane(a)) + shares[jc]) * 0.5;
        match SUM {
            ENERGY => *e = *e + inside.and(v),
            VIRIAL => *e = *e + s * r2,
            OWNED_ENERGY => *e = inside.and(v).mul_add(share(), *e),
            OWNED_VIRIAL => *e = (s * r2).mul_add(share(), *e),
            _ => {}
        }
    }
    for c in 0..3 {
        fj_out[c] = fj_out[c] + (fj[0][c] + fj[1][c]);
    }
}

/// What one instance's pullback through the cluster list reads: its row and parameters, its
/// reach², which parameters' adjoints are wanted, and the covector g by cluster (as `Neighbours::x`,
/// zeros in empty slots; empty for the potential's gradient, which reads none).
pub struct Pulled<'a, R> {
    pub row: &'a R,
    pub p: &'a [f64],
    pub reach2: f64,
    pub wanted: &'a [usize],
    pub g: &'a [Cluster],
}

/// The transpose of the forces' derivatives applied to g, over the i-clusters `range`, four
/// pairs at a time with the hand-derived jets (`Paired::jet` on `F64x4`): each pair's
/// w = s·Δg + s_r (Δg·d) d, Δg = gᵢ − gⱼ, added to j and taken from i in `f` (a piece's buffer,
/// placed as in `kernel`), and ∂s/∂p (Δg·d) to the wanted parameters' sums. With `POTENTIAL`,
/// the gradient of the energy instead (g unread): w = s·d, and ∂V/∂p. Pairs beyond the reach,
/// empty slots and a cluster's lower triangle with itself are masked, as in `kernel`.
/// The term's jet must exist (`Pairs::jets_everywhere`). Where the CPU has AVX-512, two rows a
/// register with each cluster pair's jet one pair ahead (`pipelined::pullback`), as `kernel`:
/// the same bits, for which the j-sums and the parameters' sums here are kept by the rows'
/// parity, as in `rows`.
pub fn pullback<T: Paired, const POTENTIAL: bool>(
    l: &Neighbours,
    at: &Pulled<T::Row>,
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> [Sum; 3] {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has the features `pipelined::pullback` is compiled for, checked just above.
        return unsafe { super::pipelined::pullback::<T, POTENTIAL>(l, at, range, place, f) };
    }
    portable_pullback::<T, POTENTIAL>(l, at, range, place, f)
}

#[inline(always)]
fn portable_pullback<T: Paired, const POTENTIAL: bool>(
    l: &Neighbours,
    at: &Pulled<T::Row>,
    range: Range<usize>,
    place: &[u32],
    f: &mut [Cluster],
) -> [Sum; 3] {
    let zero = F64x4::splat(0.0);
    let reach2 = F64x4::splat(at.reach2);
    let mut params = [Sum::default(), Sum::default(), Sum::default()];
    let base = range.start;
    for ic in range {
        let mut fi = [[zero; 3]; LANES];
        let mut dp = [[zero; 2]; 3];
        let listed = l.start[ic]..l.start[ic + 1];
        for (p, &slot) in l.pairs[listed.clone()].iter().zip(&place[listed]) {
            let (jc, image) = (p.j(), p.image());
            let (xi, xj, sh) = (&l.x[ic], &l.x[jc], &l.shifts[image]);
            let xs = [xj[0] + sh[0], xj[1] + sh[1], xj[2] + sh[2]];
            let mut wj = [[zero; 3]; 2];
            for (a, fa) in fi.iter_mut().enumerate() {
                let wj = &mut wj[a % 2];
                let d = [xs[0] - xi[0].lane(a), xs[1] - xi[1].lane(a), xs[2] - xi[2].lane(a)];
                let r2 = norm2(&d);
                let inside = if jc == ic && image == CENTRE { r2.lt(reach2) & after(a) } else { r2.lt(reach2) };
                // a row with no pair inside adds only zeros: its jet (a division, a dozen
                // products) is skipped. The force's shorter row does not repay the branch: the
                // same test there made 200 steps of lj_32k 1.40 → 1.80 s; here it cut the
                // gradient 3.14 → 2.86 s
                if !inside.any() {
                    continue;
                }
                let jet = T::jet(at.row, at.p, r2).expect("a jet for every instance");
                if POTENTIAL {
                    let s = inside.and(jet.s);
                    for c in 0..3 {
                        wj[c] = s.mul_add(d[c], wj[c]);
                        fa[c] = d[c].mul_neg_add(s, fa[c]);
                    }
                    for &w in at.wanted {
                        dp[w][a % 2] = dp[w][a % 2] + inside.and(jet.dv[w]);
                    }
                    continue;
                }
                let (s, s_r) = (inside.and(jet.s), inside.and(jet.s_r));
                let (gi, gj) = (&at.g[ic], &at.g[jc]);
                let dg = [
                    F64x4::splat(gi[0].lane(a)) - gj[0],
                    F64x4::splat(gi[1].lane(a)) - gj[1],
                    F64x4::splat(gi[2].lane(a)) - gj[2],
                ];
                let along = dg[2].mul_add(d[2], dg[1].mul_add(d[1], dg[0] * d[0]));
                let sa = s_r * along;
                for c in 0..3 {
                    let w = s.mul_add(dg[c], sa * d[c]);
                    wj[c] = wj[c] + w;
                    fa[c] = fa[c] - w;
                }
                for &w in at.wanted {
                    dp[w][a % 2] = inside.and(jet.ds[w]).mul_add(along, dp[w][a % 2]);
                }
            }
            for c in 0..3 {
                f[slot as usize][c] = f[slot as usize][c] + (wj[0][c] + wj[1][c]);
            }
        }
        for c in 0..3 {
            f[ic - base][c] = f[ic - base][c] + F64x4::new(std::array::from_fn(|a| fi[a][c].sum()));
        }
        for &w in at.wanted {
            params[w].add((dp[w][0] + dp[w][1]).sum());
        }
    }
    params
}

/// [mᵢ, mⱼ, qᵢ, qⱼ] and cᵢ·cⱼ for body a of cluster `ic` against cluster `jc`'s four, if the
/// term reads them (zeros, and no loads, if not).
#[inline(always)]
fn pair_traits<T: Paired>(traits: &[Traits], ic: usize, a: usize, jc: usize) -> ([F64x4; 4], F64x4) {
    let zero = F64x4::splat(0.0);
    if !(T::BODIES || T::COLOUR) {
        return ([zero; 4], zero);
    }
    let (i, j) = (&traits[ic], &traits[jc]);
    let mq = [F64x4::splat(i.m.lane(a)), j.m, F64x4::splat(i.q.lane(a)), j.q];
    let colour = j.c[0] * i.c[0].lane(a) + j.c[1] * i.c[1].lane(a);
    (mq, colour)
}

#[cfg(test)]
mod tests;
