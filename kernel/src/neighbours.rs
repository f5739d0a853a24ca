//! The Verlet neighbour list: for each body, the bodies after it in traversal order that lie
//! within reach + skin, each pair once (Newton's third law), with the periodic image it was found
//! at.
//!
//! At a build the bodies are sorted into cell order (`traverse::Binned`) and the list is kept in
//! that order: position b holds body `bodies[b]`, and a pair names its partner by position, so
//! that the pair loop reads neighbours that sit together in memory. Each body is wrapped into the
//! box and its wrap offset kept; between builds the kernel reads positions minus those fixed
//! offsets (`wrapped`, gathered into cell order every step), which move continuously, so a
//! listed pair's image stays right. The list is rebuilt once the two bodies that moved most since
//! the last build have together moved more than the skin: until then no unlisted pair can have
//! come within reach.

use crate::traverse::Binned;
use lagra_checker::model::Cell;
use rayon::prelude::*;
use rayon::ThreadPool;
use std::ops::Range;

/// The skin as a fraction of the reach (LAMMPS's 0.3 for a 2.5 cutoff).
const SKIN: f64 = 0.12;

/// A listed neighbour: its position in the list's order in the low 27 bits, the index of the
/// image shift to add to xⱼ − xᵢ (`Neighbours::shifts`) in the high 5. One word per pair: the
/// pair loop reads one stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair(u32);

impl Pair {
    /// Bodies a list can index (larger scenes get no list).
    pub const BODIES: usize = 1 << 27;
    fn new(j: usize, image: u8) -> Pair {
        Pair(j as u32 | u32::from(image) << 27)
    }
    #[inline(always)]
    pub fn j(self) -> usize {
        (self.0 & (Self::BODIES as u32 - 1)) as usize
    }
    #[inline(always)]
    pub fn image(self) -> usize {
        (self.0 >> 27) as usize
    }
}

