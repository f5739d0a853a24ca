//! The arithmetic a step is made of — kick, drift, the clock — on plain arrays, and `Stride`,
//! the fused inner steps of a conservative velocity Verlet run that the force groups
//! monomorphize around their own code. It knows no term and no solver: forces, the graph and the
//! solvers all build on it, and it on nothing of theirs.

use crate::spread;
pub use crate::spread::BLOCK;
use crate::state::State;
use rayon::prelude::*;
use rayon::ThreadPool;

/// v += h·F/m, with `inverse` the 1/m of each body.
pub fn kick(v: &mut [[f64; 3]], f: &[[f64; 3]], inverse: &[f64], h: f64) {
    for ((v, f), w) in v.iter_mut().zip(f).zip(inverse) {
        let s = h * w;
        for c in 0..3 {
            v[c] += s * f[c];
        }
    }
}

/// `kick` over the run's threads where the kick-drift spreads (`spread`), as a clocked pass at
/// one thread where that many bodies would spread at more: each body's velocity is its own, so
/// the bits are the same. The closing kick of every `advance_to` is one such pass: left on one
/// thread it was half the serial part of lj_32k at 256,000 atoms (1.1 ms a kick, 25 in 100 steps
/// when progress is shown).
pub fn kick_on(v: &mut [[f64; 3]], f: &[[f64; 3]], inverse: &[f64], h: f64, spread: Option<&ThreadPool>) {
    spread::over(spread, v.len(), |on_pool| match on_pool {
        true => {
            let bodies = v.par_chunks_mut(BLOCK).zip(f.par_chunks(BLOCK)).zip(inverse.par_chunks(BLOCK));
            bodies.for_each(|((v, f), w)| kick(v, f, w, h))
        }
        false => kick(v, f, inverse, h),
    })
}

/// x += h·v.
pub fn drift(x: &mut [[f64; 3]], v: &[[f64; 3]], h: f64) {
    for (x, v) in x.iter_mut().zip(v) {
        for c in 0..3 {
            x[c] += h * v[c];
        }
    }
}

/// One pass over the bodies: v += h·F/m (twice with `closing`: the closing kick of a step, then
/// the opening kick of the next, with the same forces), then x += dt·v; and the forces, spent,
/// are zeroed for the next evaluation to add to (no pass of their own). With `spread`, in
/// blocks of bodies on its threads: each body's arithmetic is its own, so the same bits.
pub fn kick_drift(
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    f: &mut [[f64; 3]],
    inverse: &[f64],
    steps: (f64, f64),
    closing: bool,
    spread: Option<&ThreadPool>,
) {
    // (a few bodies never spread, at any thread count: serial, and not clocked; wrapped in the
    // clock, a one-body step took 38–51 ns against 30)
    spread::over(spread, x.len(), |on_pool| match on_pool {
        true => {
            let blocks = x.par_chunks_mut(BLOCK).zip(v.par_chunks_mut(BLOCK)).zip(f.par_chunks_mut(BLOCK));
            blocks
                .zip(inverse.par_chunks(BLOCK))
                .for_each(|(((x, v), f), w)| kick_drift_alone(x, v, f, w, steps, closing))
        }
        false => kick_drift_alone(x, v, f, inverse, steps, closing),
    })
}

/// `kick_drift` on this thread: a function of its own, whose slices the compiler knows apart
/// (as the captures of the pass's closure it did not: each `v` was stored and loaded again, and
/// the one-body step took 40 ns against 24).
fn kick_drift_alone(
    x: &mut [[f64; 3]],
    v: &mut [[f64; 3]],
    f: &mut [[f64; 3]],
    inverse: &[f64],
    (h, dt): (f64, f64),
    closing: bool,
) {
    for (((x, v), f), w) in x.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(inverse) {
        let s = h * w;
        for c in 0..3 {
            if closing {
                v[c] += s * f[c];
            }
            v[c] += s * f[c];
            x[c] += dt * v[c];
        }
        *f = [0.0; 3];
    }
}

/// The step counter and the clock after one step.
pub fn tick(s: &mut State, dt: f64) {
    set_step(s, s.step + 1, dt);
}

/// The step counter and the clock at `step` (t = step·dt, never accumulated).
pub fn set_step(s: &mut State, step: u64, dt: f64) {
    s.step = step;
    s.t = step as f64 * dt;
}

