//! What the domains say to each other: four collectives and an exchange among neighbours,
//! enough for ghosts, migration, the step's agreement, a thermostat's sums and the gather. MPI provides them in the binary (`src/ranks.rs`, the `mpi`
//! feature); `Alone` is one rank; `Threads` (tests) runs the ranks as threads of one process,
//! so the decomposition is tested without MPI.

/// The collectives of a job of `size` ranks. Every rank calls each, in the same order.
pub trait Exchange {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// Sends `out[r]` to rank r, for every r; returns what each rank sent to this one, in rank
    /// order.
    fn all_to_all(&self, out: Vec<Vec<f64>>) -> Vec<Vec<f64>>;
    /// Each entry becomes its largest over the ranks.
    fn max(&self, x: &mut [f64]);
    /// Rank 0's value, on every rank.
    fn broadcast(&self, x: &mut u64);
    /// Every rank's `mine` (as long on each), one after another in rank order, on every rank.
    fn all_gather(&self, mine: &[f64]) -> Vec<f64> {
        self.all_to_all(vec![mine.to_vec(); self.size()]).concat()
    }
    /// Sends `out[k]` to rank `peers[k]` and returns what each peer sent here, in the same
    /// order: an exchange among neighbours only, every rank's `peers` naming it back. By
    /// default through `all_to_all`; MPI's sends and receives only to the peers.
    fn swap(&self, peers: &[usize], out: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        let mut all = vec![vec![]; self.size()];
        peers.iter().zip(out).for_each(|(&p, o)| all[p] = o);
        let mut got = self.all_to_all(all);
        peers.iter().map(|&p| std::mem::take(&mut got[p])).collect()
    }
}

/// A job of one rank.
pub struct Alone;

impl Exchange for Alone {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_to_all(&self, out: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        out
    }
    fn max(&self, _: &mut [f64]) {}
    fn broadcast(&self, _: &mut u64) {}
}

#[cfg(test)]
pub use threads::Threads;

#[cfg(test)]
mod threads {
    use super::Exchange;
    use std::sync::{Arc, Barrier, Mutex};

    /// The ranks of a job as threads: a mailbox per (to, from) and a barrier around each
    /// collective, so that no rank reads before every rank has written.
    #[derive(Clone)]
    pub struct Threads {
        rank: usize,
        size: usize,
        boxes: Arc<Mutex<Vec<Vec<Vec<f64>>>>>,
        barrier: Arc<Barrier>,
    }

    impl Threads {
        /// The `size` ranks of one job, to hand a thread each.
        pub fn job(size: usize) -> Vec<Threads> {
            let boxes = Arc::new(Mutex::new(vec![vec![vec![]; size]; size]));
            let barrier = Arc::new(Barrier::new(size));
            (0..size).map(|rank| Threads { rank, size, boxes: boxes.clone(), barrier: barrier.clone() }).collect()
        }
    }

    impl Exchange for Threads {
        fn rank(&self) -> usize {
            self.rank
        }
        fn size(&self) -> usize {
            self.size
        }
        fn all_to_all(&self, out: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
            {
                let mut b = self.boxes.lock().unwrap();
                out.into_iter().enumerate().for_each(|(to, m)| b[to][self.rank] = m);
            }
            self.barrier.wait();
            // taken one by one, leaving empty mail: a rank past the next barrier may write again
            let got = self.boxes.lock().unwrap()[self.rank].iter_mut().map(std::mem::take).collect();
            self.barrier.wait();
            got
        }
        fn max(&self, x: &mut [f64]) {
            let all = self.all_to_all(vec![x.to_vec(); self.size]);
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = all.iter().map(|a| a[i]).fold(f64::NEG_INFINITY, f64::max);
            }
        }
        fn broadcast(&self, x: &mut u64) {
            // the bits travel, not the value
            let out = if self.rank == 0 { vec![vec![f64::from_bits(*x)]; self.size] } else { vec![vec![]; self.size] };
            *x = self.all_to_all(out)[0][0].to_bits();
        }
    }
}
