//! The force groups' derivatives, for gradients of runs (`grad`): along a direction of the
//! inputs (`tangent`: forward mode) and their transpose applied to a covector (`pullback`:
//! reverse mode). Both come from the terms' definitions (`derivatives::exact`), never from the
//! fast force code: bonds and fields through the full Euler–Lagrange force on duals, pair terms
//! through their radial form (central, position-only: V along the distance), over the same
//! pairs the fast loop visits.

use super::{Frame, Jet, Singularity};
use crate::derivatives::dual::Dual;
use crate::derivatives::exact::{force, radial, radial_potential, radial_sensitivities, Radial};
use lagra_checker::model::{Images, TermInstance};
use lagra_checker::terms::{Kind, Site};

/// A direction of a force's inputs: positions, velocities, masses, charges, and each model
/// term's parameters (indexed by the term's place in the model; empty: no change).
pub struct Direction<'a> {
    pub x: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    pub m: &'a [f64],
    pub q: &'a [f64],
    pub params: &'a [Vec<f64>],
}

/// What reverse mode wants beyond positions and velocities: for each model term the indices of
/// the parameters asked for, and whether masses and charges are.
#[derive(Clone, Debug, Default)]
pub struct Wanted {
    pub params: Vec<Vec<usize>>,
    pub masses: bool,
    pub charges: bool,
}

impl Wanted {
    /// What it wants of model term `term`: its parameters' indices, masses, charges.
    pub fn of(&self, term: usize) -> (&[usize], bool, bool) {
        (self.params.get(term).map_or(&[][..], |v| v.as_slice()), self.masses, self.charges)
    }
}

/// Adjoints gathered by `pullback`: of positions, velocities, masses, charges, parameters.
#[derive(Clone, Debug)]
pub struct Adjoint {
    pub x: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
    pub m: Vec<f64>,
    pub q: Vec<f64>,
    /// By model term, by parameter index (zeros where not wanted).
    pub params: Vec<Vec<f64>>,
}

impl Adjoint {
    pub fn zero(bodies: usize, terms: &[TermInstance]) -> Adjoint {
        Adjoint {
            x: vec![[0.0; 3]; bodies],
            v: vec![[0.0; 3]; bodies],
            m: vec![0.0; bodies],
            q: vec![0.0; bodies],
            params: terms.iter().map(|t| vec![0.0; t.params.len()]).collect(),
        }
    }
}

/// One instance of a bond or field term as its definition sees it: its kind, parameters,
/// bodies, their positions (periodic images resolved), and its place in the model.
pub struct Instance<'a> {
    pub kind: Kind,
    pub p: &'a [f64],
    pub bodies: &'a [usize],
    pub x: Vec<[f64; 3]>,
    pub term: usize,
}

/// A direction at an instance's own sites: positions, velocities, masses, charges (one per
/// site) and its parameters.
struct Seed {
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    m: Vec<f64>,
    q: Vec<f64>,
    p: Vec<f64>,
}

/// One input of an instance: a site's coordinate of position or velocity, its mass or charge, or
/// a parameter.
#[derive(Clone, Copy)]
enum Input {
    X(usize, usize),
    V(usize, usize),
    M(usize),
    Q(usize),
    P(usize),
}

