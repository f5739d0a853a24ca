//! Islands: the bodies joined by contacts and by pins between bodies (the floor and the world
//! join nothing), each with the contacts and pins among them, renumbered from nought. Bodies of
//! different islands never share a row, so each island is a problem of its own, and a pool of
//! threads takes them one at a time without waiting between colours.

use crate::contact::Touch;
use lagra_checker::model::Pin;

/// One island, borrowed: its bodies' indices in the state, in order; the touches among them
/// (their places in the step's list `found`, in the order they were found) and the pins, with
/// their bodies renumbered into that list (`local`); each pin's index in the scene (its warm
/// start's key). Places and local numbers are `u32`: a step's touches and bodies number far
/// below 2³² (a body's state alone takes a kilobyte).
#[derive(Clone, Copy)]
pub struct Island<'a> {
    pub bodies: &'a [usize],
    found: &'a [Touch],
    which: &'a [u32],
    local: &'a [u32],
    pub pins: &'a [(usize, Pin)],
}

impl<'a> Island<'a> {
    /// Its touches, their bodies numbered within the island: renumbered as they are read, in
    /// the island's own task, where the split copied them out on one thread (on the 1,000-block
    /// stack 8,000 touches, 700 kB a step, a third of the split).
    pub fn touches(&self) -> impl ExactSizeIterator<Item = Touch> + 'a {
        let (found, local) = (self.found, self.local);
        self.which.iter().map(move |&s| {
            let t = &found[s as usize];
            Touch { a: t.a.map(|a| local[a] as usize), b: local[t.b] as usize, ..*t }
        })
    }
}

/// The whole scene as one island: every body, touch and pin, numbered as in the state.
pub struct Whole {
    bodies: Vec<usize>,
    local: Vec<u32>,
    which: Vec<u32>,
    pins: Vec<(usize, Pin)>,
}

impl Whole {
    pub fn of(n: usize, touches: usize, pins: Vec<(usize, Pin)>) -> Whole {
        let which = (0..touches as u32).collect();
        Whole { bodies: (0..n).collect(), local: (0..n as u32).collect(), which, pins }
    }

    /// The island, its touches those of `found` (as many as `of` was told).
    pub fn island<'a>(&'a self, found: &'a [Touch]) -> Island<'a> {
        Island { bodies: &self.bodies, found, which: &self.which, local: &self.local, pins: &self.pins }
    }
}

/// Every island of a step, laid out flat: island k's bodies, touches (their places in the
/// step's list) and pins are the k-th runs of three lists (a counting sort), so splitting a step
/// allocates a few lists, not three an island (the 1,000-block stack's hundred islands made that
/// a third of its serial time).
pub struct Islands {
    bodies: Vec<usize>,
    touches: Vec<u32>,
    pins: Vec<(usize, Pin)>,
    /// A body's place within its island.
    local: Vec<u32>,
    /// Where island k's runs start in the three lists; one more entry, the lists' lengths.
    starts: Vec<[usize; 3]>,
}

impl Islands {
    /// The islands of `n` bodies joined by `touches` and `pins`, ordered by their first body; a
    /// body that touches nothing is in none.
    pub fn of(touches: &[Touch], pins: &[Pin], n: usize) -> Islands {
        let mut root: Vec<usize> = (0..n).collect();
        let mut joined = vec![false; n];
        let links = touches.iter().map(|t| (t.a, t.b)).chain(pins.iter().map(|p| (p.a, p.b)));
        let mut last = None;
        for (a, b) in links {
            joined[b] = true;
            // a pair's touches come one after another (up to four for two boxes): joined once
            if let Some(a) = a.filter(|_| last != Some((a, b))) {
                joined[a] = true;
                let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                root[ra.max(rb)] = ra.min(rb);
            }
            last = Some((a, b));
        }
        // each island's root is its lowest body, so numbering the roots in order numbers the
        // islands by their first body; `local` is a body's place within its island
        let mut island = vec![usize::MAX; n];
        let mut local = vec![0; n];
        let mut counts: Vec<[usize; 3]> = vec![];
        for i in (0..n).filter(|&i| joined[i]) {
            let r = find(&mut root, i);
            if r == i {
                island[i] = counts.len();
                counts.push([0; 3]);
            }
            island[i] = island[r];
            local[i] = counts[island[i]][0] as u32;
            counts[island[i]][0] += 1;
        }
        touches.iter().for_each(|t| counts[island[t.b]][1] += 1);
        pins.iter().for_each(|p| counts[island[p.b]][2] += 1);
        let mut starts = Vec::with_capacity(counts.len() + 1);
        let mut at = [0; 3];
        for c in &counts {
            starts.push(at);
            at = std::array::from_fn(|k| at[k] + c[k]);
        }
        starts.push(at);
        // where each touch and pin goes: the next free place of its island's run, so each
        // island's keep the order they were found in; `from[d]` is what lands at place d
        let mut next: Vec<[usize; 3]> = starts.clone();
        let mut bodies = vec![0; at[0]];
        for i in (0..n).filter(|&i| joined[i]) {
            bodies[starts[island[i]][0] + local[i] as usize] = i;
        }
        let mut from = vec![0; at[1]];
        for (s, t) in touches.iter().enumerate() {
            let k = island[t.b];
            from[next[k][1]] = s as u32;
            next[k][1] += 1;
        }
        let mut picked = vec![0; at[2]];
        for (j, p) in pins.iter().enumerate() {
            let k = island[p.b];
            picked[next[k][2]] = j;
            next[k][2] += 1;
        }
        let local_of = |b: usize| local[b] as usize;
        let pins = picked
            .iter()
            .map(|&j| (j, Pin { a: pins[j].a.map(local_of), b: local_of(pins[j].b), ..pins[j] }))
            .collect();
        Islands { bodies, touches: from, pins, local, starts }
    }

    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// Island k of the step whose touches were `found` (the list the islands were split from).
    pub fn get<'a>(&'a self, k: usize, found: &'a [Touch]) -> Island<'a> {
        let ([b0, t0, p0], [b1, t1, p1]) = (self.starts[k], self.starts[k + 1]);
        let (which, local) = (&self.touches[t0..t1], &self.local[..]);
        Island { bodies: &self.bodies[b0..b1], found, which, local, pins: &self.pins[p0..p1] }
    }