#[derive(Clone)]
pub struct Neighbours {
    pub reach: f64,
    pub skin: f64,
    /// The body at each position of the list's order.
    pub bodies: Vec<u32>,
    /// The pairs of position b are `pairs[start[b]..start[b + 1]]`.
    pub start: Vec<usize>,
    pub pairs: Vec<Pair>,
    /// The periodic image shifts by index (27 used; 32, so that any 5-bit index is in bounds and
    /// the pair loop needs no check).
    pub shifts: [[f64; 3]; 32],
    /// Positions at the last build, by body.
    at: Vec<[f64; 3]>,
    /// What was taken off each body to wrap it into the box at the last build, by position.
    offset: Vec<[f64; 3]>,
    /// The positions minus `offset`, by position, as of the last `update`: what the pair loop
    /// reads.
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
            bodies: vec![],
            start: vec![],
            pairs: vec![],
            shifts,
            at: vec![],
            offset: vec![],
            wrapped: vec![],
            builds: 0,
        })
    }

    /// Rebuilds the list if two bodies together moved more than the skin since the last build,
    /// and gathers the wrapped positions in the list's order.
    pub fn update(&mut self, x: &[[f64; 3]], cell: &Option<Cell>, pool: Option<&ThreadPool>) {
        // A pair the list left out was at least reach + skin apart at the build; it can have
        // come within reach only if its two bodies together moved more than the skin, so the
        // two largest displacements decide (less often than "one body moved half the skin",
        // and as exact). The 1e-9 keeps the test on the safe side of rounding.
        let (mut first, mut second) = (0.0f64, 0.0f64);
        for (p, q) in x.iter().zip(&self.at) {
            let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
            if d2 > second {
                (first, second) = if d2 > first { (d2, first) } else { (first, d2) };
            }
        }
        if self.at.len() != x.len() || !(first.sqrt() + second.sqrt() < self.skin * (1.0 - 1e-9)) {
            self.build(x, cell, pool);
        }
        self.wrapped.clear();
        self.wrapped.extend(self.bodies.iter().zip(&self.offset).map(|(&i, o)| {
            let p = x[i as usize];
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        }));
    }

    fn build(&mut self, x: &[[f64; 3]], cell: &Option<Cell>, pool: Option<&ThreadPool>) {
        let r = self.reach + self.skin;
        self.at.clear();
        self.at.extend_from_slice(x);
        let offset: Vec<[f64; 3]> = x
            .iter()
            .map(|p| match cell {
                None => [0.0; 3],
                Some(c) => {
                    std::array::from_fn(|a| if c.periodic[a] { c.size[a] * (p[a] / c.size[a]).floor() } else { 0.0 })
                }
            })
            .collect();
        let wrapped: Vec<[f64; 3]> =
            x.iter().zip(&offset).map(|(p, o)| [p[0] - o[0], p[1] - o[1], p[2] - o[2]]).collect();
        let binned = Binned::new(&wrapped, cell, r);
        self.bodies.clear();
        match &binned {
            Some(b) => self.bodies.extend(b.order.iter().map(|&i| i as u32)),
            None => self.bodies.extend(0..x.len() as u32),
        }
        self.offset.clear();
        self.offset.extend(self.bodies.iter().map(|&i| offset[i as usize]));
        self.wrapped.clear();
        self.wrapped.extend(self.bodies.iter().map(|&i| wrapped[i as usize]));
        let reach = self.reach;
        let Neighbours { start, pairs, shifts, wrapped: w, .. } = self;
        start.clear();
        match &binned {
            // in cell order, in as many parts as there are threads, each listed on its own and
            // joined in order: the same list as one pass makes, for any thread count
            Some(b) => {
                pairs.clear();
                match pool {
                    Some(p) if p.current_num_threads() > 1 => {
                        let parts: Vec<(Vec<usize>, Vec<Pair>)> = p.install(|| {
                            b.split(p.current_num_threads())
                                .into_par_iter()
                                .map(|cells| {
                                    let (mut s, mut l) = (vec![], vec![]);
                                    listed_in(b, cells, w, shifts, (reach, r), &mut s, &mut l);
                                    (s, l)
                                })
                                .collect()
                        });
                        for (s, p) in parts {
                            let base = pairs.len();
                            start.extend(s.into_iter().map(|k| k + base));
                            pairs.extend_from_slice(&p);
                        }
                    }
                    // into the list itself, whose storage is kept from build to build
                    _ => listed_in(b, 0..b.cells(), w, shifts, (reach, r), start, pairs),
                }
            }
            // every pair, in body order
            None => {
                pairs.clear();
                for i in 0..w.len() {
                    start.push(pairs.len());
                    for j in i + 1..w.len() {
                        let d = Cell::image(cell, std::array::from_fn(|a| w[j][a] - w[i][a]));
                        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r {
                            pairs.push(Pair::new(j, image_of(shifts, &w[i], &w[j], d)));
                        }
                    }
                }
            }
        }
        start.push(pairs.len());
        self.builds += 1;
    }

    pub fn count(&self) -> usize {
        self.pairs.len()
    }
}

/// Appends the pairs within `reach` + skin (`r`) of the positions in `cells`, and where each
/// position's start in `pairs`: first those within `reach` at the build, then those in the skin,
/// so that the pair loop's cutoff test is nearly always the same as for the pair before (the
/// bodies move little between builds), not a coin toss. Every candidate is written to both
/// places, and kept by advancing the end of one of them: no branch to mispredict either.
#[allow(clippy::too_many_arguments)]
fn listed_in(
    b: &Binned,
    cells: Range<usize>,
    w: &[[f64; 3]],
    shifts: &[[f64; 3]; 32],
    (reach, r): (f64, f64),
    start: &mut Vec<usize>,
    pairs: &mut Vec<Pair>,
) {
    let mut end = pairs.len();
    let (inner, r2) = (reach * reach, r * r);
    let mut shell: Vec<Pair> = vec![];
    b.each_in(cells, |i, runs| {
        start.push(end);
        let xi = w[i];
        let mut outer = 0;
        for (run, k) in runs {
            if pairs.len() < end + run.len() {
                pairs.resize((2 * pairs.len()).max(end + run.len() + 1024), Pair(0));
            }
            if shell.len() < outer + run.len() {
                shell.resize(outer + run.len() + 256, Pair(0));
            }
            let s = &shifts[*k as usize];
            let (o0, o1, o2) = (s[0] - xi[0], s[1] - xi[1], s[2] - xi[2]);
            for j in run.clone() {
                let p = &w[j];
                let (d0, d1, d2) = (p[0] + o0, p[1] + o1, p[2] + o2);
                let d2 = d0 * d0 + d1 * d1 + d2 * d2;
                (pairs[end], shell[outer]) = (Pair::new(j, *k), Pair::new(j, *k));
                end += usize::from(d2 < inner);
                outer += usize::from(inner <= d2 && d2 < r2);
            }
        }
        if pairs.len() < end + outer {
            pairs.resize(end + outer + 1024, Pair(0));
        }
        pairs[end..end + outer].copy_from_slice(&shell[..outer]);
        end += outer;
    });
    pairs.truncate(end);
}