impl Instance<'_> {
    fn zero_seed(&self) -> Seed {
        let n = self.bodies.len();
        Seed {
            x: vec![[0.0; 3]; n],
            v: vec![[0.0; 3]; n],
            m: vec![0.0; n],
            q: vec![0.0; n],
            p: vec![0.0; self.p.len()],
        }
    }

    /// The unit direction of one input.
    fn unit(&self, input: Input) -> Seed {
        let mut seed = self.zero_seed();
        match input {
            Input::X(k, c) => seed.x[k][c] = 1.0,
            Input::V(k, c) => seed.v[k][c] = 1.0,
            Input::M(k) => seed.m[k] = 1.0,
            Input::Q(k) => seed.q[k] = 1.0,
            Input::P(k) => seed.p[k] = 1.0,
        }
        seed
    }

    /// Its sites and parameters lifted to duals along `seed`.
    fn lifted(&self, s: &Frame, seed: &Seed) -> (Vec<Dual<f64>>, Vec<Site<Dual<f64>>>) {
        let params = self.p.iter().zip(&seed.p).map(|(&c, &d)| Dual::new(c, d)).collect();
        let sites = self
            .bodies
            .iter()
            .enumerate()
            .map(|(k, &b)| Site {
                x: std::array::from_fn(|c| Dual::new(self.x[k][c], seed.x[k][c])),
                v: std::array::from_fn(|c| Dual::new(s.v[b][c], seed.v[k][c])),
                m: Dual::new(s.m[b], seed.m[k]),
                q: Dual::new(s.q[b], seed.q[k]),
                colour: s.c[b].map(Dual::constant),
            })
            .collect();
        (params, sites)
    }

    /// The derivative of its force on each of its sites along `seed`.
    fn force_along(&self, s: &Frame, seed: &Seed) -> Vec<[f64; 3]> {
        let (params, sites) = self.lifted(s, seed);
        force(self.kind, &params, &sites).iter().map(|f| f.map(|c| c.d)).collect()
    }

    /// Whether its force reads velocities (a dissipation function or a gyroscopic part).
    fn reads_velocities(&self, s: &Frame) -> bool {
        let sites: Vec<Site<f64>> = self
            .bodies
            .iter()
            .zip(&self.x)
            .map(|(&b, x)| Site { x: *x, v: s.v[b], m: s.m[b], q: s.q[b], colour: s.c[b] })
            .collect();
        let r: Vec<&Site<f64>> = sites.iter().collect();
        self.kind.rayleigh(self.p, &r).is_some() || self.kind.gyroscopic(self.p, &r).is_some()
    }

    /// The inputs a pullback gathers: every position coordinate, the velocities if `velocities`,
    /// and what `wanted` names.
    fn inputs(&self, velocities: bool, wanted: (&[usize], bool, bool)) -> Vec<Input> {
        let mut v = vec![];
        for k in 0..self.bodies.len() {
            v.extend((0..3).map(|c| Input::X(k, c)));
            if velocities {
                v.extend((0..3).map(|c| Input::V(k, c)));
            }
            if wanted.1 {
                v.push(Input::M(k));
            }
            if wanted.2 {
                v.push(Input::Q(k));
            }
        }
        v.extend(wanted.0.iter().map(|&p| Input::P(p)));
        v
    }

    /// Adds `value` to the adjoint of one input.
    fn add(&self, input: Input, value: f64, out: &mut Adjoint) {
        match input {
            Input::X(k, c) => out.x[self.bodies[k]][c] += value,
            Input::V(k, c) => out.v[self.bodies[k]][c] += value,
            Input::M(k) => out.m[self.bodies[k]] += value,
            Input::Q(k) => out.q[self.bodies[k]] += value,
            Input::P(p) => out.params[self.term][p] += value,
        }
    }

    /// Adds the derivative of its forces along a direction of the whole state to `df`.
    pub fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) {
        let seed = Seed {
            x: self.bodies.iter().map(|&b| dir.x[b]).collect(),
            v: self.bodies.iter().map(|&b| dir.v[b]).collect(),
            m: self.bodies.iter().map(|&b| dir.m[b]).collect(),
            q: self.bodies.iter().map(|&b| dir.q[b]).collect(),
            p: (0..self.p.len())
                .map(|k| dir.params.get(self.term).and_then(|d| d.get(k)).copied().unwrap_or(0.0))
                .collect(),
        };
        for (&b, f) in self.bodies.iter().zip(self.force_along(s, &seed)) {
            (0..3).for_each(|c| df[b][c] += f[c]);
        }
    }

    /// Adds g·(∂F/∂input) for each of its inputs to their adjoints: forward mode, one input at
    /// a time (an instance has a few dozen).
    pub fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: (&[usize], bool, bool), out: &mut Adjoint) {
        for input in self.inputs(self.reads_velocities(s), wanted) {
            let df = self.force_along(s, &self.unit(input));
            let value =
                df.iter().zip(self.bodies).map(|(f, &b)| f[0] * g[b][0] + f[1] * g[b][1] + f[2] * g[b][2]).sum();
            self.add(input, value, out);
        }
    }

    /// Adds the gradient of its potential energy to the adjoints of its inputs.
    pub fn potential_pullback(&self, s: &Frame, wanted: (&[usize], bool, bool), out: &mut Adjoint) {
        for input in self.inputs(false, wanted) {
            let (params, sites) = self.lifted(s, &self.unit(input));
            let value = self.kind.potential(&params, &sites.iter().collect::<Vec<_>>()).d;
            self.add(input, value, out);
        }
    }
}

