//! What a run keeps in memory for a look at it afterwards (a page's frames and bound plots, a
//! notebook's arrays), held to a fixed size however long the run: when a sequence reaches its
//! cap, every other item is dropped and from then on only every second as many are kept. The
//! first item and the latest one are always there; which were kept is said by `stride`.

use crate::trace::{Frames, Recorded};
use lagra_kernel::state::State;

/// A sequence thinned to at most `cap` items taken every `stride`-th, plus the latest.
#[derive(Clone, Debug)]
pub struct Thinned<T> {
    kept: Vec<T>,
    /// Whether the last kept item is off the stride (kept only as the latest).
    tail: bool,
    seen: u64,
    stride: u64,
    cap: usize,
}

impl<T> Thinned<T> {
    /// At most `cap` (at least 2) items on the stride, and the latest.
    pub fn new(cap: usize) -> Self {
        Thinned { kept: vec![], tail: false, seen: 0, stride: 1, cap: cap.max(2) }
    }

    pub fn push(&mut self, item: T) {
        if self.tail {
            self.kept.pop();
        }
        self.tail = !self.seen.is_multiple_of(self.stride);
        self.seen += 1;
        self.kept.push(item);
        if self.kept.len() > self.cap {
            // the items on the stride are 0, s, 2s, ...: keep 0, 2s, 4s, ... and the latest
            let latest = self.kept.pop().expect("over the cap");
            let mut k = 0;
            self.kept.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
            self.tail = !(self.seen - 1).is_multiple_of(self.stride);
            self.kept.push(latest);
        }
    }

    /// Every `stride`-th item was kept (1: every one).
    pub fn stride(&self) -> u64 {
        self.stride
    }

    /// How many items were pushed.
    pub fn seen(&self) -> u64 {
        self.seen
    }

    pub fn items(&self) -> &[T] {
        &self.kept
    }

    pub fn into_items(self) -> Vec<T> {
        self.kept
    }
}

/// One frame, kept whole.
#[derive(Clone, Debug)]
struct Frame {
    step: u64,
    t: f64,
    energy: f64,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    /// The rigid bodies' orientations.
    turns: Vec<[f64; 4]>,
}

/// Frames kept in memory within a budget of bytes (thinned past it), for a notebook's arrays.
pub struct Kept {
    frames: Option<Thinned<Frame>>,
    budget: usize,
}

impl Kept {
    /// Frames of positions and velocities within `budget` bytes (never fewer than two).
    pub fn within(budget: usize) -> Self {
        Kept { frames: None, budget }
    }

    /// Every how many frames one was kept (1: every one).
    pub fn stride(&self) -> u64 {
        self.frames.as_ref().map_or(1, Thinned::stride)
    }

    /// The frames kept, flat (each frame's storage freed as it is copied).
    pub fn into_recorded(self) -> Recorded {
        let mut r = Recorded::default();
        for f in self.frames.map(Thinned::into_items).unwrap_or_default() {
            r.bodies = f.x.len();
            r.steps.push(f.step);
            r.times.push(f.t);
            r.energies.push(f.energy);
            r.x.extend(f.x.iter().flatten());
            r.v.extend(f.v.iter().flatten());
            r.turns.extend(f.turns.iter().flatten());
        }
        r
    }
}

impl Frames for Kept {
    fn frame(&mut self, s: &State, energy: f64) -> std::io::Result<()> {
        let per_frame = 48 * s.x.len() + 32 * s.spin.len() + 24;
        let budget = self.budget;
        let frames = self.frames.get_or_insert_with(|| Thinned::new(budget / per_frame));
        let turns = s.spin.iter().map(|r| [r[0], r[1], r[2], r[3]]).collect();
        frames.push(Frame { step: s.step, t: s.t, energy, x: s.x.clone(), v: s.v.clone(), turns });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// However many items, at most cap + 1 are kept: the first, the latest, and every
        /// stride-th between, in order.
        #[test]
        fn thinning_keeps_the_stride_the_first_and_the_latest(cap in 2usize..40, n in 1u64..2000) {
            let mut t = Thinned::new(cap);
            (0..n).for_each(|i| t.push(i));
            let kept = t.items();
            prop_assert!(kept.len() <= cap + 1);
            prop_assert_eq!(kept[0], 0);
            prop_assert_eq!(*kept.last().unwrap(), n - 1);
            let s = t.stride();
            let on_stride: Vec<u64> = (0..n).filter(|i| i % s == 0).collect();
            let body: Vec<u64> = kept.iter().copied().filter(|i| i % s == 0).collect();
            prop_assert_eq!(body, on_stride);
            prop_assert!(kept.windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn below_the_cap_everything_is_kept() {
        let mut t = Thinned::new(10);
        (0..10).for_each(|i| t.push(i));
        assert_eq!((t.items(), t.stride()), (&(0..10).collect::<Vec<_>>()[..], 1));
    }

    #[test]
    fn kept_frames_stay_within_their_budget() {
        let s = State { step: 0, t: 0.0, x: vec![[1.0; 3]; 10], v: vec![[2.0; 3]; 10], chain: vec![], spin: vec![] };
        let mut k = Kept::within(20 * (48 * 10 + 24));
        for step in 0..1000 {
            k.frame(&State { step, ..s.clone() }, 0.0).unwrap();
        }
        assert_eq!(k.stride(), 64);
        let r = k.into_recorded();
        assert!(r.steps.len() <= 21 && r.steps[0] == 0 && *r.steps.last().unwrap() == 999);
        assert_eq!(r.x.len(), 30 * r.steps.len());
    }
}
