//! The cluster kernels' tests: each pair term's formula in lanes against the scalar one, the
//! kernel against the scalar sum's rounding bound, and the AVX-512 kernels against the portable
//! ones, bit for bit.

use super::super::{coulomb_reaction_field, lennard_jones, qcd_coulomb, wca, yukawa};
use super::*;
use crate::forces::dual::Rng;
use lagra_checker::model::Cell;

/// The whole list as one piece: each pair's j-cluster at its own index.
fn whole(l: &Neighbours) -> Vec<u32> {
    l.pairs.iter().map(|p| p.j() as u32).collect()
}

/// Lane k of the four-lane formula is the scalar formula at lane k's r², bit for bit, for
/// every pair term.
fn lanes_are_the_scalar_formula<T: Paired>(p: &[f64], far: f64) {
    let row = T::row(p);
    let mut rng = Rng::new(9);
    for _ in 0..1000 {
        let r2 = F64x4::new(std::array::from_fn(|_| rng.uniform(0.05, far).powi(2)));
        let mq: [F64x4; 4] = std::array::from_fn(|_| F64x4::new(std::array::from_fn(|_| rng.uniform(-2.0, 2.0))));
        let colour = F64x4::new(std::array::from_fn(|_| rng.uniform(-1.0, 1.0)));
        let (v, s) = T::radial(&row, r2, mq, colour);
        for k in 0..LANES {
            let (v1, s1) = T::radial(&row, r2.lane(k), mq.map(|m| m.lane(k)), colour.lane(k));
            assert_eq!((v.lane(k).to_bits(), s.lane(k).to_bits()), (v1.to_bits(), s1.to_bits()));
        }
    }
}

/// The same for the AVX-512 kernel's eight lanes (`lanes8`), where the CPU has them.
#[cfg(target_arch = "x86_64")]
fn eight_lanes_are_the_scalar_formula<T: Paired>(p: &[f64], far: f64) {
    use crate::lanes8::F64x8;
    if !std::is_x86_feature_detected!("avx512f") {
        return;
    }
    let row = T::row(p);
    let mut rng = Rng::new(10);
    for _ in 0..1000 {
        let mut draw = |lo: f64, hi: f64| F64x8::new(std::array::from_fn(|_| rng.uniform(lo, hi)));
        let r = draw(0.05, far);
        let r2 = r * r;
        let mq: [F64x8; 4] = std::array::from_fn(|_| draw(-2.0, 2.0));
        let colour = draw(-1.0, 1.0);
        let (v, s) = T::radial(&row, r2, mq, colour);
        let (v, s, r2) = (v.to_array(), s.to_array(), r2.to_array());
        let (mq, colour) = (mq.map(F64x8::to_array), colour.to_array());
        for k in 0..8 {
            let (v1, s1) = T::radial(&row, r2[k], mq.map(|m| m[k]), colour[k]);
            assert_eq!((v[k].to_bits(), s[k].to_bits()), (v1.to_bits(), s1.to_bits()));
        }
    }
}

#[test]
#[cfg(target_arch = "x86_64")]
fn every_pair_term_is_one_formula_in_eight_lanes_too() {
    eight_lanes_are_the_scalar_formula::<lennard_jones::Plain>(&[1.0, 1.0, 2.5], 3.0);
    eight_lanes_are_the_scalar_formula::<lennard_jones::Shifted>(&[1.2, 0.9, 2.5], 3.0);
    eight_lanes_are_the_scalar_formula::<lennard_jones::ForceShifted>(&[0.8, 1.1, 3.0], 3.0);
    eight_lanes_are_the_scalar_formula::<wca::Fast>(&[1.0, 1.0], 1.2);
    eight_lanes_are_the_scalar_formula::<coulomb_reaction_field::Fast>(&[1.0, 2.0, 78.0], 2.5);
    eight_lanes_are_the_scalar_formula::<yukawa::Fast>(&[1.0, 1.5], 5.0);
    eight_lanes_are_the_scalar_formula::<super::super::coulomb::Fast>(&[1.0], 5.0);
    eight_lanes_are_the_scalar_formula::<super::super::gravity::Fast>(&[1.0], 5.0);
    eight_lanes_are_the_scalar_formula::<super::super::nuclear_yukawa::Fast>(&[1.0, 2.0], 5.0);
    eight_lanes_are_the_scalar_formula::<qcd_coulomb::Fast>(&[0.3, 0.2], 5.0);
}

