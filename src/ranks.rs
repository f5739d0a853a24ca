//! The processes a command runs on: this one, or the ranks of an MPI job (`mpirun -np P lagra
//! ...`, built with `--features mpi`). MPI is started only when a launcher started this process
//! (it sets `OMPI_COMM_WORLD_SIZE` or `PMI_SIZE`): a plain `lagra` never touches it. A `lagra`
//! built without MPI but launched as one of several ranks refuses to go on, since every rank
//! would do the whole job and write the same files.

/// This process's place in the job.
pub struct World {
    /// Finalizes MPI when dropped: the world lives as long as the command's work.
    #[cfg(feature = "mpi")]
    universe: Option<mpi::environment::Universe>,
    pub rank: usize,
    pub size: usize,
}

/// The variables by which Open MPI's and MPICH's launchers (and Slurm's, through PMI) tell a
/// process the job's size, and its share of this machine.
const SIZE: [&str; 2] = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"];
const LOCAL_SIZE: [&str; 2] = ["OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"];

/// What the launcher says, for the names given: the first that reads as a number.
fn said(names: &[&str]) -> Option<usize> {
    names.iter().find_map(|n| std::env::var(n).ok()?.trim().parse().ok())
}

/// The prefixes of every variable a launcher sets: a child process that is not a rank (a sweep's
/// variant) must not believe it is one.
pub const LAUNCHER_VARIABLES: [&str; 3] = ["OMPI_", "PMI_", "PMIX_"];

impl World {
    /// This process alone.
    pub fn one() -> World {
        World {
            #[cfg(feature = "mpi")]
            universe: None,
            rank: 0,
            size: 1,
        }
    }

    /// The job this process belongs to: MPI's world if a launcher started it, else this process.
    pub fn join() -> Result<World, String> {
        let launched = said(&SIZE);
        #[cfg(feature = "mpi")]
        if launched.is_some() {
            use mpi::traits::Communicator;
            let universe = mpi::initialize().ok_or("MPI could not be started (it was started before)")?;
            let world = universe.world();
            let (rank, size) = (world.rank() as usize, world.size() as usize);
            return Ok(World { universe: Some(universe), rank, size });
        }
        match launched {
            Some(p) if p > 1 && cfg!(not(feature = "mpi")) => Err(format!(
                "started as one of {p} MPI ranks, but this lagra was built without MPI: every rank would do \
                 the whole job. Build it with `cargo build --release --features mpi` (after `bash setup.sh --mpi`), \
                 or run it without mpirun"
            )),
            _ => Ok(World::one()),
        }
    }

    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// How many ranks share this machine (the launcher says; one without a launcher).
    pub fn here(&self) -> usize {
        if self.size == 1 {
            1
        } else {
            said(&LOCAL_SIZE).unwrap_or(1).max(1)
        }
    }

    /// Every rank's bytes at rank 0, in rank order (`None` on the other ranks). A collective:
    /// every rank must call it. A rank that dies makes the launcher end the job; nothing here
    /// waits on it alone.
    pub fn gather(&self, mine: Vec<u8>) -> Option<Vec<Vec<u8>>> {
        #[cfg(feature = "mpi")]
        if let Some(u) = &self.universe {
            return gather(&u.world(), mine);
        }
        Some(vec![mine])
    }
}

/// The collectives a scene cut into domains needs (`lagra_run::domains`), over MPI's world.
#[cfg(feature = "mpi")]
pub struct Collectives(mpi::topology::SimpleCommunicator);

impl World {
    /// The world's collectives for the domains (`None` without MPI: one process).
    #[cfg(feature = "mpi")]
    pub fn collectives(&self) -> Option<Collectives> {
        self.universe.as_ref().map(|u| Collectives(u.world()))
    }
}

#[cfg(feature = "mpi")]
impl lagra_run::domains::exchange::Exchange for Collectives {
    fn rank(&self) -> usize {
        use mpi::traits::Communicator;
        self.0.rank() as usize
    }

    fn size(&self) -> usize {
        use mpi::traits::Communicator;
        self.0.size() as usize
    }

    /// MPI_Alltoall of the counts, then MPI_Alltoallv of the numbers.
    fn all_to_all(&self, out: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        use mpi::datatype::{Partition, PartitionMut};
        use mpi::traits::CommunicatorCollectives;
        use mpi::Count;
        let count = |n: usize| Count::try_from(n).expect("a message under 2^31 numbers");
        let starts = |c: &[Count]| c.iter().scan(0, |at, &n| Some(std::mem::replace(at, *at + n))).collect::<Vec<_>>();
        let sent: Vec<Count> = out.iter().map(|o| count(o.len())).collect();
        let mut got = vec![0 as Count; sent.len()];
        self.0.all_to_all_into(&sent[..], &mut got[..]);
        let flat: Vec<f64> = out.concat();
        let mut back = vec![0.0; got.iter().map(|&n| n as usize).sum()];
        let (from, to) = (starts(&sent), starts(&got));
        self.0.all_to_all_varcount_into(
            &Partition::new(&flat[..], &sent[..], &from[..]),
            &mut PartitionMut::new(&mut back[..], &got[..], &to[..]),
        );
        let mut at = 0;
        got.iter()
            .map(|&n| {
                at += n as usize;
                back[at - n as usize..at].to_vec()
            })
            .collect()
    }