/// The steps before the last of a conservative velocity Verlet `advance_to`: forces only, then
/// the closing kick, the next opening kick and the drift. A graph of one group runs them
/// monomorphized around that group's force code (`Force::stride`); any other through the graph.
pub struct Stride<'a> {
    pub s: &'a mut State,
    pub f: &'a mut Vec<[f64; 3]>,
    pub inverse: &'a [f64],
    pub h: f64,
    pub dt: f64,
    pub until: u64,
    /// The threads a pass over the bodies spreads over, if the system is big enough.
    pub spread: Option<&'a ThreadPool>,
}

impl Stride<'_> {
    /// Steps until one step before `until`, with `forces` adding the forces at a state to `f`,
    /// which it finds zeroed. The first error stops it, with the counter at the last step done.
    #[inline]
    pub fn run<E>(self, mut forces: impl FnMut(&State, &mut [[f64; 3]]) -> Result<(), E>) -> Result<(), E> {
        // the clock is set once at the end (t = step·dt: the same bits); no force reads it
        let (mut step, mut done) = (self.s.step, Ok(()));
        while step + 1 < self.until {
            if let Err(e) = forces(self.s, self.f) {
                done = Err(e);
                break;
            }
            kick_drift(&mut self.s.x, &mut self.s.v, self.f, self.inverse, (self.h, self.dt), true, self.spread);
            step += 1;
        }
        set_step(self.s, step, self.dt);
        done
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fused_pass_is_a_kick_then_a_drift() {
        let (mut x, mut v, mut f) = (vec![[1.0, 2.0, 3.0]], vec![[0.5, -0.25, 0.0]], vec![[2.0, 4.0, -8.0]]);
        let (mut x2, mut v2) = (x.clone(), v.clone());
        kick(&mut v2, &f, &[0.5], 0.1);
        kick(&mut v2, &f, &[0.5], 0.1);
        drift(&mut x2, &v2, 0.2);
        kick_drift(&mut x, &mut v, &mut f, &[0.5], (0.1, 0.2), true, None);
        assert_eq!((x, v, f), (x2, v2, vec![[0.0; 3]]));
    }

    /// Spread over threads, a pass over the bodies (the kick-drift, the kick) gives the same bits as
    /// on one.
    #[test]
    fn a_spread_pass_is_the_same_bits() {
        let n = 3 * BLOCK + 17;
        let at = |k: usize, c: usize| ((k * 7919 + c * 104_729) % 1000) as f64 / 37.0 - 13.0;
        let start: Vec<[f64; 3]> = (0..n).map(|k| [at(k, 0), at(k, 1), at(k, 2)]).collect();
        let inverse: Vec<f64> = (0..n).map(|k| 1.0 / (1.0 + at(k, 3).abs())).collect();
        let pass = |spread: Option<&ThreadPool>| {
            let (mut x, mut v, mut f) =
                (start.clone(), start.iter().map(|p| p.map(|c| 0.1 * c)).collect::<Vec<_>>(), start.clone());
            kick_drift(&mut x, &mut v, &mut f, &inverse, (0.013, 0.026), true, spread);
            kick_on(&mut v, &start, &inverse, 0.013, spread);
            (
                x.concat().iter().map(|c| c.to_bits()).collect::<Vec<_>>(),
                v.concat().iter().map(|c| c.to_bits()).collect::<Vec<_>>(),
            )
        };
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let (one, three) = (pass(None), pass(Some(&pool)));
        assert!(one == three);
        // and the spread kick is the plain one
        let mut v: Vec<[f64; 3]> = start.iter().map(|p| p.map(|c| 0.1 * c)).collect();
        let mut x = start.clone();
        kick_drift(&mut x, &mut v, &mut start.clone(), &inverse, (0.013, 0.026), true, None);
        kick(&mut v, &start, &inverse, 0.013);
        assert!(one.1 == v.concat().iter().map(|c| c.to_bits()).collect::<Vec<_>>());
    }

    #[test]
    fn the_clock_is_the_step_times_dt() {
        let mut s = State { step: 0, t: 0.0, x: vec![], v: vec![], chain: vec![], spin: vec![] };
        for _ in 0..10 {
            tick(&mut s, 0.1);
        }
        assert_eq!((s.step, s.t.to_bits()), (10, (10.0f64 * 0.1).to_bits()));
    }
}
