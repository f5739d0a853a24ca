//! Last step's contacts, kept for the warm start: each contact's place, λ and k, filed under its
//! body b (and, there, its other body a: the floor none), each pin's under its index. Filed by
//! body rather than hashed by pair, the store is cleared and refilled every step without
//! allocating (each body's list keeps its room), and a look-up scans b's few contacts: a hash map
//! of pairs, a list each, was a third of the 1,000-block stack's serial time.

use nalgebra::Vector3;

/// A contact's place (where the next step's search will find it), λ and k of its three rows.
pub(super) type Kept = (Vector3<f64>, [f64; 3], [f64; 3]);

/// Whose a kept contact is: pin j's, or a contact's between a (none: the floor) and b.
#[derive(Clone, Copy)]
pub(super) enum Key {
    Pin(usize),
    Pair(Option<usize>, usize),
}

/// The carried form: each pair (a, b) with its contacts, the floor's a being `usize::MAX` and
/// pin j's pair (j, `usize::MAX`), which no contact's can be (b is a body).
pub(super) type Pairs = Vec<((usize, usize), Vec<Kept>)>;

#[derive(Default)]
pub(super) struct Warm {
    /// By body b: its contacts' other bodies (`usize::MAX`: the floor) and what they kept, in
    /// the order they were kept.
    contacts: Vec<Vec<(usize, Kept)>>,
    pins: Vec<Option<Kept>>,
}

impl Warm {
    /// Empties the store, keeping its room.
    pub(super) fn clear(&mut self) {
        self.contacts.iter_mut().for_each(Vec::clear);
        self.pins.iter_mut().for_each(|p| *p = None);
    }

    /// Keeps a contact between a (none: the floor) and b.
    pub(super) fn keep(&mut self, a: Option<usize>, b: usize, kept: Kept) {
        if self.contacts.len() <= b {
            self.contacts.resize_with(b + 1, Vec::new);
        }
        self.contacts[b].push((a.unwrap_or(usize::MAX), kept));
    }

    /// Keeps pin j's rows.
    pub(super) fn keep_pin(&mut self, j: usize, kept: Kept) {
        if self.pins.len() <= j {
            self.pins.resize(j + 1, None);
        }
        self.pins[j] = Some(kept);
    }

    /// What the contacts between a (none: the floor) and b kept, in the order they were kept.
    pub(super) fn between(&self, a: Option<usize>, b: usize) -> impl Iterator<Item = &Kept> {
        let a = a.unwrap_or(usize::MAX);
        self.contacts.get(b).into_iter().flatten().filter(move |c| c.0 == a).map(|c| &c.1)
    }

    /// What pin j kept.
    pub(super) fn pin(&self, j: usize) -> Option<&Kept> {
        self.pins.get(j).and_then(Option::as_ref)
    }

    /// Every pair's contacts and every pin's, in the order of their pairs.
    pub(super) fn pairs(&self) -> Pairs {
        let mut pairs: Pairs = vec![];
        for (b, kept) in self.contacts.iter().enumerate() {
            let mut by_a: Vec<&(usize, Kept)> = kept.iter().collect();
            by_a.sort_by_key(|c| c.0); // stable: a pair's contacts stay in the order kept
            for chunk in by_a.chunk_by(|x, y| x.0 == y.0) {
                pairs.push(((chunk[0].0, b), chunk.iter().map(|c| c.1).collect()));
            }
        }
        pairs.extend(self.pins.iter().enumerate().filter_map(|(j, p)| p.map(|p| ((j, usize::MAX), vec![p]))));
        pairs.sort_by_key(|p| p.0);
        pairs
    }

    /// The store that `pairs` gave.
    pub(super) fn from_pairs(pairs: &Pairs) -> Warm {
        let mut warm = Warm::default();
        for ((a, b), kept) in pairs {
            match (*b == usize::MAX, kept.first()) {
                (true, Some(k)) => warm.keep_pin(*a, *k),
                (true, None) => {}
                (false, _) => kept.iter().for_each(|k| warm.keep((*a != usize::MAX).then_some(*a), *b, *k)),
            }
        }
        warm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kept(x: f64) -> Kept {
        (Vector3::new(x, 0.0, 0.0), [x; 3], [2.0 * x; 3])
    }

    /// Contacts kept out of pair order, a floor contact and a pin come back in the order of their
    /// pairs, each pair's contacts in the order kept, and the carried form gives the same store.
    #[test]
    fn pairs_come_back_in_order_and_round_trip() {
        let mut w = Warm::default();
        w.keep(Some(3), 5, kept(1.0));
        w.keep(None, 5, kept(2.0));
        w.keep(Some(0), 5, kept(3.0));
        w.keep(Some(3), 5, kept(4.0));
        w.keep_pin(1, kept(5.0));
        w.keep(Some(1), 2, kept(6.0));
        let pairs = w.pairs();
        let keys: Vec<_> = pairs.iter().map(|p| p.0).collect();
        assert_eq!(keys, vec![(0, 5), (1, 2), (1, usize::MAX), (3, 5), (usize::MAX, 5)]);
        assert_eq!(pairs[3].1, vec![kept(1.0), kept(4.0)]);
        assert_eq!(Warm::from_pairs(&pairs).pairs(), pairs);
        let near: Vec<_> = w.between(Some(3), 5).copied().collect();
        assert_eq!(near, vec![kept(1.0), kept(4.0)]);
        assert_eq!(w.between(None, 5).count(), 1);
        assert_eq!(w.between(Some(2), 9).count(), 0);
        assert_eq!(w.pin(1), Some(&kept(5.0)));
    }

    /// Cleared, the store holds nothing, a pin included.
    #[test]
    fn cleared_it_holds_nothing() {
        let mut w = Warm::default();
        w.keep(Some(0), 1, kept(1.0));
        w.keep_pin(0, kept(2.0));
        w.clear();
        assert!(w.pairs().is_empty());
        assert_eq!(w.pin(0), None);
    }
}