    /// MPI_Allreduce with MPI_MAX.
    fn max(&self, x: &mut [f64]) {
        use mpi::collective::SystemOperation;
        use mpi::traits::CommunicatorCollectives;
        let mine = x.to_vec();
        self.0.all_reduce_into(&mine[..], x, SystemOperation::max());
    }

    /// MPI_Bcast from rank 0.
    fn broadcast(&self, x: &mut u64) {
        use mpi::traits::{Communicator, Root};
        self.0.process_at_rank(0).broadcast_into(x);
    }

    /// MPI_Allgather.
    fn all_gather(&self, mine: &[f64]) -> Vec<f64> {
        use mpi::traits::{Communicator, CommunicatorCollectives};
        let mut all = vec![0.0; mine.len() * self.0.size() as usize];
        self.0.all_gather_into(mine, &mut all[..]);
        all
    }

    /// MPI_Isend and MPI_Irecv with the peers alone: the counts, then the numbers (each pair of
    /// ranks' messages arrive in the order sent, so one tag a kind serves every exchange).
    fn swap(&self, peers: &[usize], out: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        use mpi::traits::{Communicator, Destination, Source};
        const COUNT: mpi::Tag = 41;
        const NUMBERS: mpi::Tag = 42;
        let at = |p: usize| self.0.process_at_rank(p as mpi::Rank);
        let sent: Vec<u64> = out.iter().map(|o| o.len() as u64).collect();
        let mut counts = vec![0u64; peers.len()];
        mpi::request::scope(|scope| {
            let got: Vec<_> = counts
                .iter_mut()
                .zip(peers)
                .map(|(c, &p)| at(p).immediate_receive_into_with_tag(scope, c, COUNT))
                .collect();
            let gone: Vec<_> =
                sent.iter().zip(peers).map(|(c, &p)| at(p).immediate_send_with_tag(scope, c, COUNT)).collect();
            got.into_iter().for_each(|r| {
                r.wait();
            });
            gone.into_iter().for_each(|r| {
                r.wait();
            });
        });
        let mut back: Vec<Vec<f64>> = counts.iter().map(|&n| vec![0.0; n as usize]).collect();
        mpi::request::scope(|scope| {
            let got: Vec<_> = back
                .iter_mut()
                .zip(peers)
                .map(|(b, &p)| at(p).immediate_receive_into_with_tag(scope, &mut b[..], NUMBERS))
                .collect();
            let gone: Vec<_> =
                out.iter().zip(peers).map(|(o, &p)| at(p).immediate_send_with_tag(scope, &o[..], NUMBERS)).collect();
            got.into_iter().for_each(|r| {
                r.wait();
            });
            gone.into_iter().for_each(|r| {
                r.wait();
            });
        });
        back
    }
}

/// MPI_Gather of the lengths, then MPI_Gatherv of the bytes.
#[cfg(feature = "mpi")]
fn gather(world: &mpi::topology::SimpleCommunicator, mine: Vec<u8>) -> Option<Vec<Vec<u8>>> {
    use mpi::datatype::PartitionMut;
    use mpi::traits::{Communicator, Root};
    use mpi::Count;
    let root = world.process_at_rank(0);
    let count = Count::try_from(mine.len()).expect("a rank's share is under 2 GiB");
    if world.rank() != 0 {
        root.gather_into(&count);
        root.gather_varcount_into(&mine[..]);
        return None;
    }
    let mut counts = vec![0 as Count; world.size() as usize];
    root.gather_into_root(&count, &mut counts[..]);
    let starts: Vec<Count> = counts.iter().scan(0, |at, &n| Some(std::mem::replace(at, *at + n))).collect();
    let mut all = vec![0u8; counts.iter().map(|&n| n as usize).sum()];
    root.gather_varcount_into_root(&mine[..], &mut PartitionMut::new(&mut all[..], &counts[..], &starts[..]));
    let mut at = 0;
    Some(
        counts
            .iter()
            .map(|&n| {
                at += n as usize;
                all[at - n as usize..at].to_vec()
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alone_a_world_is_this_process_and_gathers_its_own_bytes() {
        let w = World::one();
        assert!(w.is_root() && w.size == 1 && w.here() == 1);
        assert_eq!(w.gather(vec![1, 2, 3]), Some(vec![vec![1, 2, 3]]));
    }
}
