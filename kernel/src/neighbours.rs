//! The Verlet neighbour list: for each body, the bodies after it in traversal order that lie
//! within reach + skin, each pair once (Newton's third law), with the periodic image it was found
//! at. At a build every body is wrapped into the box and its wrap offset kept; between builds the
//! kernel reads positions minus those fixed offsets, which move continuously, so a listed pair's
//! image stays right. The list is rebuilt once some body has moved more than half the skin since
//! the last build: until then no unlisted pair can have come within reach.

use crate::traverse;
use lagra_checker::model::Cell;

/// The skin as a fraction of the reach (LAMMPS's 0.3 for a 2.5 cutoff).
const SKIN: f64 = 0.12;

pub struct Neighbours {
    pub reach: f64,
    pub skin: f64,
    /// CSR: the neighbours of body i are `j[start[i]..start[i + 1]]`, each with the image shift
    /// `shifts[image[k]]` to add to xⱼ − xᵢ (27 used; 32 so that `image & 31` needs no bounds
    /// check in the pair loop).
    pub start: Vec<usize>,
    pub j: Vec<u32>,
    pub image: Vec<u8>,
    pub shifts: [[f64; 3]; 32],
    /// Positions at the last build.
    at: Vec<[f64; 3]>,
    /// What was taken off each body to wrap it into the box at the last build.
    offset: Vec<[f64; 3]>,
    /// The positions minus `offset`, as of the last `update`: what the pair loop reads.
    pub wrapped: Vec<[f64; 3]>,
    pub builds: u64,
}

impl Neighbours {
    /// `None` where a list could pick the wrong image: a periodic axis shorter than twice
    /// reach + skin.
    pub fn new(cell: &Option<Cell>, reach: f64) -> Option<Neighbours> {
        let skin = SKIN * reach;
        let mut shifts = [[0.0; 3]; 32];
        if let Some(c) = cell {
            for a in 0..3 {
                if c.periodic[a] && c.size[a] <= 2.0 * (reach + skin) {
                    return None;
                }
            }
            for (k, s) in shifts.iter_mut().enumerate().take(27) {
                let n = [k % 3, (k / 3) % 3, k / 9];
                *s = std::array::from_fn(|a| (n[a] as f64 - 1.0) * c.size[a]);
            }
        }
        Some(Neighbours {
            reach,
            skin,
            start: vec![],
            j: vec![],
            image: vec![],
            shifts,
            at: vec![],
            offset: vec![],
            wrapped: vec![],
            builds: 0,
        })
    }

    /// Rebuilds the list if some body moved more than half the skin since the last build.
    pub fn update(&mut self, x: &[[f64; 3]], cell: &Option<Cell>) {
        let limit = 0.25 * self.skin * self.skin;
        let moved = self.at.len() != x.len()
            || x.iter().zip(&self.at).any(|(p, q)| {
                let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > limit
            });
        if moved {
            self.build(x, cell);
        }
        self.wrapped.clear();
        self.wrapped.extend(x.iter().zip(&self.offset).map(|(p, o)| [p[0] - o[0], p[1] - o[1], p[2] - o[2]]));
    }

