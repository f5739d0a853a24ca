//! The physical quantities a claim speaks of, evaluated from the model's definitions on one
//! state, generic over [`Real`]: energy, dissipated power, linear and angular momentum.

use crate::broad_phase::{Foreseen, Near, Neighbourhood};
use crate::model::{Cell, Images, Model, Snapshot, TermInstance};
use crate::real::{cross3, dot3, norm2, sub3, Real, Vec3};
use crate::terms::{Shape, Site};
use std::borrow::Cow;
use std::sync::{Arc, OnceLock};

mod pair_sums;
mod parts;

/// Bodies from which a checkpoint's pair sums spread over the helpers (`Lifted::on_threads`):
/// handing a sum out and waking the helpers costs tens of microseconds. Measured (2-CPU AMD
/// EPYC, LJ liquid, energy judged every step, 200 steps, always spread on 2 CPUs against one
/// CPU): 256 bodies 0.15 against 0.12 s, 864 bodies 0.40 against 0.46 s, 2,048 bodies 0.78
/// against 0.97 s.
const SPREAD_FROM: usize = 512;

pub use pair_sums::{asked_reach, foresee, pair_reaches, PairSum};
pub use parts::{Local, Part, Parts, Region, Whole, PART_BITS};

/// The model and one state lifted into `R` (`proto` fixes the kind and precision).
pub struct Lifted<R> {
    pub(crate) sites: Vec<Site<R>>,
    /// A thermostat chain's links (η, ξ).
    links: Vec<[R; 2]>,
    /// Each rigid body's spin: orientation q, body-frame angular momentum π, principal moments.
    pub(crate) spins: Vec<Spin<R>>,
    params: Vec<Vec<R>>,
    pub(crate) zero: R,
    /// The exact positions, to choose periodic images from.
    x: Vec<[f64; 3]>,
    cell: Option<Cell>,
    images: Images,
    /// k·L for k = −1, 0, 1 along each axis (L: the cell's side), the shifts nearly every
    /// periodic image takes, evaluated once: ~5% of a 32,000-body checkpoint was evaluating them
    /// for each pair.
    shifts: [[R; 3]; 3],
    /// Threads to sum pair terms and the bodies' kinetic energy and momenta on (the bits are the
    /// same for any count).
    threads: usize,
    /// Pair lists made ahead of this state, used where they hold (the bits are the same).
    ahead: Arc<[Foreseen]>,
    /// ½ Σ m |v|² and Σ m v, summed in one pass over the sites the first time either is asked
    /// for: the energy and the momentum each reading them alone was four passes, ~2% of a
    /// checkpoint of 32,000 bodies.
    moving: OnceLock<[R; 4]>,
}

impl<R: PairSum> Lifted<R> {
    pub fn new(model: &Model, s: &Snapshot, proto: &R) -> Self {
        Lifted::reusing(Vec::new(), model, s, proto)
    }

    /// `new`, its sites written into `sites`'s memory (the sites of an earlier state,
    /// `into_sites`): fresh memory for 32,000 sites is ~1,300 page faults, ~3 ms.
    pub fn reusing(mut sites: Vec<Site<R>>, model: &Model, s: &Snapshot, proto: &R) -> Self {
        let lift3 = |a: &[f64; 3]| a.map(|c| proto.lift(c));
        sites.clear();
        sites.extend(model.bodies.iter().zip(s.x.iter().zip(s.v)).map(|(b, (x, v))| Site {
            x: lift3(x),
            v: lift3(v),
            m: proto.lift(b.mass),
            q: proto.lift(b.charge),
            colour: b.colour.map(|c| proto.lift(c)),
        }));
        // each instance's parameters, then its constants (`Definition::constants`), once
        let lifted = |t: &TermInstance| -> Vec<R> { t.params.iter().map(|&c| proto.lift(c)).collect() };
        let params = model.terms.iter().map(|t| [lifted(t), t.kind.constants(&lifted(t))].concat()).collect();
        let sides = model.cell.map_or([0.0; 3], |c| c.size);
        Lifted {
            sites,
            links: s.chain.iter().map(|l| l.map(|c| proto.lift(c))).collect(),
            spins: model
                .rigid()
                .zip(s.spin)
                .map(|(i, s)| Spin {
                    q: std::array::from_fn(|k| proto.lift(s[k])),
                    pi: std::array::from_fn(|k| proto.lift(s[4 + k])),
                    moments: i.map(|c| proto.lift(c)),
                })
                .collect(),
            params,
            zero: proto.lift(0.0),
            x: s.x.to_vec(),
            shifts: sides.map(|l| [-1.0, 0.0, 1.0].map(|k| proto.lift(k) * proto.lift(l))),
            cell: model.cell,
            images: Images::of(&model.cell),
            threads: 1,
            ahead: Arc::default(),
            moving: OnceLock::new(),
        }
    }

