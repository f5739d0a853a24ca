use super::*;
use crate::forces::dual::Rng;
use crate::traverse;
use proptest::prelude::*;

/// Every pair of bodies the list holds within `reach`, as (smaller, larger), sorted, each
/// with its displacement checked against the minimum image of the positions.
fn listed_within(list: &Neighbours, x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<(usize, usize)> {
    let mut listed = vec![];
    list.each_pair::<()>(|i, j, d| {
        if d.iter().map(|c| c * c).sum::<f64>() < reach * reach {
            let exact = Cell::image(cell, std::array::from_fn(|a| x[j][a] - x[i][a]));
            assert!((0..3).all(|a| (exact[a] - d[a]).abs() < 1e-9), "{i} {j}: {d:?} vs {exact:?}");
            listed.push((i.min(j), i.max(j)));
        }
        Ok(())
    })
    .unwrap();
    listed.sort();
    listed
}

fn all_within(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<(usize, usize)> {
    let mut all = vec![];
    traverse::pairs::<()>(x, cell, None, |i, j, d| {
        if d.iter().map(|c| c * c).sum::<f64>() < reach * reach {
            all.push((i.min(j), i.max(j)));
        }
        Ok(())
    })
    .unwrap();
    all.sort();
    all
}

proptest! {
    /// After the bodies move so that no two together moved the skin (one up to 0.7 of it, the
    /// rest up to 0.29), the stale list still holds every pair within reach exactly once,
    /// and its stored image gives the minimum-image displacement.
    #[test]
    fn a_stale_list_still_holds_every_pair_within_reach_once(seed in any::<u64>(), n in 64usize..300, side in 6.0f64..14.0, periodic in any::<bool>()) {
        let mut rng = Rng::new(seed);
        let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, rng.uniform(0.0, 1.0) < 0.7, rng.uniform(0.0, 1.0) < 0.5] });
        let reach = 2.5;
        // bodies that have drifted out of the box, as unwrapped positions do in a long run
        let mut x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-3.0 * side, 4.0 * side))).collect();
        let mut list = Neighbours::new(&cell, reach).unwrap();
        list.update(&x, &cell, None);
        let far = rng.uniform(0.0, n as f64) as usize;
        for (i, p) in x.iter_mut().enumerate() {
            let most = if i == far { 0.7 } else { 0.29 } * list.skin / 3f64.sqrt();
            p.iter_mut().for_each(|c| *c += rng.uniform(-most, most));
        }
        list.update(&x, &cell, None);
        prop_assert_eq!(list.builds, 1);
        prop_assert_eq!(list.bodies.iter().filter(|&&b| b != EMPTY).count(), n);
        prop_assert_eq!(listed_within(&list, &x, &cell, reach), all_within(&x, &cell, reach));
    }
}

proptest! {
    /// The list is exactly the cluster pairs some of whose bodies (not empty slots) lie
    /// within reach + skin, each once (j after i, or i itself at the zero image or a later
    /// one): the columns' z windows and the test that leaves a column out drop only pairs
    /// the sixteen distances would, on a CPU with AVX-512 the search's eight-lane test
    /// answers as the four-lane one does, and no empty slot's image meets another's.
    #[test]
    fn the_list_is_every_cluster_pair_that_touches(seed in any::<u64>(), n in 64usize..400, side in 6.0f64..12.0, periodic in any::<bool>()) {
        let mut rng = Rng::new(seed);
        let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, rng.uniform(0.0, 1.0) < 0.7, rng.uniform(0.0, 1.0) < 0.5] });
        let x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-side, 2.0 * side))).collect();
        let mut list = Neighbours::new(&cell, 2.5).unwrap();
        list.update(&x, &cell, None);
        let r = list.reach + list.skin;
        let images: Vec<usize> = (0..27)
            .filter(|k| (0..3).all(|a| [k % 3, k / 3 % 3, k / 9][a] == 1 || cell.is_some_and(|c| c.periodic[a])))
            .collect();
        for ic in 0..list.clusters() {
            let mut listed: Vec<(usize, usize)> =
                list.pairs[list.start[ic]..list.start[ic + 1]].iter().map(|p| (p.j(), p.image())).collect();
            listed.sort();
            let mut touching = vec![];
            for jc in ic..list.clusters() {
                for &k in images.iter().filter(|&&k| jc > ic || k >= CENTRE) {
                    let body = |c: usize, l: usize| list.bodies[LANES * c + l] != EMPTY;
                    let sh = &list.shifts[k];
                    let near = (0..LANES).any(|a| {
                        (0..LANES).any(|b| {
                            let d: [f64; 3] = std::array::from_fn(|c| (list.x[jc][c].lane(b) + sh[c]) - list.x[ic][c].lane(a));
                            body(ic, a) && body(jc, b) && crate::lanes::norm2(&d) < r * r
                        })
                    });
                    if near {
                        touching.push((jc, k));
                    }
                }
            }
            prop_assert_eq!(listed, touching, "i-cluster {}", ic);
        }
    }
}

/// Bodies spread along a line in open space: few columns, and still every pair.
#[test]
fn bodies_on_a_line_are_listed() {
    let x: Vec<[f64; 3]> = (0..500).map(|i| [i as f64 * 0.7, 0.0, 0.0]).collect();
    let mut list = Neighbours::new(&None, 2.5).unwrap();
    list.update(&x, &None, None);
    assert_eq!(listed_within(&list, &x, &None, 2.5), all_within(&x, &None, 2.5));
}

