//! Fast, hand-derived forces. A term supplies one `eval` for one instance — of `Bonded` (listed
//! bodies), `Paired` (every pair, on the displacement) or `Field` (each body alone) — and
//! `groups` and `pairs` loop over the instances in flat arrays, monomorphized per term. They never call the
//! checker's generic definitions; tests hold the two together (forces = −∇V − ∂F/∂v to
//! round-off, energies equal).

mod clusters;
mod density_derivative;
pub mod derivative;
mod groups;
mod pairs;
#[cfg(target_arch = "x86_64")]
mod pipelined;

mod contact_floor;
mod coulomb;
mod coulomb_reaction_field;
mod dihedral;
mod drag;
mod electric_field;
mod fene_bond;
mod gravity;
mod gravity_well;
mod harmonic_angle;
mod harmonic_bond;
mod harmonic_trap;
mod hydrogen_bond;
mod lennard_jones;
mod magnetic_field;
mod morse_bond;
mod nuclear_yukawa;
mod qcd_coulomb;
mod sph;
mod uniform_acceleration;
mod wall;
mod wca;
mod yukawa;

#[cfg(test)]
pub(crate) mod dual;

use crate::lanes::{self, Lane};
use crate::state::State;
use crate::step::Stride;
use derivative::{Adjoint, Direction, Wanted};
use groups::{Bonds, Fields};
use lagra_checker::model::{Model, TermInstance};
use lagra_checker::terms::Kind;
use pairs::Pairs;
use std::fmt;

/// A configuration where a term's force is undefined (bodies at one point, a bond stretched past
/// its limit, ...): a clear error, never a NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct Singularity {
    pub term: &'static str,
    pub bodies: Vec<usize>,
    pub what: &'static str,
    /// The numbers where it happened (the bodies' separation, or their coordinates), when known.
    pub seen: Option<String>,
}

impl Singularity {
    /// A pair's, `d` apart. Cold and out of line, like every error built in a force loop.
    #[cold]
    #[inline(never)]
    fn pair(term: &'static str, i: usize, j: usize, what: &'static str, d: &[f64; 3]) -> Singularity {
        let r = length(d);
        Singularity {
            term,
            bodies: vec![i, j],
            what,
            seen: (r > 0.0).then(|| format!("the bodies {} apart", shown(r))),
        }
    }

    /// One with the coordinates of its bodies.
    #[cold]
    #[inline(never)]
    fn located(term: &'static str, bodies: &[usize], what: &'static str, x: &[[f64; 3]]) -> Singularity {
        Singularity { term, bodies: bodies.to_vec(), what, seen: groups::at(x, bodies) }
    }
}

impl fmt::Display for Singularity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b: Vec<String> = self.bodies.iter().map(|b| b.to_string()).collect();
        write!(f, "{}: bodies {}: {}", self.term, b.join(", "), self.what)?;
        self.seen.as_ref().map_or(Ok(()), |seen| write!(f, ", {seen}"))
    }
}

/// The state as a force sees it.
pub struct Frame<'a> {
    pub x: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    pub m: &'a [f64],
    pub q: &'a [f64],
    pub c: &'a [[f64; 2]],
}

/// The bodies' masses, charges and colours: a `Frame` without the state.
#[derive(Clone, Copy)]
pub struct Parts<'a> {
    pub m: &'a [f64],
    pub q: &'a [f64],
    pub c: &'a [[f64; 2]],
}

impl<'a> Parts<'a> {
    pub fn frame<'s>(&self, s: &'s State) -> Frame<'s>
    where
        'a: 's,
    {
        Frame { x: &s.x, v: &s.v, m: self.m, q: self.q, c: self.c }
    }
}

/// The solver's inner steps with `group` the whole force field, monomorphized around it: the
/// forces accumulated (onto the zeros the kick leaves), no energy.
#[inline]
fn stride_alone<G: Force>(group: &G, stride: Stride, parts: Parts) -> Result<(), Singularity> {
    stride.run(|s, f| group.accumulate(&parts.frame(s), f, false).map(|_| ()))
}

