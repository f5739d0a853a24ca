//! Random draws that are the same bits on every platform and thread count: SplitMix64 (small,
//! fast, fully specified) and `libm` (not the platform's maths library) to turn it into a
//! normal. The lattice draws its velocities from one seeded stream; a Langevin bath draws each
//! (seed, step, body, axis) alone, with no state carried.

/// A standard normal draw for (seed, step, index): SplitMix64 over the three mixed together,
/// then Box–Muller. No state is carried, so any body's noise at any step is known alone, in
/// any order, on any thread.
pub fn normal(seed: u64, step: u64, index: u64) -> f64 {
    let mut g = SplitMix(mix(mix(seed) ^ step) ^ index.wrapping_mul(0xd1b5_4a32_d192_ed03));
    g.normal()
}

fn mix(z: u64) -> u64 {
    SplitMix(z).next()
}

/// SplitMix64: small, fast, and fully specified, so a draw is the same on every platform (and
/// `libm`, not the platform's maths library, turns it into a normal).
pub struct SplitMix(pub u64);

/// SplitMix64's step: its state advances by this at every draw.
const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

impl SplitMix {
    /// The stream of `seed` after `draws` draws: its state is the seed plus that many steps, so
    /// any place in the stream is reached at once (a lattice draws each body's alone).
    pub fn after(seed: u64, draws: u64) -> SplitMix {
        SplitMix(seed.wrapping_add(draws.wrapping_mul(GAMMA)))
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GAMMA);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    pub fn uniform(&mut self) -> f64 {
        ((self.next() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal, by Box–Muller.
    pub fn normal(&mut self) -> f64 {
        let (u, w) = (self.uniform(), self.uniform());
        libm::sqrt(-2.0 * libm::log(u)) * libm::cos(2.0 * std::f64::consts::PI * w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_standard_normal_and_counter_based() {
        let n = 200_000u64;
        let z: Vec<f64> = (0..n).map(|i| normal(42, i / 3, i % 3)).collect();
        let mean = z.iter().sum::<f64>() / n as f64;
        let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01 && (var - 1.0).abs() < 0.01, "{mean} {var}");
        assert_eq!(normal(42, 7, 5).to_bits(), normal(42, 7, 5).to_bits());
        assert_ne!(normal(42, 7, 5), normal(43, 7, 5));
        assert_ne!(normal(42, 7, 5), normal(42, 8, 5));
        assert_ne!(normal(42, 7, 5), normal(42, 7, 6));
        // neighbouring counters are uncorrelated
        let lag = (0..n - 1).map(|i| z[i as usize] * z[i as usize + 1]).sum::<f64>() / n as f64;
        assert!(lag.abs() < 0.01, "{lag}");
    }
}