/// A list built in parts on 2 or 3 threads is the list one pass builds.
#[test]
fn the_list_is_the_same_on_any_number_of_threads() {
    let mut rng = Rng::new(11);
    // 3,000 bodies (the passes over them on one thread), and 20,000 (spread over the pool)
    for (n, side) in [(3000, 16.0), (20_000, 30.0)] {
        let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
        let x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-4.0, side + 4.0))).collect();
        let built = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut list = Neighbours::new(&cell, 2.5).unwrap();
            list.update(&x, &cell, (threads > 1).then_some(&pool));
            let x: Vec<_> = list.x.iter().flatten().flat_map(|v| v.to_array().map(f64::to_bits)).collect();
            (list.bodies, list.start, list.pairs, x, list.offset, list.slot, list.pieces.place)
        };
        let one = built(1);
        assert!(one.2.len() > 3 * n, "{}", one.2.len());
        // every body in one slot (20,000 bodies are dealt into the columns in two blocks)
        let mut slotted: Vec<u32> = one.0.iter().copied().filter(|&b| b != EMPTY).collect();
        slotted.sort_unstable();
        assert!(slotted.iter().copied().eq(0..n as u32));
        assert!(built(2) == one && built(3) == one && built(7) == one);
    }
}

proptest! {
    /// Parts joined on a pool are the parts one after another.
    #[test]
    fn parts_joined_on_any_pool_are_the_parts_in_order(lens in proptest::collection::vec(0usize..50, 0..12)) {
        let parts: Vec<Vec<u64>> = lens.iter().enumerate().map(|(k, &n)| (0..n as u64).map(|v| v * 100 + k as u64).collect()).collect();
        let parts: Vec<&[u64]> = parts.iter().map(|p| &p[..]).collect();
        let want: Vec<u64> = parts.iter().enumerate().flat_map(|(k, p)| p.iter().map(move |v| v + 7 * k as u64)).collect();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        for spread in [None, Some(&pool)] {
            prop_assert_eq!(&joined(spread, &parts, |k, v| v + 7 * k as u64), &want);
        }
    }
}

/// Clusters are compact, and boxes within reach whose bodies are not are left out: on a
/// dense box at reach 2.5, over a fifth of the body pairs in the listed cluster pairs lie
/// within reach (26% measured; 18% with boxes alone).
#[test]
fn clusters_are_compact_enough_that_most_work_counts() {
    let mut rng = Rng::new(2);
    let side = (4000.0f64 / 0.8442).cbrt();
    let cell = Some(Cell { size: [side; 3], periodic: [true; 3] });
    let x: Vec<[f64; 3]> = (0..4000).map(|_| std::array::from_fn(|_| rng.uniform(0.0, side))).collect();
    let mut list = Neighbours::new(&cell, 2.5).unwrap();
    list.update(&x, &cell, None);
    let within = listed_within(&list, &x, &cell, 2.5).len();
    let computed = 16 * list.count();
    assert!(5 * within > computed, "{within} of {computed}");
}

/// Two bodies that together moved just over the skin (three quarters and a third of it)
/// bring a rebuild; either alone does not.
#[test]
fn two_bodies_moving_the_skin_together_rebuild_the_list() {
    let mut x: Vec<[f64; 3]> =
        (0..100).map(|i| [(i % 5) as f64 * 3.0, (i / 5 % 5) as f64 * 3.0, (i / 25) as f64 * 3.0]).collect();
    let mut list = Neighbours::new(&None, 2.5).unwrap();
    list.update(&x, &None, None);
    x[7][0] += 0.75 * list.skin;
    list.update(&x, &None, None);
    assert_eq!(list.builds, 1);
    x[40][1] -= 0.34 * list.skin;
    list.update(&x, &None, None);
    assert_eq!(list.builds, 2);
}

#[test]
fn a_box_too_small_for_the_skin_gets_no_list() {
    let cell = Some(Cell { size: [5.0; 3], periodic: [true; 3] });
    assert!(Neighbours::new(&cell, 2.5).is_none());
    assert!(Neighbours::new(&None, 2.5).is_some());
}

/// A list copied into another's memory (one built from other bodies, more of them) is the
/// list, field by field, and so is a fresh copy; on a pool or not.
#[test]
fn a_copied_list_is_the_list() {
    let cell = Some(Cell { size: [12.0; 3], periodic: [true; 3] });
    let mut rng = Rng::new(5);
    let mut bodies =
        |n: usize| -> Vec<[f64; 3]> { (0..n).map(|_| std::array::from_fn(|_| rng.uniform(0.0, 12.0))).collect() };
    let (x, other) = (bodies(400), bodies(700));
    let mut list = Neighbours::new(&cell, 2.5).unwrap();
    list.update(&x, &cell, None);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    for pool in [None, Some(&pool)] {
        let mut into = Neighbours::new(&cell, 2.5).unwrap();
        into.update(&other, &cell, None);
        into.copy_from(&list, pool);
        for copy in [&into, &list.copied(pool)] {
            let bits = |c: &[Cluster]| -> Vec<u64> {
                c.iter().flatten().flat_map(|l| l.to_array()).map(f64::to_bits).collect()
            };
            assert_eq!(
                (&copy.bodies, &copy.start, &copy.pairs, &copy.slot),
                (&list.bodies, &list.start, &list.pairs, &list.slot)
            );
            assert_eq!((&copy.at, &copy.offset, bits(&copy.x)), (&list.at, &list.offset, bits(&list.x)));
            assert_eq!(format!("{:?}", copy.pieces), format!("{:?}", list.pieces));
            assert_eq!(
                (copy.builds, copy.reach, copy.skin, copy.ghosts_from),
                (list.builds, list.reach, list.skin, list.ghosts_from)
            );
            assert_eq!(listed_within(copy, &x, &cell, 2.5), all_within(&x, &cell, 2.5));
        }
    }
}
