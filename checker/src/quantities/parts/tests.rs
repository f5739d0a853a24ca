use super::*;
use crate::model::{Body, UnitSystem};
use proptest::prelude::*;

/// 1,000 LJ atoms in a periodic box 11 wide, jittered off a lattice, moving; each atom bonded to
/// the next along x, and an angle at every tenth: bonded instances across any cut.
fn liquid() -> (Model, Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let body = Body { mass: 1.5, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
    let mut terms = vec![TermInstance { kind: Kind::LennardJonesShifted, sites: vec![], params: vec![1.0, 1.0, 2.5] }];
    for k in 0..1000 {
        let next = k / 10 * 10 + (k + 1) % 10;
        terms.push(TermInstance { kind: Kind::HarmonicBond, sites: vec![k, next], params: vec![2.0, 1.1, 0.0] });
        if k % 10 == 0 {
            let angle =
                TermInstance { kind: Kind::HarmonicAngle, sites: vec![k + 1, k, k + 2], params: vec![1.0, 2.0] };
            terms.push(angle);
        }
    }
    let model = Model {
        units: UnitSystem::Reduced,
        cell: Some(Cell { size: [11.0; 3], periodic: [true; 3] }),
        bodies: vec![body; 1000],
        terms,
        constraints: vec![],
        thermostat: None,
        floor: None,
        pins: vec![],
    };
    let jitter = |k: usize| ((k * 7919 % 1000) as f64 / 1000.0 - 0.5) * 0.2;
    let x = (0..1000).map(|k| [k % 10, k / 10 % 10, k / 100].map(|c| c as f64 * 1.1 + jitter(k + c))).collect();
    let v = (0..1000).map(|k| [jitter(k), jitter(k + 1), jitter(k + 2)]).collect();
    (model, x, v)
}

/// One rank's share: its local model, numbers, instances' numbers, owned count.
struct Share {
    model: Model,
    numbers: Vec<usize>,
    instances: Vec<usize>,
    owned: usize,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
}

/// The whole cut in slabs along x among `ranks` (an atom's owner from its wrapped x), each rank
/// taking as ghosts every other atom within `halo` of its slab, and the bonded instances of its
/// atoms. What the ranks send each other, and their regions.
fn cut(
    m: &Model,
    x: &[[f64; 3]],
    v: &[[f64; 3]],
    ranks: usize,
    halo: f64,
) -> (Vec<Share>, Vec<Vec<Vec<usize>>>, Vec<Region>) {
    let l = m.cell.unwrap().size[0];
    let owner = |p: &[f64; 3]| ((p[0].rem_euclid(l) / l * ranks as f64) as usize).min(ranks - 1);
    let owned: Vec<Vec<usize>> = (0..ranks).map(|r| (0..x.len()).filter(|&i| owner(&x[i]) == r).collect()).collect();
    let width = l / ranks as f64;
    // the periodic distance along x from the middle of slab r, less half its width
    let near = |r: usize, j: usize| {
        let d = x[j][0] - (r as f64 + 0.5) * width;
        (d - l * (d / l).round()).abs() - 0.5 * width <= halo
    };
    // sent[s][r]: the places among s's owned of those r takes as ghosts
    let mut sent = vec![vec![vec![]; ranks]; ranks];
    let mut shares = vec![];
    for r in 0..ranks {
        let mut numbers = owned[r].clone();
        for s in (0..ranks).filter(|&s| s != r) {
            for (k, &j) in owned[s].iter().enumerate() {
                if near(r, j) {
                    sent[s][r].push(k);
                    numbers.push(j);
                }
            }
        }
        let place: std::collections::HashMap<usize, usize> = numbers.iter().enumerate().map(|(k, &i)| (i, k)).collect();
        let bonded: Vec<&TermInstance> = m.terms.iter().filter(|t| !t.sites.is_empty()).collect();
        let mut terms: Vec<TermInstance> = m.terms.iter().filter(|t| t.sites.is_empty()).cloned().collect();
        let mut instances = vec![];
        for (k, t) in bonded.iter().enumerate() {
            if t.sites.iter().any(|i| owned[r].contains(i)) {
                terms.push(TermInstance { sites: t.sites.iter().map(|i| place[i]).collect(), ..(*t).clone() });
                instances.push(k);
            }
        }
        let bodies = numbers.iter().map(|&i| m.bodies[i].clone()).collect();
        let (xs, vs) = (numbers.iter().map(|&i| x[i]).collect(), numbers.iter().map(|&i| v[i]).collect());
        let model = Model { bodies, terms, ..m.clone() };
        shares.push(Share { model, numbers, instances, owned: owned[r].len(), x: xs, v: vs });
    }
    let regions = (0..ranks)
        .map(|r| Region::of(&shares[r].x[..shares[r].owned], [(r as f64 + 0.5) * l / ranks as f64, 5.5, 5.5], &m.cell))
        .collect();
    (shares, sent, regions)
}

fn enclose(whole: &Model, shares: &[Share], sent: &[Vec<Vec<usize>>], regions: &[Region], rank: usize) -> Part {
    let s = &shares[rank];
    Part::enclose(&Local {
        whole,
        model: &s.model,
        state: Snapshot { step: 0, t: 0.0, x: &s.x, v: &s.v, chain: &[], spin: &[] },
        owned: s.owned,
        numbers: &s.numbers,
        instances: &s.instances,
        rank,
        regions,
        sent: &sent[rank],
        threads: 2,
    })
}

fn parts_of(m: &Model, shares: &[Share], sent: &[Vec<Vec<usize>>], regions: &[Region]) -> Parts {
    let parts = (0..shares.len()).map(|r| enclose(m, shares, sent, regions, r)).collect();
    Parts { parts, numbers: shares.iter().flat_map(|s| s.numbers[..s.owned].to_vec()).collect() }
}

fn overlap(a: Outward, b: Outward) -> bool {
    let ((a0, a1), (b0, b1)) = (a.bounds(), b.bounds());
    a0 <= b1 && b0 <= a1
}

/// Cut among 2, 3 and 5 ranks, the parts added enclose the whole's energy and momentum (the
/// enclosures meet; the energy's as narrow as the whole's within 1%, the momentum's summed in
/// another order within 1e-11), and travel as f64s unchanged.
#[test]
fn the_parts_added_enclose_the_whole() {
    let (m, x, v) = liquid();
    let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
    let q = Lifted::new(&m, &s, &Outward::NAN);
    let (energy, momentum) = (q.energy(&m), q.momentum(&m));
    for ranks in [2, 3, 5] {
        let (shares, sent, regions) = cut(&m, &x, &v, ranks, 2.6);
        assert!(shares.iter().all(|s| s.model.bodies.len() > s.owned), "every rank has ghosts");
        let parts = parts_of(&m, &shares, &sent, &regions);
        let w = parts.whole(&m).unwrap();
        let width = |e: Outward| e.bounds().1 - e.bounds().0;
        let as_narrow = |a: Outward, b: Outward| overlap(a, b) && width(a) <= 1.01 * width(b) + 1e-15;
        assert!(as_narrow(w.energy, energy), "{ranks} ranks: {w:?} {energy:?}");
        let close = |c: usize| overlap(w.momentum[c], momentum[c]) && width(w.momentum[c]) < 1e-11;
        assert!((0..3).all(close), "{ranks} ranks: {w:?} {momentum:?}");
        let travelled: Vec<Part> =
            parts.parts.iter().enumerate().map(|(r, p)| Part::from_bits(&p.to_bits(), r)).collect();
        let again = Parts { parts: travelled, ..parts }.whole(&m).unwrap();
        assert_eq!(again.energy.bounds(), w.energy.bounds());
    }
}

/// Counting every pair with a ghost whole (as if each rank's pairs were its own) gives an
/// enclosure that misses the whole's energy: the halves are what make the parts add up.
#[test]
fn pairs_across_ranks_counted_whole_would_miss() {
    let (m, x, v) = liquid();
    let (shares, ..) = cut(&m, &x, &v, 2, 2.6);
    let s = &shares[0];
    let snap = Snapshot { step: 0, t: 0.0, x: &s.x, v: &s.v, chain: &[], spin: &[] };
    let q = Lifted::new(&s.model, &snap, &Outward::NAN);
    let near = Neighbourhood::new(&s.x, &s.model.cell, asked_reach(&s.model.terms[0]), &[]);
    let halves = q.pairs_part(s.model.terms[0].kind, 0, &near, s.owned);
    let wholes = q.pairs_part(s.model.terms[0].kind, 0, &near, s.model.bodies.len());
    let ghosts_only = q.pairs_part(s.model.terms[0].kind, 0, &near, 0);
    let (lo, hi) = ghosts_only.bounds();
    assert!(lo.abs() < 1e-150 && hi.abs() < 1e-150, "no owned body, nothing counted: {ghosts_only:?}");
    assert!(!overlap(halves, wholes), "{halves:?} {wholes:?}");
}

/// A ghost left out by its sender, a body owned twice, a bonded instance dropped, a region that
/// does not hold its rank's bodies, a body whose mass differs from the whole's: each refused.
#[test]
fn parts_that_do_not_cover_the_whole_are_refused() {
    let (m, x, v) = liquid();
    let (shares, sent, regions) = cut(&m, &x, &v, 3, 2.6);
    assert!(parts_of(&m, &shares, &sent, &regions).whole(&m).is_ok());

    let mut missing = sent.clone();
    let middle = missing[1][0].len() / 2;
    missing[1][0].remove(middle);
    let p = enclose(&m, &shares, &missing, &regions, 1);
    assert!(p.flaw.as_deref().unwrap().contains("is not its ghost"), "{:?}", p.flaw);
    let mut parts = parts_of(&m, &shares, &sent, &regions);
    parts.parts[1] = Part::from_bits(&p.to_bits(), 1);
    assert!(parts.whole(&m).unwrap_err().contains("rank 1"));

    let mut twice = parts_of(&m, &shares, &sent, &regions);
    let last = twice.numbers.len() - 1;
    twice.numbers[last] = twice.numbers[0];
    assert!(twice.whole(&m).unwrap_err().contains("each once"));

    let mut dropped = parts_of(&m, &shares, &sent, &regions);
    dropped.parts[2].instances -= 1;
    assert!(dropped.whole(&m).unwrap_err().contains("bonded instances"));

    let mut shrunk = regions.clone();
    shrunk[0] = Region::of(&shares[0].x[..shares[0].owned / 2], [5.5 / 3.0, 5.5, 5.5], &m.cell);
    assert!(enclose(&m, &shares, &sent, &shrunk, 0).flaw.unwrap().contains("region"));

    let mut heavier = cut(&m, &x, &v, 3, 2.6).0;
    heavier[2].model.bodies[3].mass = 1.6;
    assert!(enclose(&m, &heavier, &sent, &regions, 2).flaw.unwrap().contains("body"));

    let mut renumbered = cut(&m, &x, &v, 3, 2.6).0;
    renumbered[0].instances[0] += 1;
    assert!(enclose(&m, &renumbered, &sent, &regions, 0).flaw.is_some());
}

proptest! {
    /// A point within reach of a body of a region (to its nearest image, in a periodic box) is
    /// near the region, wherever the bodies lie (wrapped or not, far images included) and
    /// whatever the centre.
    #[test]
    fn a_point_within_reach_of_a_body_is_near_its_region(
        bodies in proptest::collection::vec(proptest::array::uniform3(-30.0f64..40.0), 1..8),
        centre in proptest::array::uniform3(-5.0f64..15.0),
        pick in 0usize..8,
        dir in proptest::array::uniform3(-1.0f64..1.0),
        along in 0.0f64..1.0,
        k in proptest::array::uniform3(-2i32..3),
    ) {
        let cell = Some(Cell { size: [10.0, 7.0, 13.0], periodic: [true, true, true] });
        let reach = 2.5;
        let r = Region::of(&bodies, centre, &cell);
        let b = bodies[pick % bodies.len()];
        let n = dir.iter().map(|c| c * c).sum::<f64>().sqrt().max(1e-9);
        let size = cell.unwrap().size;
        let p: [f64; 3] = std::array::from_fn(|a| b[a] + dir[a] / n * reach * along + k[a] as f64 * size[a]);
        prop_assert!(r.near(p, reach, &cell), "{p:?} from {b:?}");
    }
}

proptest! {
    /// Two regions with a body of one within reach of a body of the other (to its nearest
    /// image) meet, wherever the bodies lie and whatever the centres: a rank that skips the
    /// regions its own does not meet skips no body it must send.
    #[test]
    fn regions_with_bodies_within_reach_meet(
        mine in proptest::collection::vec(proptest::array::uniform3(-30.0f64..40.0), 1..6),
        theirs in proptest::collection::vec(proptest::array::uniform3(-30.0f64..40.0), 1..6),
        centres in proptest::array::uniform6(-15.0f64..25.0),
        open in proptest::array::uniform3(proptest::bool::ANY),
    ) {
        let cell = Some(Cell { size: [10.0, 7.0, 13.0], periodic: open.map(|o| !o) });
        let reach = 2.5;
        let (a, b) = (
            Region::of(&mine, [centres[0], centres[1], centres[2]], &cell),
            Region::of(&theirs, [centres[3], centres[4], centres[5]], &cell),
        );
        let l = lengths(&cell);
        let apart = |p: &[f64; 3], q: &[f64; 3]| {
            (0..3).map(|k| offset(p[k], q[k], l[k]).0.powi(2)).sum::<f64>().sqrt()
        };
        let within = mine.iter().any(|p| theirs.iter().any(|q| apart(p, q) <= reach));
        prop_assert!(!within || (a.meets(&b, reach, &cell) && b.meets(&a, reach, &cell)));
    }
}

/// Boxes a gap of 2 apart meet within a reach of 2.5, a gap of 4 do not, and across a periodic
/// face the gap is the wrapped one; an empty region meets nothing.
#[test]
fn regions_meet_across_their_gap_and_the_periodic_faces() {
    let cell = Some(Cell { size: [20.0; 3], periodic: [true; 3] });
    // unit cubes along x
    let cube = |at: f64| Region::of(&[[at, 0.0, 0.0], [at + 1.0, 1.0, 1.0]], [at + 0.5, 0.5, 0.5], &cell);
    let (a, near, far, wrapped) = (cube(0.0), cube(3.0), cube(5.0), cube(18.0));
    assert!(a.meets(&near, 2.5, &cell) && near.meets(&a, 2.5, &cell));
    assert!(!a.meets(&far, 2.5, &cell) && !far.meets(&a, 2.5, &cell));
    assert!(a.meets(&wrapped, 2.5, &cell));
    let open = Some(Cell { size: [20.0; 3], periodic: [false; 3] });
    let (a, wrapped) =
        (Region::of(&[[0.0; 3]], [0.0; 3], &open), Region::of(&[[18.0, 0.0, 0.0]], [18.0, 0.0, 0.0], &open));
    assert!(!a.meets(&wrapped, 2.5, &open));
    assert!(!Region::of(&[], [0.0; 3], &cell).meets(&a, 2.5, &cell));
}

/// Bricks of a 4×4×4 grid in a periodic box, each region holding its brick's corners: a brick
/// meets its 26 neighbours (across the periodic faces too) and no other, so a rank tests its
/// bodies one by one against 26 regions, not 63.
#[test]
fn a_brick_meets_its_26_neighbours_and_no_other() {
    let cell = Some(Cell { size: [40.0; 3], periodic: [true; 3] });
    let brick = |k: [usize; 3]| {
        let lo = k.map(|c| c as f64 * 10.0);
        let corners: Vec<[f64; 3]> =
            (0..8).map(|c| std::array::from_fn(|a| lo[a] + if c >> a & 1 == 1 { 9.99 } else { 0.0 })).collect();
        Region::of(&corners, lo.map(|c| c + 5.0), &cell)
    };
    let all: Vec<Region> = (0..64).map(|i| brick([i % 4, i / 4 % 4, i / 16])).collect();
    for (i, r) in all.iter().enumerate() {
        let met = all.iter().enumerate().filter(|(j, o)| *j != i && r.meets(o, 2.5, &cell)).count();
        assert_eq!(met, 26, "brick {i}");
    }
}