/// The index of the shift d − (xⱼ − xᵢ) between wrapped positions: −1, 0 or 1 box length per
/// axis.
fn image_of(shifts: &[[f64; 3]; 32], xi: &[f64; 3], xj: &[f64; 3], d: [f64; 3]) -> u8 {
    let mut k = 0;
    for a in (0..3).rev() {
        let len = shifts[26][a];
        let n = if len > 0.0 { ((d[a] - (xj[a] - xi[a])) / len).round() as i64 } else { 0 };
        k = 3 * k + (n + 1) as u8;
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::dual::Rng;
    use crate::traverse;
    use proptest::prelude::*;

    proptest! {
        /// After the bodies move so that no two together moved the skin (one up to 0.7 of it, the
        /// rest up to 0.29), the stale list still holds every pair within reach, and its stored
        /// image gives the minimum-image displacement.
        #[test]
        fn a_stale_list_still_holds_every_pair_within_reach(seed in any::<u64>(), n in 64usize..300, side in 7.0f64..14.0, periodic in any::<bool>()) {
            let mut rng = Rng::new(seed);
            let cell = periodic.then_some(Cell { size: [side; 3], periodic: [true, true, rng.uniform(0.0, 1.0) < 0.5] });
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
            let mut listed = vec![];
            prop_assert_eq!(list.bodies.len(), n);
            for b in 0..n {
                let i = list.bodies[b] as usize;
                for k in list.start[b]..list.start[b + 1] {
                    let (jb, w) = (list.pairs[k].j(), &list.wrapped);
                    let j = list.bodies[jb] as usize;
                    let s = list.shifts[list.pairs[k].image()];
                    let d: [f64; 3] = std::array::from_fn(|a| w[jb][a] - w[b][a] + s[a]);
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

    /// A list built in parts on 2 or 3 threads is the list one pass builds.
    #[test]
    fn the_list_is_the_same_on_any_number_of_threads() {
        let mut rng = Rng::new(11);
        let cell = Some(Cell { size: [16.0; 3], periodic: [true; 3] });
        let x: Vec<[f64; 3]> = (0..3000).map(|_| std::array::from_fn(|_| rng.uniform(-4.0, 20.0))).collect();
        let built = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut list = Neighbours::new(&cell, 2.5).unwrap();
            list.update(&x, &cell, (threads > 1).then_some(&pool));
            (list.bodies, list.start, list.pairs)
        };
        let one = built(1);
        assert!(one.2.len() > 50_000, "{}", one.2.len());
        assert!(built(2) == one && built(3) == one);
    }

    /// At a build each body's pairs within reach come first, then those in the skin.
    #[test]
    fn pairs_within_reach_come_before_the_skin() {
        let mut rng = Rng::new(5);
        let cell = Some(Cell { size: [16.0; 3], periodic: [true; 3] });
        let x: Vec<[f64; 3]> = (0..3000).map(|_| std::array::from_fn(|_| rng.uniform(-4.0, 20.0))).collect();
        let mut list = Neighbours::new(&cell, 2.5).unwrap();
        list.update(&x, &cell, None);
        let (w, mut shell) = (&list.wrapped, 0);
        for b in 0..x.len() {
            let inside: Vec<bool> = (list.start[b]..list.start[b + 1])
                .map(|k| {
                    let (jb, s) = (list.pairs[k].j(), list.shifts[list.pairs[k].image()]);
                    (0..3).map(|a| (w[jb][a] - w[b][a] + s[a]).powi(2)).sum::<f64>() < 2.5 * 2.5
                })
                .collect();
            assert!(inside.windows(2).all(|p| p[0] >= p[1]), "body {b}: {inside:?}");
            shell += inside.iter().filter(|&&i| !i).count();
        }
        assert!(shell > list.count() / 5, "{shell} of {} in the skin", list.count());
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
}
