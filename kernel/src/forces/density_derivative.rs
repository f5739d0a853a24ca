//! A density term's derivatives (SPH's), from its definition alone, for gradients of runs.
//!
//! The definition gives ρₐ = own(a) + Σ_b D(a, b) over the pairs within reach, the energy
//! U = Σₐ internal(a, ρₐ) and a Rayleigh function R(a, b) per pair. With κₐ = ∂internal/∂ρ at
//! ρₐ, the force on a is −Σ_b (∇ₐψ_ab + ∂R_ab/∂vₐ), ψ_ab = κₐD(a, b) + κ_bD(b, a), and b feels
//! the opposite (both read xₐ − x_b and vₐ − v_b alone). Everything here is that chain on nested
//! duals: the inner part along the direction (or the covector), the outer along one input. The
//! tangent runs it forwards (densities, κ, pairs); the pullback backwards (pairs, κ, densities).

use super::derivative::{Adjoint, Direction};
use super::Frame;
use crate::derivatives::dual::Dual;
use lagra_checker::terms::{Kind, Site};

type D2 = Dual<Dual<f64>>;

/// A value with its inner (direction) and outer (input) seeds.
fn d2(v: f64, inner: f64, outer: f64) -> D2 {
    Dual::new(Dual::new(v, inner), Dual::new(outer, 0.0))
}

/// A pair within reach: i, j, d = xⱼ − xᵢ (nearest image), r².
pub type Near = (u32, u32, [f64; 3], f64);

/// A seed on one site: its position, velocity and mass.
#[derive(Clone, Copy, Default)]
struct Seed {
    x: [f64; 3],
    v: [f64; 3],
    m: f64,
}

impl Seed {
    fn x(c: usize) -> Seed {
        let mut s = Seed::default();
        s.x[c] = 1.0;
        s
    }
    fn v(c: usize) -> Seed {
        let mut s = Seed::default();
        s.v[c] = 1.0;
        s
    }
    fn m() -> Seed {
        Seed { m: 1.0, ..Seed::default() }
    }
}

/// One input of a pair's share, as the outer seed: a coordinate of a's position or velocity
/// (b's is its negative), a site's mass, a parameter.
#[derive(Clone, Copy)]
enum Input {
    X(usize),
    V(usize),
    M(usize),
    P(usize),
}

impl Input {
    /// The outer seeds on the two sites.
    fn seeds(self) -> [Seed; 2] {
        match self {
            Input::X(c) => [Seed::x(c), Seed::default()],
            Input::V(c) => [Seed::v(c), Seed::default()],
            Input::M(k) => std::array::from_fn(|s| if s == k { Seed::m() } else { Seed::default() }),
            Input::P(_) => [Seed::default(); 2],
        }
    }
}

/// The parameters as duals: unseeded, and with the outer seed on each in turn (built once per
/// pass, not per pair).
struct Lifted {
    plain: Vec<D2>,
    seeded: Vec<Vec<D2>>,
}

impl Lifted {
    fn of(&self, input: Input) -> &[D2] {
        match input {
            Input::P(k) => &self.seeded[k],
            _ => &self.plain,
        }
    }
}

/// One instance of a density term over the pairs the fast force found.
pub struct DensityDerivative<'a> {
    pub kind: Kind,
    pub p: &'a [f64],
    /// This instance's place in the model.
    pub term: usize,
    pub near: &'a [Near],
}

