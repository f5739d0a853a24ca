//! Which contacts touch each body, and the colours AVBD sweeps them in: bodies in contact
//! never share a colour, so a colour's bodies descend at once, and the colours climb from the
//! floor, so a sweep carries support up a tower in one pass.

use super::Contact;

/// Which contacts touch each body (and whether as b), and the colours: bodies in contact with
/// one another never share one, so a colour's bodies descend at once.
pub(super) struct Rows {
    pub of: Vec<Vec<(usize, bool)>>,
    pub colours: Vec<Vec<usize>>,
    /// Whether a body reaches the floor or the world through contacts and pins.
    pub grounded: Vec<bool>,
}

impl Rows {
    /// Colours by level: a body's level is its distance in contacts from the world (the floor,
    /// or a pin to it), and each level is coloured greedily in body order among its own bodies,
    /// so the colours run from the ground up. Fixed by the state, so the same for any thread
    /// count. A body in no contact takes none; a group touching nothing fixed counts its levels
    /// from its lowest-numbered body.
    pub fn of(contacts: &[Contact], n: usize) -> Rows {
        let mut of = vec![vec![]; n];
        for (j, c) in contacts.iter().enumerate() {
            of[c.b].push((j, true));
            if let Some(a) = c.a {
                of[a].push((j, false));
            }
        }
        let other = |(j, as_b): (usize, bool)| if as_b { contacts[j].a } else { Some(contacts[j].b) };
        let mut level = vec![usize::MAX; n];
        let mut queue = std::collections::VecDeque::new();
        for i in 0..n {
            if of[i].iter().any(|&r| other(r).is_none()) {
                level[i] = 0;
                queue.push_back(i);
            }
        }
        let mut seeds = 0..n;
        let mut grounded = None;
        loop {
            while let Some(i) = queue.pop_front() {
                for &r in &of[i] {
                    if let Some(k) = other(r).filter(|&k| level[k] == usize::MAX) {
                        level[k] = level[i] + 1;
                        queue.push_back(k);
                    }
                }
            }
            grounded.get_or_insert_with(|| level.iter().map(|&l| l != usize::MAX).collect::<Vec<bool>>());
            match seeds.find(|&i| level[i] == usize::MAX && !of[i].is_empty()) {
                Some(i) => {
                    level[i] = 0;
                    queue.push_back(i);
                }
                None => break,
            }
        }
        let mut order: Vec<usize> = (0..n).filter(|&i| !of[i].is_empty()).collect();
        order.sort_by_key(|&i| (level[i], i));
        let mut colour: Vec<usize> = vec![usize::MAX; n];
        let mut colours: Vec<Vec<usize>> = vec![];
        let mut taken: Vec<bool> = vec![];
        let mut first = 0;
        let mut current = 0;
        for i in order {
            if level[i] != current {
                (current, first) = (level[i], colours.len());
            }
            taken.clear();
            taken.resize(colours.len() + 1, false);
            for &r in &of[i] {
                if let Some(k) = other(r).filter(|&k| colour[k] != usize::MAX && colour[k] >= first) {
                    taken[colour[k]] = true;
                }
            }
            let free = first + taken[first..].iter().position(|t| !t).expect("one more colour than are taken");
            if free == colours.len() {
                colours.push(vec![]);
            }
            colours[free].push(i);
            colour[i] = free;
        }
        Rows { of, colours, grounded: grounded.expect("set after the first pass") }
    }
}
