//! Bodies on a lattice: the positions of a crystal filling a periodic box, and thermal velocities
//! drawn from a seeded generator, so a 32,000-atom scene is one line and the same bits everywhere
//! (the draw uses `libm`, not the platform's maths library). A large lattice is laid out on the
//! run's threads, each body's site and draw computed alone: the same bits on any thread count.

use rayon::prelude::*;
use rayon::ThreadPool;

/// Bodies from which a lattice is laid out on the run's threads (the run's own threshold for
/// using every core, `lagra_run::run::AUTO_FROM`): below, starting them costs more than the
/// layout saves (~40 ms at 256,000 bodies on one thread, most of it first touches of fresh
/// memory).
pub const SPREAD_FROM: usize = 16_384;

/// Bodies a thread takes at once.
const BLOCK: usize = 4096;

/// `f(m)` for m in `0..n`, in order, in blocks on `pool`'s threads where there is one (each
/// value its own, so the same whoever computed it; fresh memory is first touched there too).
pub(crate) fn laid<U: Send>(pool: Option<&ThreadPool>, n: usize, f: impl Fn(usize) -> U + Sync + Send) -> Vec<U> {
    match pool {
        Some(pool) => pool.install(|| (0..n).into_par_iter().with_min_len(BLOCK).map(f).collect()),
        None => (0..n).map(f).collect(),
    }
}

/// `f` on each item, in blocks on `pool`'s threads where there is one.
fn each_mut<T: Send>(pool: Option<&ThreadPool>, items: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
    match pool {
        Some(pool) => pool.install(|| items.par_iter_mut().with_min_len(BLOCK).for_each(f)),
        None => items.iter_mut().for_each(f),
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Packing {
    /// Face-centred cubic: four bodies per cubic cell.
    Fcc,
    /// Simple cubic: one body per cell.
    Sc,
}

impl Packing {
    pub fn from_name(s: &str) -> Option<Packing> {
        match s {
            "fcc" => Some(Packing::Fcc),
            "sc" => Some(Packing::Sc),
            _ => None,
        }
    }

    fn basis(self) -> &'static [[f64; 3]] {
        match self {
            Packing::Fcc => &[[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]],
            Packing::Sc => &[[0.0, 0.0, 0.0]],
        }
    }

    /// The sites of `cells` unit cells at `density` bodies per unit volume (cell by cell, the
    /// last axis fastest, the basis within each), and the box they fill.
    pub fn sites(self, density: f64, cells: [usize; 3], pool: Option<&ThreadPool>) -> (Vec<[f64; 3]>, [f64; 3]) {
        let basis = self.basis();
        let a = libm::cbrt(basis.len() as f64 / density);
        let site = |m: usize| {
            let (b, cell) = (&basis[m % basis.len()], m / basis.len());
            let (i, j, k) = (cell / (cells[1] * cells[2]), cell / cells[2] % cells[1], cell % cells[2]);
            [(i as f64 + b[0]) * a, (j as f64 + b[1]) * a, (k as f64 + b[2]) * a]
        };
        (laid(pool, cells.iter().product::<usize>() * basis.len(), site), cells.map(|n| n as f64 * a))
    }
}

/// What a body costs a run, measured: ≈1.1 kB with the kernel's state, forces and Verlet list
/// (LJ at density 0.84, 32,000 bodies: 35 MB), ≈2.2 kB with the checker's enclosures at a
/// checkpoint (256,000 bodies: 571 MB). A lattice is refused, before anything is allocated, where
/// this would not fit in the memory the machine has free.
pub const BYTES_PER_BODY: u64 = 2500;

/// The memory this process may still take, where the system says: the least of what the machine
/// has free (Linux's MemAvailable), what its control group allows beyond what the group uses (a
/// batch system's cap: cgroup v2 `memory.max`, v1 `memory.limit_in_bytes`), and its
/// address-space limit (`ulimit -v`) beyond its size now.
pub fn available_memory() -> Option<u64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let number = |p: &str| read(p)?.trim().parse::<u64>().ok();
    // a field of /proc's `key: value kB` files, or a column of /proc/self/limits
    let field = |text: &str, key: &str, column: usize| -> Option<u64> {
        text.lines().find(|l| l.starts_with(key))?.split_whitespace().nth(column)?.parse().ok()
    };
    let free = read("/proc/meminfo").and_then(|m| field(&m, "MemAvailable:", 1)).map(|kb| kb * 1024);
    let group = read("/proc/self/cgroup").and_then(|groups| {
        groups.lines().find_map(|l| match l.split(':').collect::<Vec<_>>()[..] {
            ["0", "", path] => Some(("", path.to_string(), "memory.max", "memory.current")),
            [_, "memory", path] => Some(("memory", path.to_string(), "memory.limit_in_bytes", "memory.usage_in_bytes")),
            _ => None,
        })
    });
    let capped = group.and_then(|(v1, path, max, now)| {
        let dir = format!("/sys/fs/cgroup/{v1}/{path}");
        Some(number(&format!("{dir}/{max}"))?.saturating_sub(number(&format!("{dir}/{now}"))?))
    });
    let address = read("/proc/self/limits")
        .and_then(|l| field(&l, "Max address space", 3))
        .and_then(|limit| Some(limit.saturating_sub(field(&read("/proc/self/status")?, "VmSize:", 1)? * 1024)));
    [free, capped, address].into_iter().flatten().min()
}