    /// The sites' memory, for the next state (`reusing`).
    pub fn into_sites(self) -> Vec<Site<R>> {
        self.sites
    }

    /// The same, summing on `n` threads if there are bodies enough to pay for handing the work
    /// out (`SPREAD_FROM`), else on one.
    pub fn on_threads(self, n: usize) -> Self {
        Lifted { threads: if self.x.len() >= SPREAD_FROM { n } else { 1 }, ..self }
    }

    /// The same, with pair lists made ahead (`foresee`).
    pub fn foreseeing(self, ahead: Arc<[Foreseen]>) -> Self {
        Lifted { ahead, ..self }
    }

    /// Site `j` as seen from site `i`: itself, or in a periodic cell its nearest image
    /// (`image_of`).
    fn seen_from(&self, i: usize, j: usize) -> Cow<'_, Site<R>> {
        match self.image_of(i, j) {
            Some(x) => Cow::Owned(Site { x, ..self.sites[j].clone() }),
            None => Cow::Borrowed(&self.sites[j]),
        }
    }

    /// Where site `i` sees site `j` when that is not where j is: in a periodic cell, at
    /// x_j − k·L with k chosen from the exact positions (`Cell::shift`) and the shift evaluated
    /// in `R`.
    #[inline(always)]
    fn image_of(&self, i: usize, j: usize) -> Option<Vec3<R>> {
        let k = self.images.shift(std::array::from_fn(|a| self.x[j][a] - self.x[i][a]));
        let c = self.cell.as_ref().filter(|_| k != [0.0; 3])?;
        // k·L evaluated once for |k| ≤ 1 (`shifts`), here beyond
        let kl = |a: usize| self.shifts[a].get((k[a] + 1.0) as usize).filter(|_| k[a] >= -1.0).cloned();
        let shift = |a: usize| kl(a).unwrap_or_else(|| self.zero.lift(k[a]) * self.zero.lift(c.size[a]));
        Some(std::array::from_fn(|a| self.sites[j].x[a].clone() - shift(a)))
    }

    /// Pair `p`: its first site, and its second as seen from the first.
    fn sites_of(&self, p: &Near) -> (&Site<R>, Cow<'_, Site<R>>) {
        (&self.sites[p.i], self.seen_from(p.i, p.j))
    }

    /// `acc` + Σ `term(n, sites)` over the instances `which` picks (`None` adds nothing), in an order
    /// fixed by the model and the state alone: instances in order; pairs and bonds see each
    /// other's nearest periodic image; a pair term's pairs by `pairs(n, acc, near)`, from the
    /// broad phase's `near` (`in_chunks`, or a way that gives the same bits for any order).
    fn sum<T: Clone + Send + Sync>(
        &self,
        model: &Model,
        which: impl Fn(&TermInstance) -> bool,
        (mut acc, add): (T, impl Fn(T, T) -> T + Sync),
        term: impl Fn(usize, &[&Site<R>]) -> Option<T> + Sync,
        pairs: impl Fn(usize, T, &Neighbourhood) -> T,
    ) -> T {
        let fold = |acc: T, each: &mut dyn Iterator<Item = Option<T>>| each.flatten().fold(acc, &add);
        for (n, t) in model.terms.iter().enumerate().filter(|(_, t)| which(t)) {
            match t.kind.spec().shape {
                Shape::Bond(_) => {
                    let seen: Vec<Cow<Site<R>>> = t.sites.iter().map(|&j| self.seen_from(t.sites[0], j)).collect();
                    acc =
                        fold(acc, &mut std::iter::once(term(n, &seen.iter().map(|s| s.as_ref()).collect::<Vec<_>>())));
                }
                Shape::External if t.sites.is_empty() => acc = fold(acc, &mut self.sites.iter().map(|s| term(n, &[s]))),
                Shape::External => acc = fold(acc, &mut t.sites.iter().map(|&i| term(n, &[&self.sites[i]]))),
                // Broad phase: a pair whose nearest image is beyond the term's reach contributes
                // exactly zero, so leaving it out is exact. The broad phase keeps every pair
                // within the reach (`asked_reach`), from a grid or a list made ahead, each with
                // its nearest image.
                Shape::Pairwise | Shape::Density => {
                    acc = pairs(n, acc, &Neighbourhood::new(&self.x, &self.cell, asked_reach(t), &self.ahead))
                }
            }
        }
        acc
    }

    /// ½ Σ m |v|² and Σ m v (`moving`).
    fn moving(&self) -> &[R; 4] {
        let half = self.zero.lift(0.5);
        let p = |s: &Site<R>, c: usize| s.m.clone() * s.v[c].clone();
        let each = |s: &Site<R>| [half.clone() * s.m.clone() * norm2(&s.v), p(s, 0), p(s, 1), p(s, 2)];
        self.moving.get_or_init(|| R::sum_over(self, each))
    }

    /// ½ Σ m |v|², and each rigid body's ½ Σ π_k² / I_k.
    pub fn kinetic(&self) -> R {
        let half = self.zero.lift(0.5);
        self.spins.iter().fold(self.moving()[0].clone(), |acc, s| {
            (0..3).fold(acc, |acc, k| acc + half.clone() * s.pi[k].clone().powi(2) / s.moments[k].clone())
        })
    }

    pub fn potential(&self, model: &Model) -> R {
        let term = |n: usize, s: &[&Site<R>]| Some(model.terms[n].kind.potential(&self.params[n], s));
        let pairs = |n: usize, acc: R, near: &Neighbourhood| R::add_potentials(self, acc, model.terms[n].kind, n, near);
        let fluid = |t: &TermInstance| t.kind.spec().shape == Shape::Density;
        let rest = self.sum(model, |t| !fluid(t), (self.zero.clone(), R::add), term, pairs);
        let fluids = model.terms.iter().enumerate().filter(|(_, t)| fluid(t));
        fluids.fold(rest, |acc, (n, t)| acc + self.fluid_energy(t, &self.params[n]))
    }

    /// Σₐ `internal`(a, ρₐ) of a density term, ρₐ being a's own share and every share of the
    /// bodies within reach (the broad phase's pairs, each giving to both of its bodies, summed
    /// in the pairs' order), as the nearest image sees them.
    fn fluid_energy(&self, t: &TermInstance, p: &[R]) -> R {
        let (kind, share) = (t.kind, |a: &Site<R>, b: &Site<R>| t.kind.density(p, a, b).expect("a density term"));
        let mut rho: Vec<R> = self.sites.iter().map(|a| t.kind.own_density(p, a).expect("a density term")).collect();
        for pair in Neighbourhood::new(&self.x, &self.cell, asked_reach(t), &self.ahead).of(0..self.sites.len()) {
            let (a, b) = self.sites_of(&pair);
            let (to_a, to_b) = (share(a, &b), share(&b, a));
            rho[pair.i] = rho[pair.i].clone() + to_a;
            rho[pair.j] = rho[pair.j].clone() + to_b;
        }
        self.sites
            .iter()
            .zip(rho)
            .fold(self.zero.clone(), |acc, (a, rho)| acc + kind.internal(p, a, rho).expect("a density term"))
    }

    /// H = T + V (every term of the vocabulary so far has a velocity-independent potential),
    /// and with a thermostat chain H′ = H + the chain's share.
    pub fn energy(&self, model: &Model) -> R {
        let h = self.kinetic() + self.potential(model);
        match &model.thermostat {
            Some(chain) => h + chain.energy(&self.links, &self.zero),
            None => h,
        }
    }

    /// The rate 2·ΣF at which the dissipative terms remove energy, and which terms do.
    pub fn dissipated_power(&self, model: &Model) -> R {
        // only the instances that can dissipate: a conservative term is never visited
        let term = |n: usize, s: &[&Site<R>]| model.terms[n].kind.power(&self.params[n], s);
        let pairs = |n: usize, acc: R, near: &Neighbourhood| R::add_powers(self, acc, model.terms[n].kind, n, near);
        self.sum(model, |t| t.dissipates(), (self.zero.clone(), R::add), term, pairs)
    }

    /// |x_j − x_i|, to the nearest periodic image.
    pub fn distance(&self, i: usize, j: usize) -> R {
        norm2(&sub3(&self.seen_from(i, j).x, &self.sites[i].x)).sqrt()
    }

    /// Σ m v, plus the share of any term with one (a magnetic field's q B × x): Noether's
    /// charge of translations.
    pub fn momentum(&self, model: &Model) -> Vec3<R> {
        self.with_shares(model, std::array::from_fn(|c| self.moving()[c + 1].clone()), 0)
    }

    /// Σ m x × v, plus the terms' shares: Noether's charge of rotations about the origin.
    pub fn angular_momentum(&self, model: &Model) -> Vec3<R> {
        let l = |s: &Site<R>, a: usize, b: usize| {
            s.m.clone() * (s.x[a].clone() * s.v[b].clone() - s.x[b].clone() * s.v[a].clone())
        };
        let free = R::sum_over(self, |s| [l(s, 1, 2), l(s, 2, 0), l(s, 0, 1)]);
        let spun = self.spins.iter().fold(free, |acc, s| {
            let l = s.world();
            std::array::from_fn(|c| acc[c].clone() + l[c].clone())
        });
        self.with_shares(model, spun, 1)
    }

    /// `charge` plus share `which` (0 momentum, 1 angular momentum) of every instance of a kind
    /// that has one.
    fn with_shares(&self, model: &Model, charge: Vec3<R>, which: usize) -> Vec3<R> {
        let add = |[a0, a1, a2]: Vec3<R>, [b0, b1, b2]: Vec3<R>| [a0 + b0, a1 + b1, a2 + b2];
        let zero = std::array::from_fn(|_| self.zero.clone());
        let term = |n: usize, s: &[&Site<R>]| {
            model.terms[n].kind.charge_share(&self.params[n], s).map(|share| share[which].clone())
        };
        let pairs = self.in_chunks((zero, add), self.one_by_one(&term, add));
        self.sum(model, |t| t.kind.has_charge_share(), (charge, add), term, pairs)
    }
}

