//! The periodic box cut into bricks, one a rank: which rank owns a point, and which ranks'
//! bricks lie within a halo of it (those that need it as a ghost).

/// A grid of px × py × pz equal bricks over a box of `size`; rank = x + px·(y + py·z).
#[derive(Clone, Debug, PartialEq)]
pub struct Bricks {
    pub counts: [usize; 3],
    size: [f64; 3],
}

impl Bricks {
    /// The grid for `ranks` whose bricks have the smallest halo, among those whose cut axes
    /// leave bricks at least `halo` wide (a narrower brick would take most of its atoms as
    /// ghosts). Ties go to the first in (px descending, then py) order, so every rank agrees.
    pub fn chosen(ranks: usize, size: [f64; 3], halo: f64) -> Result<Bricks, String> {
        let mut best: Option<(f64, Bricks)> = None;
        for px in (1..=ranks).rev().filter(|p| ranks.is_multiple_of(*p)) {
            for py in (1..=ranks / px).rev().filter(|p| (ranks / px).is_multiple_of(*p)) {
                let b = Bricks { counts: [px, py, ranks / px / py], size };
                if b.narrowest(halo).is_some() {
                    continue;
                }
                let cut = b.halo_volume(halo);
                if best.as_ref().is_none_or(|(c, _)| cut < *c) {
                    best = Some((cut, b));
                }
            }
        }
        best.map(|b| b.1).ok_or_else(|| {
            let most = size.map(|l| (l / halo).floor().max(1.0) as usize);
            format!(
                "{ranks} ranks cannot share this box ({} × {} × {}): every way of cutting it leaves a brick \
                 narrower than the cut-off plus skin, {halo:.4}; at most {} × {} × {} bricks fit",
                size[0], size[1], size[2], most[0], most[1], most[2]
            )
        })
    }

    /// The grid `spec` names ("2x2x1"), which must hold `ranks` bricks at least `halo` wide.
    pub fn given(spec: &str, ranks: usize, size: [f64; 3], halo: f64) -> Result<Bricks, String> {
        let bad = || format!("--grid {spec}: expected three positive counts like 2x2x1");
        let n: Vec<usize> =
            spec.split(['x', 'X', '×']).map(|s| s.trim().parse().map_err(|_| bad())).collect::<Result<_, _>>()?;
        let counts: [usize; 3] = n.try_into().map_err(|_| bad())?;
        if counts.contains(&0) {
            return Err(bad());
        }
        if counts.iter().product::<usize>() != ranks {
            return Err(format!(
                "--grid {spec} has {} bricks, but the job has {ranks} ranks: the grid must have one a rank",
                counts.iter().product::<usize>()
            ));
        }
        let b = Bricks { counts, size };
        match b.narrowest(halo) {
            Some((axis, w)) => Err(format!(
                "--grid {spec}: a brick would be {w:.4} wide along {}, less than the cut-off plus skin, {halo:.4}",
                ["x", "y", "z"][axis]
            )),
            None => Ok(b),
        }
    }

    /// A cut axis along which a brick is narrower than `halo`, and its width.
    fn narrowest(&self, halo: f64) -> Option<(usize, f64)> {
        (0..3).map(|a| (a, self.size[a] / self.counts[a] as f64)).find(|&(a, w)| self.counts[a] > 1 && w < halo)
    }

    /// The volume of a brick's halo: the brick grown by `halo` across each cut axis, less the
    /// brick (what the ghosts a rank takes grow with).
    fn halo_volume(&self, halo: f64) -> f64 {
        let w = [0, 1, 2].map(|a| self.size[a] / self.counts[a] as f64);
        let grown: f64 = (0..3).map(|a| w[a] + if self.counts[a] > 1 { 2.0 * halo } else { 0.0 }).product();
        grown - w.iter().product::<f64>()
    }

    pub fn ranks(&self) -> usize {
        self.counts.iter().product()
    }

    /// Along an axis, the brick a coordinate falls in (taken into the box first).
    fn index(&self, a: usize, x: f64) -> usize {
        let l = self.size[a];
        let u = x.rem_euclid(l);
        ((u / l * self.counts[a] as f64) as usize).min(self.counts[a] - 1)
    }

    fn rank_of(&self, k: [usize; 3]) -> usize {
        k[0] + self.counts[0] * (k[1] + self.counts[1] * k[2])
    }

    /// The middle of `rank`'s brick.
    pub fn centre(&self, rank: usize) -> [f64; 3] {
        let p = self.counts;
        let k = [rank % p[0], rank / p[0] % p[1], rank / (p[0] * p[1])];
        std::array::from_fn(|a| (k[a] as f64 + 0.5) * self.size[a] / p[a] as f64)
    }

    /// The ranks whose bricks touch `rank`'s, across faces, edges and corners (through the
    /// periodic box), ascending, without `rank`: where its ghosts and migrants can go, since a
    /// brick is at least a halo wide.
    pub fn peers(&self, rank: usize) -> Vec<usize> {
        let p = self.counts;
        let k = [rank % p[0], rank / p[0] % p[1], rank / (p[0] * p[1])];
        let mut peers = vec![];
        for dz in [p[2] - 1, 0, 1] {
            for dy in [p[1] - 1, 0, 1] {
                for dx in [p[0] - 1, 0, 1] {
                    let d = [dx, dy, dz];
                    peers.push(self.rank_of([0, 1, 2].map(|a| (k[a] + d[a]) % p[a])));
                }
            }
        }
        peers.sort_unstable();
        peers.dedup();
        peers.retain(|&r| r != rank);
        peers
    }