impl Packing {
    /// Bodies in `cells` unit cells.
    pub fn count(self, cells: [usize; 3]) -> u64 {
        cells.iter().map(|&c| c as u64).product::<u64>() * self.basis().len() as u64
    }
}

/// How the velocity components are drawn before they are rescaled to the temperature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Draw {
    /// Normal: Maxwell–Boltzmann, the equilibrium distribution (the default).
    Gaussian,
    /// Uniform on a symmetric interval: LAMMPS's `velocity create` default, so a scene can start
    /// like LAMMPS's `bench/in.lj` (its fastest bodies are slower than Maxwell–Boltzmann's tail).
    Uniform,
}

impl Draw {
    pub fn from_name(s: &str) -> Option<Draw> {
        match s {
            "gaussian" => Some(Draw::Gaussian),
            "uniform" => Some(Draw::Uniform),
            _ => None,
        }
    }
}

/// `n` velocities with components drawn by `draw`, the centre of mass at rest, rescaled so the
/// kinetic temperature (k_B·T/m = `t_over_m`) over 3n − 3 degrees of freedom is exact. The
/// components are one seeded stream, body by body; each is drawn alone from its place in the
/// stream (on `pool`'s threads where there is one), and the sums are taken in order: the same
/// bits on any thread count.
pub fn velocities(n: usize, t_over_m: f64, seed: u64, draw: Draw, pool: Option<&ThreadPool>) -> Vec<[f64; 3]> {
    if t_over_m == 0.0 || n < 2 {
        return vec![[0.0; 3]; n];
    }
    // a normal takes two of the stream's numbers (Box–Muller), a uniform one
    let taken = match draw {
        Draw::Gaussian => 2,
        Draw::Uniform => 1,
    };
    let component = |d: usize| {
        let mut rng = crate::random::SplitMix::after(seed, (d * taken) as u64);
        match draw {
            Draw::Gaussian => rng.normal(),
            Draw::Uniform => 2.0 * rng.uniform() - 1.0,
        }
    };
    let mut v: Vec<[f64; 3]> = laid(pool, n, |i| std::array::from_fn(|c| component(3 * i + c)));
    let mean: [f64; 3] = std::array::from_fn(|c| v.iter().map(|v| v[c]).sum::<f64>() / n as f64);
    each_mut(pool, &mut v, |v| (0..3).for_each(|c| v[c] -= mean[c]));
    let sq: f64 = v.iter().flatten().map(|c| c * c).sum();
    let scale = libm::sqrt(t_over_m * (3 * n - 3) as f64 / sq);
    each_mut(pool, &mut v, |v| v.iter_mut().for_each(|c| *c *= scale));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fcc_at_the_triple_point_density() {
        let (x, side) = Packing::Fcc.sites(0.8442, [20, 20, 20], None);
        assert_eq!(x.len(), 32_000);
        let density = x.len() as f64 / (side[0] * side[1] * side[2]);
        assert!((density / 0.8442 - 1.0).abs() < 1e-12, "{density}");
        // nearest neighbours at a/√2
        let a = side[0] / 20.0;
        let d = (0..3).map(|c| (x[1][c] - x[0][c]).powi(2)).sum::<f64>().sqrt();
        assert!((d - a / 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn velocities_have_the_exact_temperature_and_no_drift() {
        for draw in [Draw::Gaussian, Draw::Uniform] {
            let v = velocities(500, 1.44, 87287, draw, None);
            let p: [f64; 3] = std::array::from_fn(|c| v.iter().map(|v| v[c]).sum::<f64>());
            assert!(p.iter().all(|p| p.abs() < 1e-12), "{p:?}");
            let t = v.iter().flatten().map(|c| c * c).sum::<f64>() / (3.0 * 500.0 - 3.0);
            assert!((t - 1.44).abs() < 1e-12, "{t}");
            assert_eq!(v, velocities(500, 1.44, 87287, draw, None), "a seed gives one draw");
            assert_ne!(v, velocities(500, 1.44, 87288, draw, None));
        }
    }

    fn pool(threads: usize) -> ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
    }

    /// Laid out on threads or not, the sites are the cells' in order, the last axis fastest
    /// and the basis within each cell, to the bit.
    #[test]
    fn sites_are_the_cells_in_order_on_any_thread_count() {
        let (cells, basis) = ([7, 5, 3], Packing::Fcc.basis());
        let (x, side) = Packing::Fcc.sites(0.8, cells, None);
        let a = libm::cbrt(4.0 / 0.8);
        assert_eq!(side, [7.0 * a, 5.0 * a, 3.0 * a]);
        let mut m = 0;
        for i in 0..7 {
            for j in 0..5 {
                for k in 0..3 {
                    for b in basis {
                        let want = [(i as f64 + b[0]) * a, (j as f64 + b[1]) * a, (k as f64 + b[2]) * a];
                        assert_eq!(x[m].map(f64::to_bits), want.map(f64::to_bits), "site {m}");
                        m += 1;
                    }
                }
            }
        }
        assert_eq!(m, x.len());
        let big = [30, 24, 25]; // 72,000 bodies: laid out in blocks over the threads
        let one = Packing::Fcc.sites(0.8442, big, None);
        for threads in [2, 3, 7] {
            assert_eq!(Packing::Fcc.sites(0.8442, big, Some(&pool(threads))), one, "{threads} threads");
        }
    }

    /// Each component is drawn alone from its place in the seed's stream: the same bits as one
    /// generator drawing body after body, on any thread count.
    #[test]
    fn velocities_are_one_stream_on_any_thread_count() {
        for draw in [Draw::Gaussian, Draw::Uniform] {
            let n = 40_000;
            let mut rng = crate::random::SplitMix(11);
            let raw: Vec<f64> = (0..3 * n)
                .map(|_| match draw {
                    Draw::Gaussian => rng.normal(),
                    Draw::Uniform => 2.0 * rng.uniform() - 1.0,
                })
                .collect();
            let one = velocities(n, 1.5, 11, draw, None);
            // the draw, centred and scaled: its components in the stream's order
            let mean: [f64; 3] = std::array::from_fn(|c| raw.iter().skip(c).step_by(3).sum::<f64>() / n as f64);
            let centred: Vec<f64> = raw.iter().enumerate().map(|(d, r)| r - mean[d % 3]).collect();
            let ratio: Vec<f64> = one.iter().flatten().zip(&centred).map(|(v, c)| v / c).collect();
            assert!(ratio.iter().all(|r| (r / ratio[0] - 1.0).abs() < 1e-12), "{draw:?}: not one scale");
            for threads in [2, 3, 7] {
                let many = velocities(n, 1.5, 11, draw, Some(&pool(threads)));
                assert!(many.iter().flatten().zip(one.iter().flatten()).all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
    }

    /// Fourth moment over variance squared: 3 for a normal distribution, 9/5 for a uniform one.
    fn kurtosis(draw: Draw) -> f64 {
        let v = velocities(20_000, 1.0, 7, draw, None);
        let c: Vec<f64> = v.iter().flatten().copied().collect();
        let m2 = c.iter().map(|c| c * c).sum::<f64>() / c.len() as f64;
        let m4 = c.iter().map(|c| c.powi(4)).sum::<f64>() / c.len() as f64;
        m4 / (m2 * m2)
    }

    #[test]
    fn the_draw_is_normal_or_uniform() {
        assert!((kurtosis(Draw::Gaussian) - 3.0).abs() < 0.1, "{}", kurtosis(Draw::Gaussian));
        assert!((kurtosis(Draw::Uniform) - 1.8).abs() < 0.05, "{}", kurtosis(Draw::Uniform));
    }
}