/// A homogeneous group of term instances.
pub trait Force: Send + Sync {
    /// The solver's inner steps with this group alone in the graph (`stride_alone`).
    fn stride(&self, stride: Stride, parts: Parts) -> Result<(), Singularity>;
    /// Adds the group's generalized forces to `f` and returns its potential energy, if
    /// `energy` (0 if not: a step no one looks at needs only the forces).
    fn accumulate(&self, s: &Frame, f: &mut [[f64; 3]], energy: bool) -> Result<f64, Singularity>;
    /// Whether the force depends on velocities (the solver then iterates its closing kick).
    /// Bodies `first..` are ghosts whose forces the caller drops: a group may leave out the
    /// pairs among them (`Neighbours::leave_out_pairs_among`).
    fn leave_out_pairs_among(&self, _first: usize) {}
    fn velocity_dependent(&self) -> bool;
    /// Whether the group's force only turns velocities, F = m ω × v (a magnetic field), so that
    /// a solver may rotate by ω instead of kicking (Boris).
    fn gyroscopic(&self) -> bool {
        false
    }
    /// Adds the group's ω of each body to `w` (nothing for a group that is not gyroscopic).
    fn gyration(&self, _s: &Frame, _w: &mut [[f64; 3]]) {}
    /// The group's virial W = Σ r·F over its interactions, each seen through the nearest image
    /// (a pair's −d·F on its first body; a bond's Σ_k (x_k − x_0)·F_k), so that W/3V is its
    /// share of the pressure. `None` for a group acting from outside (a field), which has no
    /// virial a periodic box would give meaning to.
    fn virial(&self, s: &Frame) -> Option<Result<f64, Singularity>>;
    /// The group's potential energy and virial with each interaction weighted by the share of
    /// its bodies below `owned` (a pair: 1, ½ or 0; a bond: the fraction of its sites): a rank's
    /// part of a system cut into domains, bodies `owned..` its ghosts, so that the ranks' parts
    /// add up to the whole's. `None` for a group the domains do not cut.
    fn owned_sums(&self, _s: &Frame, _owned: usize) -> Option<Result<[f64; 2], Singularity>> {
        None
    }
    /// Adds the derivative of the group's forces along `dir` to `df`, from the definitions.
    fn tangent(&self, s: &Frame, dir: &Direction, df: &mut [[f64; 3]]) -> Result<(), Singularity>;
    /// Adds the transpose of the forces' derivatives applied to `g` (one covector per body) to
    /// `out`: the adjoints of positions, velocities and of what `wanted` names.
    fn pullback(&self, s: &Frame, g: &[[f64; 3]], wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity>;
    /// Adds the gradient of the group's potential energy to `out` (positions, and what `wanted`
    /// names).
    fn potential_pullback(&self, s: &Frame, wanted: &Wanted, out: &mut Adjoint) -> Result<(), Singularity>;
    /// A copy of what the group keeps between evaluations (a neighbour list), so that a replay
    /// from a saved state (`restore`) gives the same bits as the run that saved it.
    fn save(&self) -> Option<Kept> {
        None
    }
    fn restore(&self, _kept: &Kept) {}
    /// The positions the group's kept list was last built at, if it keeps one that has been
    /// built: what a restart file holds so that the run resumed from it sums the same pairs in
    /// the same order (`build_at`).
    fn built_at(&self) -> Option<Vec<[f64; 3]>> {
        None
    }
    fn build_at(&self, _x: &[[f64; 3]]) {}
    /// How many times the group's kept list has been built.
    fn builds(&self) -> u64 {
        0
    }
    /// How the group visits its bodies, in a line (`lagra run --explain`).
    fn plan(&self) -> String;
}

/// What a group keeps between evaluations, saved (`Force::save`).
pub type Kept = Box<dyn std::any::Any + Send + Sync>;

/// The threads a group may use: the run's own pool, never rayon's global one (`None`: one
/// thread, no pool).
pub type Pool = Option<std::sync::Arc<rayon::ThreadPool>>;

/// Forces on N listed bodies, and the energy, of one instance with parameters `p`.
pub trait Bonded<const N: usize> {
    fn eval(p: &[f64], x: &[[f64; 3]; N], v: &[[f64; 3]; N]) -> Result<([[f64; 3]; N], f64), &'static str>;
    fn velocity_dependent(_p: &[f64]) -> bool {
        false
    }
}

/// A central pair term, given as its energy V and s = V′(r)/r at r², written once over a lane
/// type (`Lane`): for one pair (`f64`, `eval`) and for four (`F64x4`, the cluster kernel). The
/// force on body i is s·d, with d = x_j − x_i (the minimum image in a periodic box); body j feels
/// the opposite force.
pub trait Paired {
    /// One instance's constants, worked out once from its parameters, so that the pair loop does
    /// not redo per pair what depends on the parameters alone (the shifted LJ's V(r_c), 4ε, σ²).
    type Row: Copy + Send + Sync;
    fn row(p: &[f64]) -> Self::Row;
    /// Whether `radial` reads the masses and charges [mᵢ, mⱼ, qᵢ, qⱼ], resp. the product of the
    /// colour charges cᵢ·cⱼ: the loops load them only if so (zeros otherwise), and the
    /// dual-number tests, which give random masses, charges and colours, catch a wrong `false`.
    const BODIES: bool = false;
    const COLOUR: bool = false;
    /// r_c²: at and beyond it the pair contributes nothing (∞ for a term without a cutoff).
    fn reach2(_r: &Self::Row) -> f64 {
        f64::INFINITY
    }
    /// (V, s) at 0 < r² < r_c², lane by lane. Every impl is `#[inline(always)]`, as is `jet`'s:
    /// the AVX-512 kernels (`pipelined`) must inline it, or each of its eight-lane operations
    /// becomes a call (a gradient measured 7× slower with one `jet` left out).
    fn radial<L: Lane>(r: &Self::Row, r2: L, mq: [L; 4], colour: L) -> (L, L);
    /// One pair: the force on i and the energy; nothing beyond the cutoff, an error at r = 0.
    #[inline(always)]
    fn eval(r: &Self::Row, d: [f64; 3], mq: [f64; 4], colour: f64) -> Result<([f64; 3], f64), &'static str> {
        let r2 = lanes::norm2(&d);
        if r2 >= Self::reach2(r) {
            return Ok(([0.0; 3], 0.0));
        }
        if r2 == 0.0 {
            return Err(SAME_POINT);
        }
        let (v, s) = Self::radial(r, r2, mq, colour);
        Ok((d.map(|c| c * s), v))
    }
    /// The force's radial derivatives at r² inside the reach, hand-derived for the terms whose
    /// gradients run over millions of pairs (`Jet`; `p` the instance's parameters as written).
    /// `None`: the gradient code takes them from the definition (`derivatives::exact::radial`),
    /// to which a test holds every hand-derived one.
    /// Written once over a lane type, like `radial`: one pair in the scalar loops, four in the
    /// cluster pullbacks of the force and of the potential (`clusters::pullback`).
    #[inline(always)]
    fn jet<L: Lane>(_r: &Self::Row, _p: &[f64], _r2: L) -> Option<Jet<L>> {
        None
    }
}