#[test]
fn every_pair_term_is_one_formula_in_one_lane_or_four() {
    lanes_are_the_scalar_formula::<lennard_jones::Plain>(&[1.0, 1.0, 2.5], 3.0);
    lanes_are_the_scalar_formula::<lennard_jones::Shifted>(&[1.2, 0.9, 2.5], 3.0);
    lanes_are_the_scalar_formula::<lennard_jones::ForceShifted>(&[0.8, 1.1, 3.0], 3.0);
    lanes_are_the_scalar_formula::<wca::Fast>(&[1.0, 1.0], 1.2);
    lanes_are_the_scalar_formula::<coulomb_reaction_field::Fast>(&[1.0, 2.0, 78.0], 2.5);
    lanes_are_the_scalar_formula::<yukawa::Fast>(&[1.0, 1.5], 5.0);
    lanes_are_the_scalar_formula::<super::super::coulomb::Fast>(&[1.0], 5.0);
    lanes_are_the_scalar_formula::<super::super::gravity::Fast>(&[1.0], 5.0);
    lanes_are_the_scalar_formula::<super::super::nuclear_yukawa::Fast>(&[1.0, 2.0], 5.0);
    lanes_are_the_scalar_formula::<qcd_coulomb::Fast>(&[0.3, 0.2], 5.0);
}

/// A random liquid-like box and a list over it.
fn liquid(n: usize, seed: u64) -> (Vec<[f64; 3]>, Option<Cell>, Neighbours) {
    let mut rng = Rng::new(seed);
    let side = (n as f64 / 0.8).cbrt();
    let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
    // a jittered lattice, so that no two bodies come unphysically close
    let k = (n as f64).cbrt().ceil() as usize;
    let x: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let g = [i % k, (i / k) % k, i / (k * k)];
            std::array::from_fn(|a| (g[a] as f64 + rng.uniform(-0.2, 0.2)) * side / k as f64)
        })
        .collect();
    let mut l = Neighbours::new(&cell, 2.5).unwrap();
    l.update(&x, &cell, None);
    (x, cell, l)
}

/// The kernel's forces and energy against the scalar formula summed pair by pair over the
/// same list: the same pairs, summed in another order, so equal to within the summation
/// bound |error| ≤ 2(n − 1)ε Σ|terms| per body (n its pairs), held here with n = 200.
#[test]
fn the_kernel_is_the_scalar_sum_within_its_rounding_bound() {
    let (x, _, l) = liquid(1000, 4);
    let p = [1.0, 1.0, 2.5];
    let row = lennard_jones::Shifted::row(&p);
    let mut f = vec![[F64x4::default(); 3]; l.clusters()];
    let e = kernel::<lennard_jones::Shifted, ENERGY>(&l, &row, (&[], &[]), 0..l.clusters(), &whole(&l), &mut f).value();
    let (mut scalar, mut size, mut es) = (vec![[0.0; 3]; x.len()], vec![0.0; x.len()], 0.0);
    l.each_pair::<()>(|i, j, d| {
        let (a, v) = lennard_jones::Shifted::eval(&row, d, [0.0; 4], 0.0).unwrap();
        for c in 0..3 {
            scalar[i][c] += a[c];
            scalar[j][c] -= a[c];
        }
        let m = a[0].abs() + a[1].abs() + a[2].abs();
        size[i] += m;
        size[j] += m;
        es += v;
        Ok(())
    })
    .unwrap();
    let mut worst = 0.0f64;
    for (slot, &b) in l.bodies.iter().enumerate() {
        if b != EMPTY {
            let b = b as usize;
            for c in 0..3 {
                let off = (f[slot / LANES][c].lane(slot % LANES) - scalar[b][c]).abs();
                worst = worst.max(off / (size[b] * f64::EPSILON));
            }
        }
    }
    assert!(worst < 400.0, "{worst} ulps of the pair forces' size");
    assert!(worst > 0.0, "the orders differ, so some bits should");
    assert!((e - es).abs() < 1e-12 * es.abs(), "{e} vs {es}");
}