/// A rigid body's spin lifted into `R`.
pub(crate) struct Spin<R> {
    q: [R; 4],
    pub(crate) pi: Vec3<R>,
    pub(crate) moments: Vec3<R>,
}

/// The axes (the rotation's columns) of a spin's orientation q/|q|, turned in binary64 as
/// `Spin::axes` turns them in `R`: for a broad phase that only culls.
pub(crate) fn rough_axes(spin: &[f64; 7]) -> [Vec3<f64>; 3] {
    Spin { q: [spin[0], spin[1], spin[2], spin[3]], pi: [0.0; 3], moments: [1.0; 3] }.axes()
}

impl<R: Real> Spin<R> {
    /// The angular momentum about the centre of mass in the world frame: π turned by q/|q|,
    /// ((w² − u·u) π + 2(u·π) u + 2w (u × π)) / |q|² with q = (w, u) — the rotation a unit
    /// quaternion gives, divided by |q|² so that a q rounded off the unit sphere still turns
    /// without stretching.
    fn world(&self) -> Vec3<R> {
        self.turn(&self.pi)
    }

    /// The body axes in the world: the columns of the rotation q/|q| (`turn` of each e_k).
    pub(crate) fn axes(&self) -> [Vec3<R>; 3] {
        let zero = self.q[0].lift(0.0);
        std::array::from_fn(|k| self.turn(&std::array::from_fn(|c| zero.lift(if c == k { 1.0 } else { 0.0 }))))
    }