/// The indices `radial_sensitivities` and `radial_potential` take for what `wanted` names:
/// the parameters, then [mᵢ, mⱼ, qᵢ, qⱼ] after them.
fn pair_inputs(p: usize, wanted: (&[usize], bool, bool)) -> Vec<usize> {
    let mut which: Vec<usize> = wanted.0.to_vec();
    if wanted.1 {
        which.extend([p, p + 1]);
    }
    if wanted.2 {
        which.extend([p + 2, p + 3]);
    }
    which
}

/// A pair's force derivative along `dir` (added to body i, taken from body j) and the pullback,
/// through its radial form.
pub struct PairDerivative<'a> {
    pub kind: Kind,
    pub p: &'a [f64],
    /// This instance's place in the model.
    pub term: usize,
    /// The inputs a pullback gathers (`pair_inputs`), worked out once per instance.
    which: Vec<usize>,
    /// The square of its reach (∞ for an unbounded term).
    pub reach2: f64,
}

impl<'a> PairDerivative<'a> {
    /// The inputs a pullback gathers (numbered as in `pair_inputs`).
    pub fn which(&self) -> &[usize] {
        &self.which
    }

    pub fn new(kind: Kind, p: &'a [f64], term: usize, wanted: (&[usize], bool, bool)) -> PairDerivative<'a> {
        let reach2 = kind.reach(p).powi(2);
        PairDerivative { kind, p, term, which: pair_inputs(p.len(), wanted), reach2 }
    }

    fn bodies(s: &Frame, i: usize, j: usize) -> ([f64; 4], [[f64; 2]; 2]) {
        ([s.m[i], s.m[j], s.q[i], s.q[j]], [s.c[i], s.c[j]])
    }

    /// s and s_r from a hand-derived jet (the pair term reads neither masses nor charges
    /// then), or from the definition.
    fn radial(&self, jet: Option<Jet>, s: &Frame, i: usize, j: usize, r: f64) -> Radial {
        match jet {
            Some(k) => Radial { s: k.s, s_r: k.s_r },
            None => {
                let (b, col) = Self::bodies(s, i, j);
                radial(self.kind, self.p, b, col, r)
            }
        }
    }

    /// ∂s along each of `which` (numbered as in `pair_inputs`), from the jet or the definition.
    fn sensitivities(&self, jet: Option<Jet>, s: &Frame, i: usize, j: usize, r: f64, which: &[usize]) -> Vec<f64> {
        match jet {
            Some(k) => which.iter().map(|&w| if w < self.p.len() { k.ds[w] } else { 0.0 }).collect(),
            None => {
                let (b, col) = Self::bodies(s, i, j);
                radial_sensitivities(self.kind, self.p, b, col, r, which)
            }
        }
    }

    /// δfᵢ for the pair (i, j) at displacement d = xⱼ − xᵢ.
    pub fn tangent(&self, jet: Option<Jet>, s: &Frame, dir: &Direction, i: usize, j: usize, d: [f64; 3]) -> [f64; 3] {
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let k = self.radial(jet, s, i, j, r);
        let dd: [f64; 3] = std::array::from_fn(|c| dir.x[j][c] - dir.x[i][c]);
        let along = d[0] * dd[0] + d[1] * dd[1] + d[2] * dd[2];
        // the parameters', masses' and charges' share, where any of them moves
        let dp = dir.params.get(self.term).map(|v| v.as_slice()).unwrap_or(&[]);
        let moved: Vec<(usize, f64)> = dp
            .iter()
            .copied()
            .enumerate()
            .chain([dir.m[i], dir.m[j], dir.q[i], dir.q[j]].into_iter().enumerate().map(|(k, v)| (self.p.len() + k, v)))
            .filter(|(_, v)| *v != 0.0)
            .collect();
        let ds: f64 = if moved.is_empty() {
            0.0
        } else {
            let which: Vec<usize> = moved.iter().map(|m| m.0).collect();
            self.sensitivities(jet, s, i, j, r, &which).iter().zip(&moved).map(|(s, m)| s * m.1).sum()
        };
        std::array::from_fn(|c| k.s * dd[c] + (k.s_r * along + ds) * d[c])
    }

    /// Adds (∂fᵢ/∂·)ᵀ(gᵢ − gⱼ) to `out`, for the pair (i, j) at d.
    #[allow(clippy::too_many_arguments)]
    pub fn pullback(
        &self,
        jet: Option<Jet>,
        s: &Frame,
        g: &[[f64; 3]],
        i: usize,
        j: usize,
        d: [f64; 3],
        out: &mut Adjoint,
    ) {
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let k = self.radial(jet, s, i, j, r);
        let dg: [f64; 3] = std::array::from_fn(|c| g[i][c] - g[j][c]);
        let a = dg[0] * d[0] + dg[1] * d[1] + dg[2] * d[2];
        for c in 0..3 {
            let wrt_d = k.s * dg[c] + k.s_r * a * d[c];
            out.x[j][c] += wrt_d;
            out.x[i][c] -= wrt_d;
        }
        match jet {
            Some(k) => {
                for &w in &self.which {
                    self.spread_one(i, j, w, if w < self.p.len() { k.ds[w] * a } else { 0.0 }, out);
                }
            }
            None if self.which.is_empty() => {}
            None => {
                let sens = self.sensitivities(None, s, i, j, r, &self.which);
                for (&w, s) in self.which.iter().zip(sens) {
                    self.spread_one(i, j, w, s * a, out);
                }
            }
        }
    }

    /// Adds the gradient of the pair's potential energy to `out`.
    pub fn potential_pullback(&self, s: &Frame, i: usize, j: usize, d: [f64; 3], out: &mut Adjoint) {
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let (b, col) = Self::bodies(s, i, j);
        let (dv, sens) = radial_potential(self.kind, self.p, b, col, r, &self.which);
        for c in 0..3 {
            out.x[j][c] += dv * d[c] / r;
            out.x[i][c] -= dv * d[c] / r;
        }
        for (&w, share) in self.which.iter().zip(sens) {
            self.spread_one(i, j, w, share, out);
        }
    }

    /// An input's share (numbered as in `pair_inputs`) added where it belongs.
    fn spread_one(&self, i: usize, j: usize, w: usize, share: f64, out: &mut Adjoint) {
        match w.checked_sub(self.p.len()) {
            None => out.params[self.term][w] += share,
            Some(0) => out.m[i] += share,
            Some(1) => out.m[j] += share,
            Some(2) => out.q[i] += share,
            _ => out.q[j] += share,
        }
    }
}

/// The positions of a bond's bodies as it sees them: the first, and each other at its nearest
/// image from it.
pub fn bond_positions(x: &[[f64; 3]], bodies: &[usize], images: &Option<Images>) -> Vec<[f64; 3]> {
    let x0 = x[bodies[0]];
    bodies
        .iter()
        .map(|&b| match images {
            None => x[b],
            Some(im) => {
                let d = im.image([x[b][0] - x0[0], x[b][1] - x0[1], x[b][2] - x0[2]]);
                [x0[0] + d[0], x0[1] + d[1], x0[2] + d[2]]
            }
        })
        .collect()
}

/// A pair of bodies singular for the radial form (at one point): an error like the force's.
pub fn coincident(name: &'static str, i: usize, j: usize) -> Singularity {
    Singularity { term: name, bodies: vec![i, j], what: super::SAME_POINT, seen: None }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::dual::Rng;
    use crate::forces::group;
    use lagra_checker::model::{Body, Model, UnitSystem};
    use lagra_checker::terms::Shape;

    /// A random state of one instance of `kind` on its bodies, with generic parameters.
    struct Case {
        model: Model,
        x: Vec<[f64; 3]>,
        v: Vec<[f64; 3]>,
        c: Vec<[f64; 2]>,
    }

    fn case(kind: Kind, seed: u64) -> Case {
        let mut rng = Rng::new(seed);
        let spec = kind.spec();
        let n = spec.shape.arity().max(2);
        let params: Vec<f64> = spec
            .params
            .iter()
            .flat_map(|p| match p.name {
                "R0" => vec![3.0],
                "cutoff" => vec![4.0],
                "n" => vec![2.0],
                _ => (0..p.len).map(|_| rng.uniform(0.5, 1.5)).collect(),
            })
            .collect();
        let bodies = (0..n)
            .map(|_| Body {
                mass: rng.uniform(0.5, 2.0),
                charge: rng.uniform(-1.0, 1.0),
                colour: [0.0; 2],
                moments: None,
                solid: None,
            })
            .collect();
        let sites = if matches!(spec.shape, Shape::Bond(_)) { (0..n).collect() } else { vec![] };
        let terms = vec![TermInstance { kind, sites, params }];
        // bodies 0.9 to 1.4 apart, in no special alignment
        let x = (0..n)
            .map(|i| [i as f64 * 1.1 + rng.uniform(-0.2, 0.2), rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4)])
            .collect();
        let v = (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-1.0, 1.0))).collect();
        let c = (0..n).map(|_| [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)]).collect();
        Case {
            model: Model {
                units: UnitSystem::Reduced,
                cell: None,
                bodies,
                terms,
                constraints: vec![],
                thermostat: None,
                floor: None,
                pins: vec![],
            },
            x,
            v,
            c,
        }
    }

    /// The fast force at the case moved by h along (dx, dv, dm, dq, dp).
    fn fast_force(k: &Case, h: f64, d: &([Vec<[f64; 3]>; 2], [Vec<f64>; 2], Vec<f64>)) -> Vec<[f64; 3]> {
        let mut model = k.model.clone();
        for (t, dp) in model.terms[0].params.iter_mut().zip(&d.2) {
            *t += h * dp;
        }
        let moved = |a: &[[f64; 3]], b: &[[f64; 3]]| -> Vec<[f64; 3]> {
            a.iter().zip(b).map(|(a, b)| std::array::from_fn(|c| a[c] + h * b[c])).collect()
        };
        let (x, v) = (moved(&k.x, &d.0[0]), moved(&k.v, &d.0[1]));
        let m: Vec<f64> = model.bodies.iter().zip(&d.1[0]).map(|(b, dm)| b.mass + h * dm).collect();
        let q: Vec<f64> = model.bodies.iter().zip(&d.1[1]).map(|(b, dq)| b.charge + h * dq).collect();
        let g = group(model.terms[0].kind, &[(0, &model.terms[0])], &model, &None);
        let mut f = vec![[0.0; 3]; x.len()];
        g.accumulate(&Frame { x: &x, v: &v, m: &m, q: &q, c: &k.c }, &mut f, true).unwrap();
        f
    }

    /// For every term: the tangent from the definition is the central difference of the fast
    /// force, and the pullback is its transpose (g·(J u) = (Jᵀg)·u to rounding).
    #[test]
    fn tangents_are_the_forces_derivatives_and_pullbacks_their_transposes() {
        // (a density term needs a crowd to press: its derivatives are tested in `sph` over a block)
        for &kind in Kind::ALL.iter().filter(|k| k.spec().shape != Shape::Density) {
            for seed in 0..4 {
                let k = case(kind, seed);
                let n = k.x.len();
                let mut rng = Rng::new(100 + seed);
                let mut vecs =
                    || -> Vec<[f64; 3]> { (0..n).map(|_| std::array::from_fn(|_| rng.uniform(-1.0, 1.0))).collect() };
                let (dx, dv, g) = (vecs(), vecs(), vecs());
                let mut rng = Rng::new(200 + seed);
                let dm: Vec<f64> = (0..n).map(|_| rng.uniform(-0.5, 0.5)).collect();
                let dq: Vec<f64> = (0..n).map(|_| rng.uniform(-0.5, 0.5)).collect();
                let dp: Vec<f64> = k.model.terms[0].params.iter().map(|_| rng.uniform(-0.5, 0.5)).collect();
                // a cutoff, an integer multiplicity and a FENE limit are held fixed
                let fixed = |name: &str| matches!(name, "cutoff" | "n" | "R0" | "slip");
                let names: Vec<&str> =
                    kind.spec().params.iter().flat_map(|p| std::iter::repeat_n(p.name, p.len)).collect();
                let dp: Vec<f64> = dp.iter().zip(&names).map(|(d, n)| if fixed(n) { 0.0 } else { *d }).collect();
                let m: Vec<f64> = k.model.bodies.iter().map(|b| b.mass).collect();
                let q: Vec<f64> = k.model.bodies.iter().map(|b| b.charge).collect();
                let frame = Frame { x: &k.x, v: &k.v, m: &m, q: &q, c: &k.c };
                let params = vec![dp.clone()];
                let dir = Direction { x: &dx, v: &dv, m: &dm, q: &dq, params: &params };
                let g_group = group(kind, &[(0, &k.model.terms[0])], &k.model, &None);
                let mut df = vec![[0.0; 3]; n];
                g_group.tangent(&frame, &dir, &mut df).unwrap();
                let h = 1e-6;
                let d = ([dx.clone(), dv.clone()], [dm.clone(), dq.clone()], dp.clone());
                let (plus, minus) = (fast_force(&k, h, &d), fast_force(&k, -h, &d));
                let scale = plus.iter().flatten().chain(df.iter().flatten()).fold(1e-300f64, |a, c| a.max(c.abs()));
                for b in 0..n {
                    for c in 0..3 {
                        let fd = (plus[b][c] - minus[b][c]) / (2.0 * h);
                        assert!(
                            (fd - df[b][c]).abs() <= 1e-6 * scale,
                            "{kind:?} seed {seed} body {b} axis {c}: tangent {} vs difference {fd}",
                            df[b][c]
                        );
                    }
                }
                // the transpose
                let wanted = Wanted { params: vec![(0..dp.len()).collect()], masses: true, charges: true };
                let mut out = Adjoint::zero(n, &k.model.terms);
                g_group.pullback(&frame, &g, &wanted, &mut out).unwrap();
                let dot3 = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
                    a.iter().zip(b).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum()
                };
                let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(a, b)| a * b).sum() };
                let forward = dot3(&g, &df);
                let reverse = dot3(&out.x, &dx)
                    + dot3(&out.v, &dv)
                    + dot(&out.m, &dm)
                    + dot(&out.q, &dq)
                    + dot(&out.params[0], &dp);
                assert!(
                    (forward - reverse).abs() <= 1e-11 * (forward.abs() + scale),
                    "{kind:?} seed {seed}: g·Ju {forward} vs Jᵀg·u {reverse}"
                );
            }
        }
    }
}