impl DensityDerivative<'_> {
    fn params(&self, inner: &[f64], outer: Option<usize>) -> Vec<D2> {
        let seed = |k: usize| if outer == Some(k) { 1.0 } else { 0.0 };
        self.p.iter().enumerate().map(|(k, &p)| d2(p, inner.get(k).copied().unwrap_or(0.0), seed(k))).collect()
    }

    fn lifted(&self) -> Lifted {
        Lifted { plain: self.params(&[], None), seeded: (0..self.p.len()).map(|k| self.params(&[], Some(k))).collect() }
    }

    /// The inputs a pair's share gathers besides positions (and velocities): what `wanted` names.
    fn extra(wanted: (&[usize], bool, bool)) -> Vec<Input> {
        let mut extra: Vec<Input> = wanted.0.iter().map(|&k| Input::P(k)).collect();
        if wanted.1 {
            extra.extend([Input::M(0), Input::M(1)]);
        }
        extra
    }

    fn site(s: &Frame, b: usize, x: [f64; 3], inner: Seed, outer: Seed) -> Site<D2> {
        Site {
            x: std::array::from_fn(|c| d2(x[c], inner.x[c], outer.x[c])),
            v: std::array::from_fn(|c| d2(s.v[b][c], inner.v[c], outer.v[c])),
            m: d2(s.m[b], inner.m, outer.m),
            q: d2(s.q[b], 0.0, 0.0),
            colour: s.c[b].map(|c| d2(c, 0.0, 0.0)),
        }
    }

    /// The pair's two sites, a at xᵢ and b at xᵢ + d (the image a sees).
    fn pair(s: &Frame, near: &Near, inner: [Seed; 2], outer: [Seed; 2]) -> [Site<D2>; 2] {
        let (i, j, d, _) = *near;
        let (i, j) = (i as usize, j as usize);
        let xb = std::array::from_fn(|c| s.x[i][c] + d[c]);
        [Self::site(s, i, s.x[i], inner[0], outer[0]), Self::site(s, j, xb, inner[1], outer[1])]
    }

    fn density(&self, p: &[D2], a: &Site<D2>, b: &Site<D2>) -> D2 {
        self.kind.density(p, a, b).expect("a density term defines its density")
    }

    fn own(&self, p: &[D2], a: &Site<D2>) -> D2 {
        self.kind.own_density(p, a).expect("a density term defines its own share")
    }

    fn internal(&self, p: &[D2], a: &Site<D2>, rho: D2) -> D2 {
        self.kind.internal(p, a, rho).expect("a density term defines its internal energy")
    }

    /// The Rayleigh function of the pair, if the instance dissipates.
    fn rayleigh(&self, p: &[D2], s: &[Site<D2>; 2]) -> Option<D2> {
        self.kind.dissipates(self.p).then(|| self.kind.rayleigh(p, &[&s[0], &s[1]])).flatten()
    }

    /// ψ = κₐD(a, b) + κ_bD(b, a).
    fn psi(&self, p: &[D2], s: &[Site<D2>; 2], kappa: [D2; 2]) -> D2 {
        let [ka, kb] = kappa;
        ka * self.density(p, &s[0], &s[1]) + kb * self.density(p, &s[1], &s[0])
    }

    /// Each body's density, with its derivative along the inner seeds `moving` and `dp`.
    fn densities(&self, s: &Frame, moving: &dyn Fn(usize) -> Seed, dp: &[f64]) -> Vec<Dual<f64>> {
        let p = self.params(dp, None);
        let mut rho: Vec<Dual<f64>> =
            (0..s.x.len()).map(|a| self.own(&p, &Self::site(s, a, s.x[a], moving(a), Seed::default())).v).collect();
        for near in self.near {
            let (i, j) = (near.0 as usize, near.1 as usize);
            let [a, b] = Self::pair(s, near, [moving(i), moving(j)], [Seed::default(); 2]);
            rho[i] = rho[i] + self.density(&p, &a, &b).v;
            rho[j] = rho[j] + self.density(&p, &b, &a).v;
        }
        rho
    }

    /// Adds the derivative of the forces along `dir` to `df`.
    pub fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) {
        let dp = dir.params.get(self.term).map_or(&[][..], |v| v.as_slice());
        let p = self.params(dp, None);
        let moving = |b: usize| Seed { x: dir.x[b], v: dir.v[b], m: dir.m[b] };
        let rho = self.densities(s, &moving, dp);
        // κ and its derivative: ∂internal/∂ρ, the outer seed on ρ
        let kappa: Vec<D2> = (0..s.x.len())
            .map(|a| {
                let site = Self::site(s, a, s.x[a], moving(a), Seed::default());
                Dual::new(self.internal(&p, &site, Dual::new(rho[a], Dual::new(1.0, 0.0))).d, Dual::new(0.0, 0.0))
            })
            .collect();
        for near in self.near {
            let (i, j) = (near.0 as usize, near.1 as usize);
            let inner = [moving(i), moving(j)];
            for c in 0..3 {
                let sites = Self::pair(s, near, inner, [Seed::x(c), Seed::default()]);
                let mut along = self.psi(&p, &sites, [kappa[i], kappa[j]]).d.d;
                let sites = Self::pair(s, near, inner, [Seed::v(c), Seed::default()]);
                along += self.rayleigh(&p, &sites).map_or(0.0, |r| r.d.d);
                df[i][c] -= along;
                df[j][c] += along;
            }
        }
    }

    /// Adds Jᵀg, J the forces' derivative, to `out` (positions, velocities, and the masses and
    /// parameters `wanted` names).
    pub fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: (&[usize], bool, bool), out: &mut Adjoint) {
        let still = |_: usize| Seed::default();
        let p = self.params(&[], None);
        let rho: Vec<f64> = self.densities(s, &still, &[]).iter().map(|r| r.v).collect();
        let kappa: Vec<f64> = (0..s.x.len())
            .map(|a| {
                self.internal(&p, &Self::site(s, a, s.x[a], Seed::default(), Seed::default()), d2(rho[a], 0.0, 1.0)).d.v
            })
            .collect();
        let mut kappa_bar = vec![0.0; s.x.len()];
        let (lifted, extra) = (self.lifted(), Self::extra(wanted));
        for near in self.near {
            let (i, j) = (near.0 as usize, near.1 as usize);
            let e: [f64; 3] = std::array::from_fn(|c| g[i][c] - g[j][c]);
            // −e·∇ₐψ, ψ = κₐD(a, b) + κ_bD(b, a): the inner seed on a's position
            let mut inner = [Seed::default(); 2];
            inner[0].x = e;
            for input in (0..3).map(Input::X).chain(extra.iter().copied()) {
                let (p, sites) = (lifted.of(input), Self::pair(s, near, inner, input.seeds()));
                let (ab, ba) = (self.density(p, &sites[0], &sites[1]), self.density(p, &sites[1], &sites[0]));
                if let Input::X(0) = input {
                    // κ's shares, −e·∇ₐD: the inner derivative, whatever the outer seed
                    kappa_bar[i] -= ab.v.d;
                    kappa_bar[j] -= ba.v.d;
                }
                self.spread(input, i, j, -(kappa[i] * ab.d.d + kappa[j] * ba.d.d), out);
            }
            // −e·∂R/∂vₐ: the inner seed on a's velocity
            if self.kind.dissipates(self.p) {
                let mut inner = [Seed::default(); 2];
                inner[0].v = e;
                for input in (0..3).map(Input::X).chain((0..3).map(Input::V)).chain(extra.iter().copied()) {
                    let sites = Self::pair(s, near, inner, input.seeds());
                    let share = -self.rayleigh(lifted.of(input), &sites).map_or(0.0, |r| r.d.d);
                    self.spread(input, i, j, share, out);
                }
            }
        }
        // κ̄ back to ρ̄ (and to the masses and parameters κ reads directly)
        let mut rho_bar = vec![0.0; s.x.len()];
        for a in 0..s.x.len() {
            if kappa_bar[a] == 0.0 {
                continue;
            }
            // κ's derivative along the outer seed: the inner seed on ρ gives κ itself
            let slope = |outer: Seed, k: Option<usize>, on_rho: f64| {
                let site = Self::site(s, a, s.x[a], Seed::default(), outer);
                self.internal(&self.params(&[], k), &site, d2(rho[a], 1.0, on_rho)).d.d
            };
            rho_bar[a] = kappa_bar[a] * slope(Seed::default(), None, 1.0);
            if wanted.1 {
                out.m[a] += kappa_bar[a] * slope(Seed::m(), None, 0.0);
            }
            for &k in wanted.0 {
                out.params[self.term][k] += kappa_bar[a] * slope(Seed::default(), Some(k), 0.0);
            }
        }
        self.density_pullback(s, &rho_bar, wanted, out);
    }

    /// Adds the gradient of the energy Σ internal(a, ρₐ) to `out`.
    pub fn potential_pullback(&self, s: &Frame, wanted: (&[usize], bool, bool), out: &mut Adjoint) {
        let still = |_: usize| Seed::default();
        let rho: Vec<f64> = self.densities(s, &still, &[]).iter().map(|r| r.v).collect();
        let mut rho_bar = vec![0.0; s.x.len()];
        for a in 0..s.x.len() {
            let at = |outer: Seed, k: Option<usize>, on_rho: f64| {
                let site = Self::site(s, a, s.x[a], Seed::default(), outer);
                self.internal(&self.params(&[], k), &site, d2(rho[a], 0.0, on_rho)).d.v
            };
            rho_bar[a] = at(Seed::default(), None, 1.0);
            if wanted.1 {
                out.m[a] += at(Seed::m(), None, 0.0);
            }
            for &k in wanted.0 {
                out.params[self.term][k] += at(Seed::default(), Some(k), 0.0);
            }
        }
        self.density_pullback(s, &rho_bar, wanted, out);
    }

    /// Adds Σₐ ρ̄ₐ ∂ρₐ/∂· to `out`: positions, and the masses and parameters `wanted` names.
    fn density_pullback(&self, s: &Frame, rho_bar: &[f64], wanted: (&[usize], bool, bool), out: &mut Adjoint) {
        for (a, &bar) in rho_bar.iter().enumerate() {
            if bar == 0.0 {
                continue;
            }
            let own = |outer: Seed, k: Option<usize>| {
                self.own(&self.params(&[], k), &Self::site(s, a, s.x[a], Seed::default(), outer)).d.v
            };
            if wanted.1 {
                out.m[a] += bar * own(Seed::m(), None);
            }
            for &k in wanted.0 {
                out.params[self.term][k] += bar * own(Seed::default(), Some(k));
            }
        }
        let (lifted, extra) = (self.lifted(), Self::extra(wanted));
        for near in self.near {
            let (i, j) = (near.0 as usize, near.1 as usize);
            if rho_bar[i] == 0.0 && rho_bar[j] == 0.0 {
                continue;
            }
            for input in (0..3).map(Input::X).chain(extra.iter().copied()) {
                let (p, sites) = (lifted.of(input), Self::pair(s, near, [Seed::default(); 2], input.seeds()));
                let (ab, ba) = (self.density(p, &sites[0], &sites[1]), self.density(p, &sites[1], &sites[0]));
                self.spread(input, i, j, rho_bar[i] * ab.d.v + rho_bar[j] * ba.d.v, out);
            }
        }
    }

    /// An input's share added where it belongs (a's position or velocity, b's the opposite).
    fn spread(&self, input: Input, i: usize, j: usize, share: f64, out: &mut Adjoint) {
        match input {
            Input::X(c) => {
                out.x[i][c] += share;
                out.x[j][c] -= share;
            }
            Input::V(c) => {
                out.v[i][c] += share;
                out.v[j][c] -= share;
            }
            Input::M(k) => out.m[[i, j][k]] += share,
            Input::P(k) => out.params[self.term][k] += share,
        }
    }
}