    /// The rank that owns a point.
    pub fn owner(&self, x: [f64; 3]) -> usize {
        self.rank_of([0, 1, 2].map(|a| self.index(a, x[a])))
    }

    /// Every rank whose brick lies nearer than `halo` to the point, through the periodic box
    /// (its owner among them), each once. A brick is at least `halo` wide along a cut axis
    /// (`chosen`, `given`), so along each only the point's brick and its two neighbours can be.
    pub fn near(&self, x: [f64; 3], halo: f64, mut visit: impl FnMut(usize)) {
        // per axis: up to three bricks within the halo and the distance to each (0 inside)
        let mut along = [[(0, 0.0); 3]; 3];
        let mut count = [1; 3];
        for a in 0..3 {
            let (l, p) = (self.size[a], self.counts[a]);
            let home = self.index(a, x[a]);
            along[a][0] = (home, 0.0);
            if p == 1 {
                continue;
            }
            let w = l / p as f64;
            let u = x[a].rem_euclid(l);
            for k in [(home + p - 1) % p, (home + 1) % p] {
                let past = (u - k as f64 * w).rem_euclid(l);
                let d = if past < w { 0.0 } else { (past - w).min(l - past) };
                if d < halo && along[a][..count[a]].iter().all(|c| c.0 != k) {
                    along[a][count[a]] = (k, d);
                    count[a] += 1;
                }
            }
        }
        for &(kz, dz) in &along[2][..count[2]] {
            for &(ky, dy) in &along[1][..count[1]] {
                for &(kx, dx) in &along[0][..count[0]] {
                    if dx * dx + dy * dy + dz * dz < halo * halo {
                        visit(self.rank_of([kx, ky, kz]));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_cube_cut_for_four_ranks_is_cut_across_two_axes() {
        assert_eq!(Bricks::chosen(4, [10.0; 3], 2.8).unwrap().counts, [2, 2, 1]);
        // halos of 2,307 against 2,796 (2×2×2); 4,480 against 5,107 (4×2×1)
        assert_eq!(Bricks::chosen(8, [20.0; 3], 2.8).unwrap().counts, [4, 2, 1]);
        assert_eq!(Bricks::chosen(8, [80.0, 40.0, 20.0], 2.8).unwrap().counts, [8, 1, 1]);
        assert_eq!(Bricks::chosen(2, [10.0, 30.0, 10.0], 2.8).unwrap().counts, [1, 2, 1]);
    }

    #[test]
    fn a_brick_has_up_to_26_peers_each_once() {
        let b = |counts| Bricks { counts, size: [30.0; 3] };
        assert_eq!(b([3, 3, 3]).peers(13).len(), 26);
        assert_eq!(b([2, 1, 1]).peers(0), [1]);
        assert_eq!(b([2, 2, 1]).peers(3), [0, 1, 2]);
        assert_eq!(b([4, 1, 1]).peers(0), [1, 3]);
        assert!(b([1, 1, 1]).peers(0).is_empty());
    }

    #[test]
    fn too_many_ranks_for_the_box_is_said() {
        let e = Bricks::chosen(64, [10.0; 3], 2.8).unwrap_err();
        assert!(e.contains("64 ranks cannot share") && e.contains("3 × 3 × 3"), "{e}");
        assert!(Bricks::given("4x1x1", 4, [10.0; 3], 2.8).unwrap_err().contains("2.5000 wide along x"));
        assert!(Bricks::given("2x2", 4, [10.0; 3], 2.8).unwrap_err().contains("three positive counts"));
        assert!(Bricks::given("2x2x2", 4, [10.0; 3], 2.8).unwrap_err().contains("has 8 bricks"));
        assert_eq!(Bricks::given("1x2x2", 4, [10.0; 3], 2.8).unwrap().counts, [1, 2, 2]);
    }

    proptest! {
        /// Every point has one owner, inside the box or out of it (an atom's image), and the
        /// ranks near it are exactly those whose brick some point within the halo falls in.
        #[test]
        fn the_ranks_near_a_point_are_those_a_nearby_point_falls_in(
            x in prop::array::uniform3(-30.0f64..40.0),
            step in prop::array::uniform3(-1.0f64..1.0),
            grid in prop::sample::select(vec![[2, 1, 1], [2, 2, 1], [3, 2, 2], [1, 1, 4]]),
        ) {
            let (size, halo) = ([10.0, 12.0, 13.0], 2.8);
            let b = Bricks { counts: grid, size };
            let mut near = vec![];
            b.near(x, halo, |r| near.push(r));
            let owner = b.owner(x);
            prop_assert!(owner < b.ranks() && near.contains(&owner));
            let mut sorted = near.clone();
            sorted.sort();
            sorted.dedup();
            prop_assert_eq!(sorted.len(), near.len());
            // every rank near the point other than its owner is a peer of the owner's, and back
            let peers = b.peers(owner);
            prop_assert!(near.iter().all(|r| *r == owner || peers.contains(r)));
            prop_assert!(peers.iter().all(|&r| b.peers(r).contains(&owner)));
            // a point a little less than the halo away falls in a rank listed as near
            let n = (step[0] * step[0] + step[1] * step[1] + step[2] * step[2]).sqrt().max(1e-9);
            let y = [0, 1, 2].map(|a| x[a] + step[a] / n * halo * 0.999);
            prop_assert!(near.contains(&b.owner(y)), "{:?} owns {:?}, not in {:?}", b.owner(y), y, near);
            // the owner's image a box away is the same rank
            prop_assert_eq!(b.owner([x[0] + 10.0, x[1] - 12.0, x[2] + 26.0]), owner);
        }
    }
}
