//! What rank 0 asks of every rank at a state the ranks reach together, and how they answer: the
//! whole state gathered at rank 0 for its checker, the potential energy and virial as each rank's
//! share added in rank order, and each rank's part of the energy and momentum enclosed with the
//! checker's arithmetic. Every function here is a collective: each rank calls it at the same step.

use super::exchange::Exchange;
use super::{with_number, Domain, Shared, STOP};
use lagra_checker::quantities::{Local, Part, Parts, Region, PART_BITS};
use lagra_kernel::state::State;
use lagra_kernel::step::set_step;
use lagra_kernel::sum::Sum;
use std::time::Instant;

/// What rank 0 asks of every rank at the state an advance reaches.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Asks {
    /// Its potential energy and virial (`EnergyAndVirial`), for a sample or a trace frame.
    pub measure: bool,
    /// Each rank's part of the energy and momentum, enclosed (`Parts`), for a checkpoint.
    pub enclose: bool,
}

impl Asks {
    fn to_bits(self) -> u64 {
        u64::from(self.measure) | u64::from(self.enclose) << 1
    }

    fn from_bits(b: u64) -> Asks {
        Asks { measure: b & 1 != 0, enclose: b & 2 != 0 }
    }
}

/// What the ranks answered at the state reached.
#[derive(Debug, Default)]
pub struct Reached {
    pub measured: Option<EnergyAndVirial>,
    pub parts: Option<Parts>,
}

/// The whole system's potential energy and virial at a state, each rank's part (its own atoms'
/// share of its interactions: `LagrangianGraph::owned_sums`) added in rank order: what a trace
/// frame and a sampled observable read, with no pass over the whole system on rank 0.
#[derive(Clone, Copy, Debug)]
pub struct EnergyAndVirial {
    pub potential: f64,
    pub virial: f64,
}

impl<E: Exchange> Domain<E> {
    /// Every rank's atoms at rank 0, into `whole` (on the other ranks `None`), and their numbers
    /// in the order received (rank by rank; empty on the other ranks). A collective.
    fn gather(&mut self, whole: Option<&mut State>) -> Vec<usize> {
        let n = self.owned.len();
        let mut out = vec![vec![]; self.ex.size()];
        out[0] = (0..n)
            .flat_map(|k| with_number(self.owned[k], self.local.x[k]).into_iter().chain(self.local.v[k]))
            .collect();
        let got = self.talk(|ex, _| ex.all_to_all(out));
        let mut numbers = vec![];
        if let Some(s) = whole {
            for a in got.iter().flat_map(|g| g.chunks_exact(7)) {
                let i = a[0] as usize;
                (s.x[i], s.v[i]) = ([a[1], a[2], a[3]], [a[4], a[5], a[6]]);
                numbers.push(i);
            }
            s.chain.clone_from(&self.local.chain);
            set_step(s, self.step, self.dt);
        }
        numbers
    }

    /// Every rank's part of the energy and momentum at the state reached, enclosed by the
    /// checker (`Part::enclose`, which also checks that the part covers its share), on rank 0
    /// with the `numbers` it gathered (`None` on the other ranks). A collective.
    fn enclose(&mut self, numbers: Vec<usize>) -> Option<Parts> {
        let started = Instant::now();
        let (me, n) = (self.ex.rank(), self.owned.len());
        let mine = Region::of(&self.local.x[..n], self.bricks.centre(me), &self.model.cell);
        let all = self.talk(|ex, _| ex.all_gather(&mine.to_bits()));
        let regions: Vec<Region> = all.chunks_exact(9).map(Region::from_bits).collect();
        let mut sent = vec![vec![]; self.ex.size()];
        self.peers.iter().zip(&self.send).for_each(|(&r, s)| sent[r].clone_from(s));
        let local_numbers: Vec<usize> = self.owned.iter().chain(&self.ghosts).copied().collect();
        let part = Part::enclose(&Local {
            whole: &self.whole,
            model: &self.local_model,
            state: self.local.snapshot(),
            owned: n,
            numbers: &local_numbers,
            instances: &self.instances,
            rank: me,
            regions: &regions,
            sent: &sent,
            threads: self.threads,
        });
        if let Some(f) = &part.flaw {
            eprintln!("lagra (rank {me}): at step {}: its part of the energy and momentum is refused: {f}", self.step);
        }
        let all = self.talk(|ex, _| ex.all_gather(&part.to_bits()));
        let parts = all.chunks_exact(PART_BITS).enumerate().map(|(r, b)| Part::from_bits(b, r)).collect();
        self.tally.enclosing += started.elapsed().as_secs_f64();
        (me == 0).then_some(Parts { parts, numbers })
    }