/// s = V′(r)/r (the force on i is s·d), s_r = (V″ − s)/r² (so δs = s_r·(d·δd)), ∂s/∂p and
/// ∂V/∂p for each parameter p of the instance (at most three), for one pair (`f64`) or four
/// (`F64x4`). The force's pullback reads s, s_r and ∂s/∂p, the potential's s and ∂V/∂p (what
/// one does not read, inlined, is not computed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet<L = f64> {
    pub s: L,
    pub s_r: L,
    pub ds: [L; 3],
    pub dv: [L; 3],
}

/// The force on one body and its energy, from its position, velocity, mass and charge.
pub trait Field {
    fn eval(p: &[f64], x: &[f64; 3], v: &[f64; 3], m: f64, q: f64) -> Result<([f64; 3], f64), &'static str>;
    fn velocity_dependent(_p: &[f64]) -> bool {
        false
    }
    /// Whether the force only turns the velocity: `eval` is then m ω × v with ω from `gyration`
    /// (a test holds the two together).
    const GYROSCOPIC: bool = false;
    fn gyration(_p: &[f64], _x: &[f64; 3], _m: f64, _q: f64) -> [f64; 3] {
        [0.0; 3]
    }
}

/// The group for all instances of one kind (each with its place in the model): one line per
/// term kind.
pub fn group(kind: Kind, t: &[(usize, &TermInstance)], m: &Model, pool: &Pool) -> Box<dyn Force> {
    match kind {
        Kind::HarmonicBond => Bonds::<harmonic_bond::Fast, 2>::boxed(kind, t, m),
        Kind::MorseBond => Bonds::<morse_bond::Fast, 2>::boxed(kind, t, m),
        Kind::FeneBond => Bonds::<fene_bond::Fast, 2>::boxed(kind, t, m),
        Kind::HarmonicAngle => Bonds::<harmonic_angle::Fast, 3>::boxed(kind, t, m),
        Kind::Dihedral => Bonds::<dihedral::Fast, 4>::boxed(kind, t, m),
        Kind::HydrogenBond => Bonds::<hydrogen_bond::Fast, 3>::boxed(kind, t, m),
        Kind::Gravity => Pairs::<gravity::Fast>::boxed(kind, t, m, pool),
        Kind::LennardJones => Pairs::<lennard_jones::Plain>::boxed(kind, t, m, pool),
        Kind::LennardJonesShifted => Pairs::<lennard_jones::Shifted>::boxed(kind, t, m, pool),
        Kind::LennardJonesForceShifted => Pairs::<lennard_jones::ForceShifted>::boxed(kind, t, m, pool),
        Kind::Wca => Pairs::<wca::Fast>::boxed(kind, t, m, pool),
        Kind::Coulomb => Pairs::<coulomb::Fast>::boxed(kind, t, m, pool),
        Kind::CoulombReactionField => Pairs::<coulomb_reaction_field::Fast>::boxed(kind, t, m, pool),
        Kind::Yukawa => Pairs::<yukawa::Fast>::boxed(kind, t, m, pool),
        Kind::NuclearYukawa => Pairs::<nuclear_yukawa::Fast>::boxed(kind, t, m, pool),
        Kind::QcdCoulomb => Pairs::<qcd_coulomb::Fast>::boxed(kind, t, m, pool),
        Kind::UniformAcceleration => Fields::<uniform_acceleration::Fast>::boxed(kind, t),
        Kind::GravityWell => Fields::<gravity_well::Fast>::boxed(kind, t),
        Kind::HarmonicTrap => Fields::<harmonic_trap::Fast>::boxed(kind, t),
        Kind::ElectricField => Fields::<electric_field::Fast>::boxed(kind, t),
        Kind::Drag => Fields::<drag::Fast>::boxed(kind, t),
        Kind::ContactFloor => Fields::<contact_floor::Fast>::boxed(kind, t),
        Kind::MagneticField => Fields::<magnetic_field::Fast>::boxed(kind, t),
        Kind::Wall => Fields::<wall::Fast>::boxed(kind, t),
        Kind::Sph | Kind::SphCubicSpline => sph::Fluid::boxed(kind, t, m, pool),
    }
}