    /// The islands' sizes in bodies, in order.
    pub fn sizes(&self) -> impl ExactSizeIterator<Item = usize> + '_ {
        self.starts.windows(2).map(|w| w[1][0] - w[0][0])
    }
}

/// The root of i's set, halving the path on the way.
fn find(root: &mut [usize], mut i: usize) -> usize {
    while root[i] != i {
        root[i] = root[root[i]];
        i = root[i];
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn touch(a: Option<usize>, b: usize) -> Touch {
        Touch { a, b, point: Vector3::zeros(), normal: Vector3::y(), depth: 0.0, friction: 0.5 }
    }

    /// Two towers on the floor (0 under 2, 1 under 3), a pair hinged in the air (4, 5) and a
    /// body touching nothing (6): three islands, by their first body, renumbered in order.
    #[test]
    fn contacts_and_pins_between_bodies_join_islands_and_the_floor_does_not() {
        let touches = [touch(None, 0), touch(None, 1), touch(Some(1), 3), touch(Some(0), 2)];
        let pins = [Pin { a: Some(4), b: 5, on_a: [0.0; 3], on_b: [0.0; 3] }];
        let split = Islands::of(&touches, &pins, 7);
        let islands: Vec<Island> = (0..split.len()).map(|k| split.get(k, &touches)).collect();
        let bodies: Vec<_> = islands.iter().map(|i| i.bodies.to_vec()).collect();
        assert_eq!(bodies, vec![vec![0, 2], vec![1, 3], vec![4, 5]]);
        let pairs = |i: &Island| i.touches().map(|t| (t.a, t.b)).collect::<Vec<_>>();
        assert_eq!(pairs(&islands[0]), vec![(None, 0), (Some(0), 1)]);
        assert_eq!(pairs(&islands[1]), vec![(None, 0), (Some(0), 1)]);
        assert_eq!(islands[2].pins, vec![(0, Pin { a: Some(0), b: 1, on_a: [0.0; 3], on_b: [0.0; 3] })]);
    }

    /// A chain joined out of order (3–1, then 1–2, 0 alone on the floor) is one island whose
    /// root is its lowest body.
    #[test]
    fn a_chain_found_out_of_order_is_one_island() {
        let touches = [touch(Some(1), 3), touch(None, 0), touch(Some(1), 2)];
        let split = Islands::of(&touches, &[], 4);
        let islands: Vec<Island> = (0..split.len()).map(|k| split.get(k, &touches)).collect();
        let bodies: Vec<_> = islands.iter().map(|i| i.bodies.to_vec()).collect();
        assert_eq!(bodies, vec![vec![0], vec![1, 2, 3]]);
        let pairs: Vec<_> = islands[1].touches().map(|t| (t.a, t.b)).collect();
        assert_eq!(pairs, vec![(Some(0), 2), (Some(0), 1)]);
    }

    /// A pair's touches side by side (joined once), the same pair again after another, and the
    /// whole scene as one island: every touch kept, in order, numbered as the islands say.
    #[test]
    fn a_pairs_touches_are_joined_once_and_all_kept() {
        let touches = [
            touch(Some(1), 3),
            touch(Some(1), 3),
            touch(None, 0),
            touch(Some(1), 3),
            touch(Some(0), 2),
            touch(None, 2),
        ];
        let split = Islands::of(&touches, &[], 5);
        assert_eq!(split.sizes().collect::<Vec<_>>(), vec![2, 2]);
        let pairs = |i: Island| i.touches().map(|t| (t.a, t.b)).collect::<Vec<_>>();
        assert_eq!(pairs(split.get(0, &touches)), vec![(None, 0), (Some(0), 1), (None, 1)]);
        assert_eq!(pairs(split.get(1, &touches)), vec![(Some(0), 1); 3]);
        let whole = Whole::of(5, touches.len(), vec![]);
        let all: Vec<_> = whole.island(&touches).touches().map(|t| (t.a, t.b)).collect();
        assert_eq!(all, touches.iter().map(|t| (t.a, t.b)).collect::<Vec<_>>());
    }
}