    /// The whole system's potential energy and virial at the state reached (a collective): a
    /// rank whose part cannot be evaluated sends NaN, so that every rank fails alike.
    fn measure(&mut self) -> Result<EnergyAndVirial, String> {
        let n = self.owned.len();
        let mine = match self.graph.owned_sums(&self.local, n) {
            Some(Ok(sums)) => sums,
            Some(Err(e)) => {
                eprintln!("lagra (rank {}): measuring at step {}: {e}", self.ex.rank(), self.step);
                [f64::NAN; 2]
            }
            None => [f64::NAN; 2],
        };
        let all = self.talk(|ex, _| ex.all_gather(&mine));
        let (mut potential, mut virial) = (Sum::default(), Sum::default());
        all.chunks_exact(2).for_each(|p| (potential.add(p[0]), virial.add(p[1])).1);
        let m = EnergyAndVirial { potential: potential.value(), virial: virial.value() };
        match m.potential.is_finite() && m.virial.is_finite() {
            true => Ok(m),
            false => Err(format!(
                "the potential energy or virial at step {} is not finite on some rank (it says why on its stderr)",
                self.step
            )),
        }
    }

    /// Follows rank 0's run loop on another rank: advances where it says (answering what it
    /// asks there), until it says stop.
    pub fn follow(mut self) {
        loop {
            let (mut until, mut asks) = (0, 0);
            self.ex.broadcast(&mut until);
            if until == STOP {
                return;
            }
            self.ex.broadcast(&mut asks);
            let asks = Asks::from_bits(asks);
            // a failure is rank 0's to report: every rank knows it and stops at the same step
            let _ = self.steps_to(until);
            self.gather(None);
            if asks.measure {
                let _ = self.measure();
            }
            if asks.enclose {
                self.enclose(vec![]);
            }
        }
    }
}

impl<E: Exchange> Shared for Domain<E> {
    fn advance_to(&mut self, s: &mut State, until: u64, asks: Asks) -> Result<Reached, String> {
        let (mut u, mut a) = (until, asks.to_bits());
        self.ex.broadcast(&mut u);
        self.ex.broadcast(&mut a);
        let done = self.steps_to(until);
        let numbers = self.gather(Some(s));
        let measured = asks.measure.then(|| self.measure()).transpose();
        let parts = if asks.enclose { self.enclose(numbers) } else { None };
        done.and(measured).map(|measured| Reached { measured, parts })
    }

    fn plan(&self) -> String {
        let t = &self.tally;
        let [px, py, pz] = self.bricks.counts;
        let total = t.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        format!(
            "domains: {px}×{py}×{pz} bricks on {} ranks, halo {:.3} (reach {} + skin {:.3}){}; ghosts chosen {} time(s), \
             {:.0}% as many ghosts as owned atoms on rank 0; rank 0 spent {:.3} s of {:.3} s in exchanges (its waits \
             for the other ranks included), {:.3} s moving atoms and choosing ghosts, {:.3} s in forces, {:.3} s \
             enclosing its part of the energy and momentum; rank 0's forces since its ghosts were last chosen: {}",
            self.ex.size(),
            self.halo,
            self.reach,
            self.halo - self.reach,
            self.bath.said(),
            t.regroups,
            100.0 * t.ghosts as f64 / t.owned.max(1) as f64,
            t.talking,
            total,
            t.regrouping,
            t.forcing,
            t.enclosing,
            self.graph.plan().into_iter().map(|(_, p)| p).collect::<Vec<_>>().join("; ")
        )
    }
}