/// Why a pair term has no force at r = 0.
pub(crate) const SAME_POINT: &str = "at the same point, where the pair force is infinite";

/// A central potential V(r) on the displacement d (a bond's, a well's): `vr(r)` gives
/// (V, dV/dr); the force on the first body is dV/dr · d/r.
#[inline(always)]
pub(crate) fn central(d: [f64; 3], vr: impl Fn(f64) -> (f64, f64)) -> Result<([f64; 3], f64), &'static str> {
    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if r == 0.0 {
        return Err(SAME_POINT);
    }
    let (v, dv) = vr(r);
    let s = dv / r;
    Ok((d.map(|c| c * s), v))
}

pub(crate) fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// A number for a message: plain where that is short, else in exponent form (1e308, 2.5e-9).
pub(crate) fn shown(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// |d| without overflow or underflow in its squares, for messages about far-apart bodies.
pub(crate) fn length(d: &[f64; 3]) -> f64 {
    d[0].hypot(d[1]).hypot(d[2])
}

pub(crate) fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::{group, Frame};
    use lagra_checker::model::{Body, Model, TermInstance, UnitSystem};
    use lagra_checker::terms::{Kind, Shape};

    /// A group of one instance of `kind` (generic parameters) on n bodies, and n.
    fn one_of(kind: Kind) -> (Model, usize) {
        let spec = kind.spec();
        let params: Vec<f64> = spec
            .params
            .iter()
            .flat_map(|p| std::iter::repeat_n(if p.name == "R0" { 3.0 } else { 1.0 }, p.len))
            .collect();
        let n = spec.shape.arity().max(2);
        let bodies = (0..n)
            .map(|i| Body {
                mass: 1.0,
                charge: 1.0 - i as f64,
                colour: [0.5, 0.3 - 0.2 * i as f64],
                moments: None,
                solid: None,
            })
            .collect();
        let sites = if matches!(spec.shape, Shape::Bond(_)) { (0..n).collect() } else { vec![] };
        let terms = vec![TermInstance { kind, sites, params }];
        (
            Model {
                units: UnitSystem::Reduced,
                cell: None,
                bodies,
                terms,
                constraints: vec![],
                thermostat: None,
                floor: None,
                pins: vec![],
            },
            n,
        )
    }

    /// Every term at positions `x` (n of them): finite forces and energy, or a clear error.
    fn finite_or_error(kind: Kind, x: &[[f64; 3]]) -> Result<(), &'static str> {
        let (model, n) = one_of(kind);
        let g = group(kind, &[(0, &model.terms[0])], &model, &None);
        let v = vec![[0.2, -0.1, 0.05]; n];
        let (m, q, c) = (vec![1.0; n], vec![1.0; n], vec![[0.5, 0.3]; n]);
        let mut f = vec![[0.0; 3]; n];
        match g.accumulate(&Frame { x: &x[..n], v: &v, m: &m, q: &q, c: &c }, &mut f, true) {
            Ok(e) => {
                assert!(e.is_finite() && f.iter().flatten().all(|c| c.is_finite()), "{kind:?} at {x:?}: {e} {f:?}");
                Ok(())
            }
            Err(s) => Err(s.what),
        }
    }

    /// Every term, with bodies 0 and 1 brought to `r` apart (down to 0), gives finite forces and
    /// energy or a clear error: never a NaN or an infinity.
    #[test]
    fn near_singular_configurations_are_finite_or_a_clear_error() {
        for &kind in Kind::ALL {
            for r in [1e-300, 1e-160, 1e-100, 1e-20, 1e-8, 0.0] {
                // at the origin, so that a tiny separation is not lost to rounding
                let x = [[0.0; 3], [r, 0.0, 0.0], [1.1, 0.9, 0.4], [2.0, -0.5, 1.3]];
                if let Err(what) = finite_or_error(kind, &x) {
                    assert!(!what.is_empty(), "{kind:?}");
                }
            }
        }
    }

    /// Bodies on opposite sides of ±1e308, whose separation overflows binary64: finite forces,
    /// or an error that says so (not that they are too close).
    #[test]
    fn bodies_beyond_binary64_apart_are_said_to_be() {
        for &kind in Kind::ALL.iter().filter(|k| k.spec().shape != Shape::External) {
            let x = [[-1e308, 0.0, 0.0], [1e308, 0.0, 0.0], [1.1, 0.9, 0.4], [2.0, -0.5, 1.3]];
            if let Err(what) = finite_or_error(kind, &x) {
                assert!(what.contains("so far apart"), "{kind:?}: {what}");
            }
        }
    }
}
