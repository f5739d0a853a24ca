//! Islands: the bodies joined by contacts and by pins between bodies (the floor and the world
//! join nothing), each with the contacts and pins among them, renumbered from nought. Bodies of
//! different islands never share a row, so each island is a problem of its own, and a pool of
//! threads takes them one at a time without waiting between colours.

use crate::contact::Touch;
use lagra_checker::model::Pin;

/// One island: its bodies' indices in the state, in order; the touches and pins among them with
/// their bodies renumbered into that list (in the order they were found); each pin's index in
/// the scene (its warm start's key).
pub struct Island {
    pub bodies: Vec<usize>,
    pub touches: Vec<Touch>,
    pub pins: Vec<(usize, Pin)>,
}

impl Island {
    /// The islands of `n` bodies joined by `touches` and `pins`, ordered by their first body; a
    /// body that touches nothing is in none.
    pub fn all(touches: &[Touch], pins: &[Pin], n: usize) -> Vec<Island> {
        let mut root: Vec<usize> = (0..n).collect();
        let mut joined = vec![false; n];
        let links = touches.iter().map(|t| (t.a, t.b)).chain(pins.iter().map(|p| (p.a, p.b)));
        for (a, b) in links {
            joined[b] = true;
            if let Some(a) = a {
                joined[a] = true;
                let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                root[ra.max(rb)] = ra.min(rb);
            }
        }
        // each island's root is its lowest body, so numbering the roots in order numbers the
        // islands by their first body
        let mut island = vec![usize::MAX; n];
        let mut local = vec![0; n];
        let mut islands: Vec<Island> = vec![];
        for i in (0..n).filter(|&i| joined[i]) {
            let r = find(&mut root, i);
            if r == i {
                island[i] = islands.len();
                islands.push(Island { bodies: vec![], touches: vec![], pins: vec![] });
            }
            island[i] = island[r];
            local[i] = islands[island[i]].bodies.len();
            islands[island[i]].bodies.push(i);
        }
        for t in touches {
            let (a, b) = (t.a.map(|a| local[a]), local[t.b]);
            islands[island[t.b]].touches.push(Touch { a, b, ..*t });
        }
        for (j, p) in pins.iter().enumerate() {
            let (a, b) = (p.a.map(|a| local[a]), local[p.b]);
            islands[island[p.b]].pins.push((j, Pin { a, b, ..*p }));
        }
        islands
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
        let islands = Island::all(&touches, &pins, 7);
        let bodies: Vec<_> = islands.iter().map(|i| i.bodies.clone()).collect();
        assert_eq!(bodies, vec![vec![0, 2], vec![1, 3], vec![4, 5]]);
        let pairs = |i: &Island| i.touches.iter().map(|t| (t.a, t.b)).collect::<Vec<_>>();
        assert_eq!(pairs(&islands[0]), vec![(None, 0), (Some(0), 1)]);
        assert_eq!(pairs(&islands[1]), vec![(None, 0), (Some(0), 1)]);
        assert_eq!(islands[2].pins, vec![(0, Pin { a: Some(0), b: 1, on_a: [0.0; 3], on_b: [0.0; 3] })]);
    }

    /// A chain joined out of order (3–1, then 1–2, 0 alone on the floor) is one island whose
    /// root is its lowest body.
    #[test]
    fn a_chain_found_out_of_order_is_one_island() {
        let touches = [touch(Some(1), 3), touch(None, 0), touch(Some(1), 2)];
        let islands = Island::all(&touches, &[], 4);
        let bodies: Vec<_> = islands.iter().map(|i| i.bodies.clone()).collect();
        assert_eq!(bodies, vec![vec![0], vec![1, 2, 3]]);
        let pairs: Vec<_> = islands[1].touches.iter().map(|t| (t.a, t.b)).collect();
        assert_eq!(pairs, vec![(Some(0), 2), (Some(0), 1)]);
    }
}