/// A sparse gas in a small box periodic along x (side 10.17 against a list reach of 2.8),
/// whose clusters span wide columns and are listed against their own images: the kernel's energy
/// is that of the pairs within the cutoff and no more. (Empty slots 4 r apart along x met
/// their neighbours' images one box over here, within the cutoff: a phantom pair's energy.)
#[test]
fn a_small_sparse_box_has_no_pair_of_empty_slots() {
    let side = 10.17;
    let row = lennard_jones::Shifted::row(&[1.0, 1.0, 2.5]);
    for seed in 0..400 {
        let mut rng = Rng::new(seed);
        // periodic along x, and along y and z or not
        let periodic = [true, seed % 2 == 0, seed % 4 < 2];
        let cell = Some(Cell { size: [side; 3], periodic });
        // bodies no closer than 0.9, so that no pair's energy drowns a phantom's
        let mut x: Vec<[f64; 3]> = vec![];
        while x.len() < 64 + seed as usize % 100 {
            // (spread over three box lengths: along an open axis the columns are then few
            // and wide, and a cluster can span the box along x)
            let p: [f64; 3] = std::array::from_fn(|_| rng.uniform(-side, 2.0 * side));
            let close = x.iter().any(|q| norm2(&Cell::image(&cell, std::array::from_fn(|a| p[a] - q[a]))) < 0.81);
            if !close {
                x.push(p);
            }
        }
        let mut l = Neighbours::new(&cell, 2.5).unwrap();
        l.update(&x, &cell, None);
        let mut f = vec![[F64x4::default(); 3]; l.clusters()];
        let e =
            kernel::<lennard_jones::Shifted, ENERGY>(&l, &row, (&[], &[]), 0..l.clusters(), &whole(&l), &mut f).value();
        let (mut pairs, mut size) = (0.0, 0.0);
        crate::traverse::pairs::<()>(&x, &cell, None, |_, _, d| {
            let v = lennard_jones::Shifted::eval(&row, d, [0.0; 4], 0.0).unwrap().1;
            (pairs, size) = (pairs + v, size + v.abs());
            Ok(())
        })
        .unwrap();
        assert!((e - pairs).abs() <= 1e-12 * size, "seed {seed}: the list's {e} against the pairs' {pairs}");
    }
}