    /// A body-frame vector p seen in the world.
    pub(crate) fn turn(&self, p: &Vec3<R>) -> Vec3<R> {
        let (w, u) = (self.q[0].clone(), [self.q[1].clone(), self.q[2].clone(), self.q[3].clone()]);
        let uu = norm2(&u);
        let (two, along) = (w.lift(2.0), dot3(&u, p));
        let across = cross3(&u, p);
        let n2 = w.clone().powi(2) + uu.clone();
        std::array::from_fn(|c| {
            ((w.clone().powi(2) - uu.clone()) * p[c].clone()
                + two.clone() * along.clone() * u[c].clone()
                + two.clone() * w.clone() * across[c].clone())
                / n2.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosure::Enclosure;
    use crate::model::{Body, TermInstance, UnitSystem};
    use crate::outward::Outward;
    use crate::terms::Kind;
    use proptest::prelude::*;
    use rug::Float;

    fn model(k: f64, r0: f64, gamma: f64, g: f64) -> Model {
        Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![
                Body { mass: 1.0, charge: 1.0, colour: [0.0; 2], moments: None, solid: None },
                Body { mass: 2.5, charge: -0.5, colour: [0.0; 2], moments: None, solid: None },
                Body { mass: 0.5, charge: 2.0, colour: [0.0; 2], moments: None, solid: None },
            ],
            terms: vec![
                TermInstance { kind: Kind::HarmonicBond, sites: vec![0, 1], params: vec![k, r0, gamma] },
                TermInstance { kind: Kind::MagneticField, sites: vec![], params: vec![0.3, -0.2, 1.1] },
                TermInstance { kind: Kind::UniformAcceleration, sites: vec![], params: vec![0.0, -g, 0.0] },
                TermInstance { kind: Kind::Gravity, sites: vec![], params: vec![0.7] },
            ],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        }
    }

    /// One rigid body of moments (1, 2, 4) at rest at the origin.
    fn brick() -> Model {
        let body = Body {
            mass: 3.0,
            charge: 0.0,
            colour: [0.0; 2],
            moments: Some([1.0, 2.0, 4.0]),
            solid: Some(crate::model::Solid { extent: crate::model::Extent::Cuboid([0.5, 1.0, 1.5]), friction: 0.5 }),
        };
        Model {
            units: UnitSystem::Reduced,
            cell: None,
            bodies: vec![body],
            terms: vec![],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        }
    }

    proptest! {
        /// A rigid body's kinetic energy is ½ Σ π_k²/I_k and its angular momentum π turned by
        /// q/|q| (against nalgebra's rotation, and whatever |q| is), each enclosed.
        #[test]
        fn a_spin_has_its_energy_and_angular_momentum(
            axis in prop::array::uniform3(-1.0f64..1.0), angle in -3.0f64..3.0, pi in coord(), stretch in 0.5f64..2.0,
        ) {
            use nalgebra::{Unit, UnitQuaternion, Vector3};
            let axis = Unit::try_new(Vector3::from(axis), 1e-3);
            prop_assume!(axis.is_some());
            let q = UnitQuaternion::from_axis_angle(&axis.unwrap(), angle).into_inner() * stretch;
            let spin = [[q.w, q.i, q.j, q.k, pi[0], pi[1], pi[2]]];
            let m = brick();
            let e = Lifted::new(&m, &Snapshot { step: 0, t: 0.0, x: &[[0.0; 3]], v: &[[0.0; 3]], chain: &[], spin: &spin }, &Outward::NAN);
            let kinetic = 0.5 * (pi[0] * pi[0] + pi[1] * pi[1] / 2.0 + pi[2] * pi[2] / 4.0);
            let (lo, hi) = e.kinetic().bounds();
            prop_assert!(lo <= kinetic * (1.0 + 1e-15) && kinetic * (1.0 - 1e-15) <= hi && hi - lo < 1e-13 * (1.0 + kinetic));
            let l = UnitQuaternion::new_normalize(q) * Vector3::from(pi);
            for (c, lc) in e.angular_momentum(&m).iter().zip(l.iter()) {
                let (lo, hi) = c.bounds();
                prop_assert!(lo - 1e-13 <= *lc && *lc <= hi + 1e-13 && hi - lo < 1e-12, "{lo} {hi} {lc}");
            }
        }
    }

    proptest! {
        /// Body 1 seen from body 0 through the image k boxes away: k·L from the table made once
        /// (`shifts`, |k| ≤ 1) or evaluated there (farther), the bits of x₁ − k·L evaluated
        /// alone, in binary64 enclosures and in MPFR; none where k = 0.
        #[test]
        fn an_image_is_its_shift_evaluated_alone(
            x0 in coord(), d in prop::array::uniform3(-0.45f64..0.45), k in prop::array::uniform3(-3i32..=3), side in 1.0f64..30.0,
        ) {
            let size = [side, side * 1.3, side * 0.7];
            let m = Model { cell: Some(Cell { size, periodic: [true; 3] }), ..model(1.0, 1.0, 0.0, 0.0) };
            let x = [x0, std::array::from_fn(|a| x0[a] + (d[a] + f64::from(k[a])) * size[a]), [0.0; 3]];
            let s = Snapshot { step: 0, t: 0.0, x: &x, v: &[[0.0; 3]; 3], chain: &[], spin: &[] };
            let direct = |q: &Lifted<Float>| -> Vec3<Float> {
                std::array::from_fn(|a| q.sites[1].x[a].clone() - q.zero.lift(f64::from(k[a])) * q.zero.lift(size[a]))
            };
            let (q, exact) = (Lifted::new(&m, &s, &Outward::NAN), Lifted::new(&m, &s, &Float::new(256)));
            match (q.image_of(0, 1), exact.image_of(0, 1)) {
                (None, None) => prop_assert_eq!(k, [0; 3]),
                (Some(seen), Some(seen_exactly)) => {
                    let bits = |e: &Outward| (e.bounds().0.to_bits(), e.bounds().1.to_bits());
                    for a in 0..3 {
                        let alone = q.sites[1].x[a] - q.zero.lift(f64::from(k[a])) * q.zero.lift(size[a]);
                        prop_assert_eq!(bits(&seen[a]), bits(&alone), "axis {}, k {:?}", a, k);
                    }
                    prop_assert_eq!(seen_exactly, direct(&exact));
                }
                _ => prop_assert!(false, "the enclosures disagree on whether there is an image"),
            }
        }
    }

    /// A state whose spins do not fit the model is refused, as a zero orientation is.
    #[test]
    fn spins_must_fit_the_model() {
        let m = brick();
        let state = |spin: &[[f64; 7]]| {
            m.check_state(&Snapshot { step: 0, t: 0.0, x: &[[0.0; 3]], v: &[[0.0; 3]], chain: &[], spin })
                .map_err(|e| e.to_string())
        };
        assert!(state(&[[1.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0]]).is_ok());
        assert_eq!(state(&[]).unwrap_err(), "state has 0 spins for 1 rigid bodies");
        assert!(state(&[[0.0; 7]]).unwrap_err().contains("orientation is zero"));
        assert!(state(&[[1.0, 0.0, 0.0, f64::NAN, 1.0, 2.0, 3.0]]).unwrap_err().contains("not finite"));
    }

    fn coord() -> impl Strategy<Value = [f64; 3]> {
        prop::array::uniform3(-10.0f64..10.0)
    }

    proptest! {
        /// The interval enclosure of every quantity contains its 256-bit MPFR value.
        #[test]
        fn interval_encloses_mpfr(x in prop::array::uniform3(coord()), v in prop::array::uniform3(coord()),
                                  k in 0.1f64..100.0, r0 in 0.0f64..3.0, gamma in 0.0f64..2.0, g in 0.0f64..20.0) {
            let m = model(k, r0, gamma, g);
            let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
            let iv = Lifted::new(&m, &s, &Outward::NAN);
            let hp = Lifted::new(&m, &s, &Float::new(256));
            let inside = |i: Outward, f: Float| {
                let (lo, hi) = (Float::with_val(256, i.bounds().0), Float::with_val(256, i.bounds().1));
                lo <= f && f <= hi
            };
            prop_assert!(inside(iv.energy(&m), hp.energy(&m)));
            prop_assert!(inside(iv.dissipated_power(&m), hp.dissipated_power(&m)));
            for (a, b) in iv.momentum(&m).into_iter().zip(hp.momentum(&m)) { prop_assert!(inside(a, b)); }
            for (a, b) in iv.angular_momentum(&m).into_iter().zip(hp.angular_momentum(&m)) { prop_assert!(inside(a, b)); }
            // and the enclosure is tight: a few ulps of the energy's scale, the sum of its parts'
            // sizes (the kinetic and the potential energies can cancel to near zero)
            let size = |r: Outward| r.abs().bounds().1;
            let each = m.terms.iter().map(|t| size(iv.potential(&Model { terms: vec![t.clone()], ..m.clone() })));
            let scale = 1.0 + size(iv.kinetic()) + each.sum::<f64>();
            let (lo, hi) = iv.energy(&m).bounds();
            prop_assert!(hi - lo <= 1e-12 * scale, "width {:e} at scale {scale:e}", hi - lo);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// A fluid's energy Σ m u(ρ) and its viscous heat rate, each enclosed: the interval holds
        /// the 256-bit value and is a few ulps wide (in a box periodic along z as well).
        #[test]
        fn a_fluid_is_enclosed(x in prop::collection::vec(prop::array::uniform3(0.0f64..0.6), 12),
                               v in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 12),
                               rho0 in 0.2f64..3.0, periodic in any::<bool>()) {
            let body = Body { mass: 0.01, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
            let m = Model {
                units: UnitSystem::Reduced,
                cell: periodic.then_some(crate::model::Cell { size: [1.0; 3], periodic: [false, false, true] }),
                bodies: vec![body; 12],
                terms: vec![TermInstance { kind: Kind::Sph, sites: vec![], params: vec![0.2, rho0, 3.0, 7.0, 0.5, 1.0] }],
                constraints: vec![],
                thermostat: None,
                floor: None,
                pins: vec![],
            };
            let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
            let (iv, hp) = (Lifted::new(&m, &s, &Outward::NAN), Lifted::new(&m, &s, &Float::new(256)));
            for (i, f) in [(iv.potential(&m), hp.potential(&m)), (iv.dissipated_power(&m), hp.dissipated_power(&m))] {
                let (lo, hi) = i.bounds();
                prop_assert!(Float::with_val(256, lo) <= f && f <= Float::with_val(256, hi), "{lo} {hi} {f}");
                prop_assert!(hi - lo <= 1e-12 * (1.0 + hi.abs()), "width {:e}", hi - lo);
            }
            // and the f64 instance is the kernel's reference
            let plain = Lifted::new(&m, &s, &0.0f64).potential(&m);
            let (lo, hi) = iv.potential(&m).bounds();
            prop_assert!(lo <= plain && plain <= hi);
        }
    }

    #[test]
    fn energy_of_stretched_spring() {
        let m = model(2.0, 2.0, 0.0, 0.0);
        let x = [[-1.35, 0.0, 0.0], [1.35, 0.0, 0.0], [0.0, 100.0, 0.0]];
        let v = [[0.0; 3]; 3];
        let s = Snapshot { step: 0, t: 0.0, x: &x, v: &v, chain: &[], spin: &[] };
        let l = Lifted::new(&Model { terms: m.terms[..1].to_vec(), ..m.clone() }, &s, &0.0f64);
        assert!((l.potential(&Model { terms: m.terms[..1].to_vec(), ..m }) - 0.49).abs() < 1e-15);
    }
}