    fn build(&mut self, x: &[[f64; 3]], cell: &Option<Cell>) {
        let r = self.reach + self.skin;
        self.at = x.to_vec();
        self.offset = x
            .iter()
            .map(|p| match cell {
                None => [0.0; 3],
                Some(c) => {
                    std::array::from_fn(|a| if c.periodic[a] { c.size[a] * (p[a] / c.size[a]).floor() } else { 0.0 })
                }
            })
            .collect();
        let x: Vec<[f64; 3]> =
            x.iter().zip(&self.offset).map(|(p, o)| [p[0] - o[0], p[1] - o[1], p[2] - o[2]]).collect();
        let mut found: Vec<(u32, u32, u8)> = vec![];
        let within = |i: usize, j: usize, k: u8| {
            let s = &self.shifts[k as usize];
            let d = [x[j][0] - x[i][0] + s[0], x[j][1] - x[i][1] + s[1], x[j][2] - x[i][2] + s[2]];
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r
        };
        let binned = traverse::binned(&x, cell, r, |i, j, k| {
            if within(i, j, k) {
                found.push((i as u32, j as u32, k));
            }
        });
        if !binned {
            traverse::pairs::<()>(&x, cell, None, |i, j, d| {
                let k = self.image_of(&x[i], &x[j], d);
                if within(i, j, k) {
                    found.push((i as u32, j as u32, k));
                }
                Ok(())
            })
            .expect("the visitor never fails");
        }
        // CSR by the first body, by counting sort (stable: the traversal's order within a body)
        self.start = vec![0; x.len() + 1];
        found.iter().for_each(|p| self.start[p.0 as usize + 1] += 1);
        for i in 0..x.len() {
            self.start[i + 1] += self.start[i];
        }
        let mut next = self.start.clone();
        self.j = vec![0; found.len()];
        self.image = vec![0; found.len()];
        for (i, j, k) in found {
            let at = &mut next[i as usize];
            (self.j[*at], self.image[*at]) = (j, k);
            *at += 1;
        }
        self.builds += 1;
    }

    /// The index of the shift d − (xⱼ − xᵢ) between wrapped positions: −1, 0 or 1 box length per
    /// axis.
    fn image_of(&self, xi: &[f64; 3], xj: &[f64; 3], d: [f64; 3]) -> u8 {
        let mut k = 0;
        for a in (0..3).rev() {
            let len = self.shifts[26][a];
            let n = if len > 0.0 { ((d[a] - (xj[a] - xi[a])) / len).round() as i64 } else { 0 };
            k = 3 * k + (n + 1) as u8;
        }
        k
    }

    pub fn pairs(&self) -> usize {
        self.j.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::dual::Rng;
    use proptest::prelude::*;

    proptest! {
        /// After the bodies move by less than half the skin, the stale list still holds every
        /// pair within reach, and its stored image gives the minimum-image displacement.
        #[test]
        fn a_stale_list_still_holds_every_pair_within_reach(seed in any::<u64>(), n in 64usize..300, side in 7.0f64..14.0, periodic in any::<bool>()) {
            let mut rng = Rng::new(seed);
            let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, true, rng.uniform(0.0, 1.0) < 0.5] });
            let reach = 2.5;
            // bodies that have drifted out of the box, as unwrapped positions do in a long run
            let mut x: Vec<[f64; 3]> = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-3.0 * side, 4.0 * side))).collect();
            let mut list = Neighbours::new(&cell, reach).unwrap();
            list.update(&x, &cell);
            let half = 0.5 * list.skin / 3f64.sqrt();
            x.iter_mut().flatten().for_each(|c| *c += rng.uniform(-half, half));
            list.update(&x, &cell);
            prop_assert_eq!(list.builds, 1);
            let mut listed = vec![];
            for i in 0..n {
                for k in list.start[i]..list.start[i + 1] {
                    let j = list.j[k] as usize;
                    let s = list.shifts[list.image[k] as usize];
                    let w = &list.wrapped;
                    let d: [f64; 3] = std::array::from_fn(|a| w[j][a] - w[i][a] + s[a]);
                    if d.iter().map(|c| c * c).sum::<f64>() < reach * reach {
                        let exact = Cell::image(&cell, std::array::from_fn(|a| x[j][a] - x[i][a]));
                        prop_assert!((0..3).all(|a| (exact[a] - d[a]).abs() < 1e-9));
                        listed.push((i.min(j), i.max(j)));
                    }
                }
            }
            let mut all = vec![];
            traverse::pairs::<()>(&x, &cell, None, |i, j, d| {
                if d.iter().map(|c| c * c).sum::<f64>() < reach * reach { all.push((i.min(j), i.max(j))); }
                Ok(())
            }).unwrap();
            listed.sort();
            all.sort();
            prop_assert_eq!(listed, all);
        }
    }

    #[test]
    fn a_box_too_small_for_the_skin_gets_no_list() {
        let cell = Some(Cell { size: [5.0; 3], periodic: [true; 3] });
        assert!(Neighbours::new(&cell, 2.5).is_none());
        assert!(Neighbours::new(&None, 2.5).is_some());
    }
}