/// The AVX-512 kernel (`pipelined`: two rows a register, each cluster pair's formula one
/// pair ahead of its forces) gives the portable kernel's bits, forces and every sum, for
/// terms with and without a shift and with charges.
#[test]
#[cfg(target_arch = "x86_64")]
fn the_pipelined_kernel_gives_the_portable_bits() {
    if !std::is_x86_feature_detected!("avx512f") {
        eprintln!("no AVX-512 on this CPU: the portable kernel is the only one");
        return;
    }
    fn run<T: Paired, const SUM: u8>(l: &Neighbours, p: &[f64], traits: &[Traits], wide: bool) -> (Vec<u64>, u64) {
        let row = T::row(p);
        let traits = if T::BODIES || T::COLOUR { traits } else { &[] };
        // every other cluster owned, for the OWNED_* sums
        let shares: Vec<F64x4> = (0..l.clusters()).map(|c| F64x4::splat((c % 2) as f64)).collect();
        let mut f = vec![[F64x4::default(); 3]; l.clusters()];
        let e = match wide {
            // SAFETY: the CPU has AVX-512F (the test returned above otherwise)
            true => unsafe {
                super::super::pipelined::kernel::<T, SUM>(
                    l,
                    &row,
                    (traits, &shares),
                    0..l.clusters(),
                    &whole(l),
                    &mut f,
                )
            },
            false => portable::<T, SUM>(l, &row, (traits, &shares), 0..l.clusters(), &whole(l), &mut f),
        };
        (f.iter().flatten().flat_map(|c| c.to_array()).map(f64::to_bits).collect(), e.value().to_bits())
    }
    fn same<T: Paired, const SUM: u8>(l: &Neighbours, p: &[f64], traits: &[Traits], what: &str) {
        let (a, b) = (run::<T, SUM>(l, p, traits, true), run::<T, SUM>(l, p, traits, false));
        assert!(a == b, "{what}, sum {SUM}: the AVX-512 kernel's bits differ");
        assert!(SUM == FORCES_ONLY || a.1 != 0, "{what}: a sum of nothing");
    }
    // charges of either sign, for the terms that read them
    let charged = Traits { m: F64x4::splat(1.0), q: F64x4::new([1.0, -0.5, 0.7, -1.2]), c: [F64x4::default(); 2] };
    for (n, seed) in [(1000, 6), (2000, 7)] {
        let (_, _, l) = liquid(n, seed);
        let traits = vec![charged; l.clusters()];
        let lj = [1.0, 1.0, 2.5];
        same::<lennard_jones::Shifted, FORCES_ONLY>(&l, &lj, &traits, "shifted LJ");
        same::<lennard_jones::Shifted, ENERGY>(&l, &lj, &traits, "shifted LJ");
        same::<lennard_jones::Shifted, VIRIAL>(&l, &lj, &traits, "shifted LJ");
        same::<lennard_jones::Shifted, OWNED_ENERGY>(&l, &lj, &traits, "shifted LJ");
        same::<lennard_jones::Shifted, OWNED_VIRIAL>(&l, &lj, &traits, "shifted LJ");
        same::<lennard_jones::ForceShifted, ENERGY>(&l, &[0.8, 1.1, 2.5], &traits, "force-shifted LJ");
        same::<wca::Fast, ENERGY>(&l, &[1.0, 1.0], &traits, "WCA");
        same::<yukawa::Fast, ENERGY>(&l, &[1.0, 1.5], &traits, "Yukawa");
        same::<coulomb_reaction_field::Fast, VIRIAL>(&l, &[1.0, 2.0, 78.0], &traits, "reaction field");
    }
}

/// The AVX-512 pullback (`pipelined::pullback`) gives the portable pullback's bits: the
/// covector's image and the parameters' sums, of the force and of the potential, on a liquid
/// and on a sparse gas where many rows have no pair inside (rows the portable one skips).
#[test]
#[cfg(target_arch = "x86_64")]
fn the_pipelined_pullback_gives_the_portable_bits() {
    if !std::is_x86_feature_detected!("avx512f") {
        eprintln!("no AVX-512 on this CPU: the portable pullback is the only one");
        return;
    }
    fn run<T: Paired, const POTENTIAL: bool>(l: &Neighbours, p: &[f64], wide: bool) -> Vec<u64> {
        let row = T::row(p);
        let mut rng = Rng::new(11);
        let g: Vec<Cluster> = (0..l.clusters())
            .map(|_| std::array::from_fn(|_| F64x4::new(std::array::from_fn(|_| rng.uniform(-1.0, 1.0)))))
            .collect();
        let at = Pulled { row: &row, p, reach2: T::reach2(&row), wanted: &[0, 1, 2], g: &g };
        let mut f = vec![[F64x4::default(); 3]; l.clusters()];
        let sums = match wide {
            // SAFETY: the CPU has AVX-512F (the test returned above otherwise)
            true => unsafe {
                super::super::pipelined::pullback::<T, POTENTIAL>(l, &at, 0..l.clusters(), &whole(l), &mut f)
            },
            false => portable_pullback::<T, POTENTIAL>(l, &at, 0..l.clusters(), &whole(l), &mut f),
        };
        let forces = f.iter().flatten().flat_map(|c| c.to_array()).map(f64::to_bits);
        forces.chain(sums.iter().map(|s| s.value().to_bits())).collect()
    }
    for (n, seed, scale) in [(1000, 12, 1.0), (400, 13, 1.6)] {
        // (scaled by 1.6, a sparse gas: many listed rows have no pair inside)
        let (x, cell, _) = liquid(n, seed);
        let x: Vec<[f64; 3]> = x.iter().map(|p| p.map(|c| c * scale)).collect();
        let cell = cell.map(|c| Cell { size: c.size.map(|s| s * scale), ..c });
        let mut l = Neighbours::new(&cell, 2.5).unwrap();
        l.update(&x, &cell, None);
        let empty_rows = (0..l.clusters())
            .flat_map(|ic| l.pairs[l.start[ic]..l.start[ic + 1]].iter().map(move |p| (ic, p)))
            .flat_map(|(ic, p)| (0..4).map(move |a| (ic, p, a)))
            .filter(|&(ic, p, a)| {
                let (xi, xj, sh) = (&l.x[ic], &l.x[p.j()], &l.shifts[p.image()]);
                (0..4).all(|b| norm2(&std::array::from_fn(|c| xj[c].lane(b) + sh[c] - xi[c].lane(a))) >= 6.25)
            })
            .count();
        assert!(empty_rows > 0, "no row without a pair inside: the skipped rows go untested");
        for (lj, what) in [(&[1.0, 1.0, 2.5], "shifted LJ"), (&[0.9, 1.1, 2.5], "other parameters")] {
            let (a, b) = (
                run::<lennard_jones::Shifted, false>(&l, lj, true),
                run::<lennard_jones::Shifted, false>(&l, lj, false),
            );
            assert!(a == b, "{what}: the force's pullback differs");
            assert!(a.iter().any(|&v| v != 0), "{what}: a pullback of nothing");
            let (a, b) =
                (run::<lennard_jones::Shifted, true>(&l, lj, true), run::<lennard_jones::Shifted, true>(&l, lj, false));
            assert!(a == b, "{what}: the potential's gradient differs");
        }
        let (a, b) = (
            run::<lennard_jones::ForceShifted, false>(&l, &[1.0, 1.0, 2.5], true),
            run::<lennard_jones::ForceShifted, false>(&l, &[1.0, 1.0, 2.5], false),
        );
        assert!(a == b, "force-shifted LJ: the force's pullback differs");
    }
}

/// Two bodies at one point inside the cutoff give non-finite forces (which the group then
/// names), and no other pair does.
#[test]
fn coincident_bodies_give_non_finite_forces() {
    let (mut x, cell, _) = liquid(300, 5);
    x[17] = x[42];
    let mut l = Neighbours::new(&cell, 2.5).unwrap();
    l.update(&x, &cell, None);
    let row = lennard_jones::Plain::row(&[1.0, 1.0, 2.5]);
    let mut f = vec![[F64x4::default(); 3]; l.clusters()];
    kernel::<lennard_jones::Plain, FORCES_ONLY>(&l, &row, (&[], &[]), 0..l.clusters(), &whole(&l), &mut f);
    assert!(f.iter().flatten().any(|c| c.to_array().iter().any(|v| !v.is_finite())));
    x[17][0] += 0.9;
    l.update(&x, &cell, None);
    let mut f = vec![[F64x4::default(); 3]; l.clusters()];
    kernel::<lennard_jones::Plain, FORCES_ONLY>(&l, &row, (&[], &[]), 0..l.clusters(), &whole(&l), &mut f);
    assert!(f.iter().flatten().all(|c| c.to_array().iter().all(|v| v.is_finite())));
}
