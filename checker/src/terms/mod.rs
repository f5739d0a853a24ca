//! The closed vocabulary of interaction terms. Each term is one file holding its [`Spec`] (name,
//! source keyword, shape, parameter dimensions) and its one [`Definition`] of the potential
//! (and, for dissipative terms, of the Rayleigh dissipation function), generic over [`Real`].
//! Adding a term is one file and one line in `vocabulary!` below.

use crate::real::{Real, Vec3};
use crate::units::{Dim, Dimension};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// What a term sees of one body: position, velocity, mass and charge.
#[derive(Clone, Debug)]
pub struct Site<R> {
    pub x: Vec3<R>,
    pub v: Vec3<R>,
    pub m: R,
    pub q: R,
    /// Colour charge (a weight of SU(3)), zero for colourless bodies.
    pub colour: [R; 2],
}

/// Which fields of a site besides its position a potential reads (`Kind::reads`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reads {
    pub v: bool,
    pub m: bool,
    pub q: bool,
    pub colour: bool,
}

/// Which bodies a term acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Listed bodies, written `bond KEYWORD [i, j, ...] { .. }`; the number is the arity.
    Bond(usize),
    /// Every pair of bodies, written `interaction KEYWORD { .. }`.
    Pairwise,
    /// Every body on its own, written `KEYWORD { .. }`.
    External,
    /// Every body through its density, a sum over the bodies within reach (`Definition::density`),
    /// written `KEYWORD { .. }` like an external term: the energy Σₐ `internal`(a, ρₐ) is not a
    /// sum over pairs. `potential` is then a body's energy with one neighbour (`fluid_pair`): the
    /// same formula, for the dimensions, the symmetries and the Lean export.
    Density,
}

impl Shape {
    pub fn arity(self) -> usize {
        match self {
            Shape::Bond(n) => n,
            Shape::Pairwise | Shape::Density => 2,
            Shape::External => 1,
        }
    }
}

/// One parameter: its name in the source, its dimension, its length (1 or 3), its default and
/// whether it must be positive (a smoothing length, a density: the compiler refuses others, and
/// so does a certificate's model).
#[derive(Clone, Copy, Debug)]
pub struct Param {
    pub name: &'static str,
    pub dim: Dim,
    pub len: usize,
    pub default: Option<f64>,
    pub positive: bool,
}

impl Param {
    pub const fn scalar(name: &'static str, dim: Dim) -> Param {
        Param { name, dim, len: 1, default: None, positive: false }
    }
    pub const fn vector(name: &'static str, dim: Dim) -> Param {
        Param { name, dim, len: 3, default: None, positive: false }
    }
    pub const fn or(self, default: f64) -> Param {
        Param { default: Some(default), ..self }
    }
    pub const fn positive(self) -> Param {
        Param { positive: true, ..self }
    }
}

/// A choice written in a term's block that selects among the terms of one keyword (`sph {
/// kernel: cubic_spline }`): the field, and the value that selects this term. A block without
/// the field gets the first such term of `vocabulary!`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    pub field: &'static str,
    pub value: &'static str,
}

#[derive(Debug)]
pub struct Spec {
    /// The canonical name, used in the graph, the certificate and messages (`HarmonicBond`).
    pub name: &'static str,
    /// The word that selects the term in a `.lagra` file (`harmonic`).
    pub keyword: &'static str,
    pub shape: Shape,
    pub params: &'static [Param],
}

impl Spec {
    /// Number of reals in the flattened parameter list.
    pub fn width(&self) -> usize {
        self.params.iter().map(|p| p.len).sum()
    }
}

/// One term's physics, written once.
pub trait Definition {
    const SPEC: Spec;
    /// What selects this term among those of its keyword, if others share it.
    const VARIANT: Option<Variant> = None;
    /// Potential energy of the sites `s` (in the order the shape gives) with parameters `p`
    /// (flattened in the order of `SPEC.params`).
    fn potential<R: Real>(p: &[R], s: &[&Site<R>]) -> R;
    /// Values of the parameters alone that `potential` reads after them (`p[width..]`, through
    /// `constant`): worked out once per instance by `Lifted` rather than once per pair, and by
    /// the definition itself, with the same code, when a caller passes the bare parameters.
    fn constants<R: Real>(_p: &[R]) -> Vec<R> {
        vec![]
    }
    /// Rayleigh dissipation function F: the term's force on a velocity is −∂F/∂v.
    /// `None` for a conservative term.
    fn rayleigh<R: Real>(_p: &[R], _s: &[&Site<R>]) -> Option<R> {
        None
    }
    /// The rate at which the term removes energy, v·∂F/∂v: 2F for a quadratic F (the default).
    fn power<R: Real>(p: &[R], s: &[&Site<R>]) -> Option<R> {
        Self::rayleigh(p, s).map(|f| f.lift(2.0) * f)
    }
    /// The part of the Lagrangian linear in the velocities (a magnetic q A·v): it exerts the
    /// force ∂L/∂x − d/dt ∂L/∂v and does no work, so it adds nothing to the energy H.
    fn gyroscopic<R: Real>(_p: &[R], _s: &[&Site<R>]) -> Option<R> {
        None
    }
    /// The term's share of the conserved momentum and angular momentum, beyond Σ m v and
    /// Σ m x × v: where L has a part linear in the velocities, Noether's charges of translations
    /// and rotations take it in (a magnetic field's q B × x). `lagra-noether-derive` derives it
    /// from `gyroscopic`; a test holds the two equal.
    fn charge_share<R: Real>(_p: &[R], _s: &[&Site<R>]) -> Option<[Vec3<R>; 2]> {
        None
    }
    /// A `Shape::Density` term's share of body a's density that body b gives (m_b W(|x_a − x_b|)
    /// for SPH); a's own share is `own_density`. `None` for every other shape.
    fn density<R: Real>(_p: &[R], _a: &Site<R>, _b: &Site<R>) -> Option<R> {
        None
    }
    /// A's own share of its density: `density(p, a, a)`, unless the definition gives it in
    /// closed form (SPH's mₐW(0), which the pair form reaches only through √0: a tree of zeros
    /// that the symbolic derivation differentiates to 0⁻¹ and Lean must simplify away).
    fn own_density<R: Real>(p: &[R], a: &Site<R>) -> Option<R> {
        Self::density(p, a, a)
    }
    /// A `Shape::Density` term's energy of body a at density ρ (mₐ u(ρ) for SPH).
    fn internal<R: Real>(_p: &[R], _a: &Site<R>, _rho: R) -> Option<R> {
        None
    }
    /// Whether the definition means something with parameters `p` beyond their being finite and
    /// the `positive` ones positive: `Err((parameter, why))` if not.
    fn accepts(_p: &[f64]) -> Result<(), (&'static str, &'static str)> {
        Ok(())
    }
    /// Whether an instance with parameters `p` can remove energy at all (a bond with zero
    /// damping cannot): the energy claim is a balance exactly when some instance can.
    fn dissipates(_p: &[f64]) -> bool {
        false
    }
    /// The distance beyond which the term vanishes: its `cutoff` parameter if it has one, else
    /// ∞. A number on every path, not an `Option`: the compiler may compute with a value before
    /// it tests which path it is on, and an empty `Option`'s payload is whatever was in the
    /// register — a subnormal there raised DE/UE (tests/end_to_end/subnormal.rs).
    fn reach(p: &[f64]) -> f64 {
        match Self::SPEC.params.iter().position(|q| q.name == "cutoff") {
            Some(at) => p[Self::SPEC.params[..at].iter().map(|q| q.len).sum::<usize>()],
            None => f64::INFINITY,
        }
    }
}

/// A density term's energy of body `s[0]` with `s[1]` its one neighbour: `internal` at the
/// density the two give it (the `potential` of a `Shape::Density` term).
fn fluid_pair<D: Definition, R: Real>(p: &[R], s: &[&Site<R>]) -> R {
    let rho = D::own_density(p, s[0]).and_then(|own| Some(own + D::density(p, s[0], s[1])?));
    rho.and_then(|rho| D::internal(p, s[0], rho)).expect("a density term defines `density` and `internal`")
}

/// Constant `k` of `D::constants`: as given after the parameters in `p`, or worked out now.
fn constant<D: Definition, R: Real>(p: &[R], k: usize) -> R {
    let width = D::SPEC.width();
    p.get(width + k).cloned().unwrap_or_else(|| D::constants(&p[..width]).swap_remove(k))
}

macro_rules! vocabulary {
    ($($kind:ident => $module:ident),* $(,)?) => {
        $(pub mod $module; pub use $module::$kind;)*

        /// Every term kind there is.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        pub enum Kind { $($kind),* }

        impl Kind {
            pub const ALL: &'static [Kind] = &[$(Kind::$kind),*];
            pub fn spec(self) -> &'static Spec {
                match self { $(Kind::$kind => &<$kind as Definition>::SPEC),* }
            }
            pub fn variant(self) -> Option<Variant> {
                match self { $(Kind::$kind => <$kind as Definition>::VARIANT),* }
            }
            pub fn potential<R: Real>(self, p: &[R], s: &[&Site<R>]) -> R {
                match self { $(Kind::$kind => $kind::potential(p, s)),* }
            }
            pub fn constants<R: Real>(self, p: &[R]) -> Vec<R> {
                match self { $(Kind::$kind => $kind::constants(p)),* }
            }
            pub fn rayleigh<R: Real>(self, p: &[R], s: &[&Site<R>]) -> Option<R> {
                match self { $(Kind::$kind => $kind::rayleigh(p, s)),* }
            }
            pub fn power<R: Real>(self, p: &[R], s: &[&Site<R>]) -> Option<R> {
                match self { $(Kind::$kind => $kind::power(p, s)),* }
            }
            pub fn gyroscopic<R: Real>(self, p: &[R], s: &[&Site<R>]) -> Option<R> {
                match self { $(Kind::$kind => $kind::gyroscopic(p, s)),* }
            }
            pub fn charge_share<R: Real>(self, p: &[R], s: &[&Site<R>]) -> Option<[Vec3<R>; 2]> {
                match self { $(Kind::$kind => $kind::charge_share(p, s)),* }
            }
            pub fn density<R: Real>(self, p: &[R], a: &Site<R>, b: &Site<R>) -> Option<R> {
                match self { $(Kind::$kind => $kind::density(p, a, b)),* }
            }
            pub fn own_density<R: Real>(self, p: &[R], a: &Site<R>) -> Option<R> {
                match self { $(Kind::$kind => $kind::own_density(p, a)),* }
            }
            pub fn internal<R: Real>(self, p: &[R], a: &Site<R>, rho: R) -> Option<R> {
                match self { $(Kind::$kind => $kind::internal(p, a, rho)),* }
            }
            pub fn accepts(self, p: &[f64]) -> Result<(), (&'static str, &'static str)> {
                match self { $(Kind::$kind => $kind::accepts(p)),* }
            }
            pub fn dissipates(self, p: &[f64]) -> bool {
                match self { $(Kind::$kind => $kind::dissipates(p)),* }
            }
            pub fn reach(self, p: &[f64]) -> f64 {
                match self { $(Kind::$kind => $kind::reach(p)),* }
            }
        }
    };
}

vocabulary! {
    HarmonicBond => harmonic_bond,
    MorseBond => morse_bond,
    FeneBond => fene_bond,
    HarmonicAngle => harmonic_angle,
    Dihedral => dihedral,
    HydrogenBond => hydrogen_bond,
    Gravity => gravity,
    LennardJones => lennard_jones,
    LennardJonesShifted => lennard_jones_shifted,
    LennardJonesForceShifted => lennard_jones_force_shifted,
    Wca => wca,
    Coulomb => coulomb,
    CoulombReactionField => coulomb_reaction_field,
    Yukawa => yukawa,
    NuclearYukawa => nuclear_yukawa,
    QcdCoulomb => qcd_coulomb,
    UniformAcceleration => uniform_acceleration,
    GravityWell => gravity_well,
    HarmonicTrap => harmonic_trap,
    ElectricField => electric_field,
    Drag => drag,
    ContactFloor => contact_floor,
    MagneticField => magnetic_field,
    Wall => wall,
    Sph => sph,
    SphCubicSpline => sph_cubic_spline,
}

pub mod smoothing;

impl Kind {
    pub fn name(self) -> &'static str {
        self.spec().name
    }

    /// The definition evaluated over dimensions: parameters carry their declared dimension,
    /// sites carry L, L·T⁻¹, M, Q. Returns the potential and, where the term has them, the
    /// dissipation function, the dissipated power, the velocity-dependent Lagrangian and the
    /// shares of the momentum and angular momentum.
    fn dimensions(self) -> [Option<Dimension>; 6] {
        let spec = self.spec();
        let p = Kind::parameter_dimensions(spec);
        let site = Kind::site_dimensions();
        let s = vec![&site; spec.shape.arity()];
        // a vector is homogeneous when its components are alike: their sum says so
        let sum = |v: Vec3<Dimension>| {
            let [a, b, c] = v;
            a + b + c
        };
        let [momentum, angular] =
            self.charge_share(&p, &s).map(|[m, a]| [Some(sum(m)), Some(sum(a))]).unwrap_or([None, None]);
        [
            Some(self.potential(&p, &s)),
            self.rayleigh(&p, &s),
            self.power(&p, &s),
            self.gyroscopic(&p, &s),
            momentum,
            angular,
        ]
    }

    fn parameter_dimensions(spec: &Spec) -> Vec<Dimension> {
        spec.params.iter().flat_map(|p| std::iter::repeat_n(Dimension::of(p.dim), p.len)).collect()
    }

    fn site_dimensions() -> Site<Dimension> {
        Site {
            x: std::array::from_fn(|_| Dimension::of(Dim::LENGTH)),
            v: std::array::from_fn(|_| Dimension::of(Dim::VELOCITY)),
            m: Dimension::of(Dim::MASS),
            q: Dimension::of(Dim::CHARGE),
            colour: std::array::from_fn(|_| Dimension::of(Dim::NONE)),
        }
    }

    /// Which fields of its sites besides the positions the potential reads (worked out once per
    /// kind): a field is read when an error put in its place reaches the potential's dimension
    /// (every operation on dimensions passes an error on, and both branches of a cutoff are
    /// taken). The checker leaves the other fields unknown where it evaluates pairs in lanes.
    pub fn reads(self) -> Reads {
        static TABLE: OnceLock<Vec<Reads>> = OnceLock::new();
        let read = |k: Kind, poison: fn(&mut Site<Dimension>, Dimension)| {
            let mut site = Kind::site_dimensions();
            poison(&mut site, Dimension(Err("read".into())));
            k.potential(&Kind::parameter_dimensions(k.spec()), &vec![&site; k.spec().shape.arity()]).0.is_err()
        };
        TABLE.get_or_init(|| {
            Kind::ALL
                .iter()
                .map(|&k| Reads {
                    v: read(k, |s, e| s.v = [e.clone(), e.clone(), e]),
                    m: read(k, |s, e| s.m = e),
                    q: read(k, |s, e| s.q = e),
                    colour: read(k, |s, e| s.colour = [e.clone(), e]),
                })
                .collect()
        })[self as usize]
    }

    /// Whether the definition has a share of the momenta (worked out once per kind).
    pub fn has_charge_share(self) -> bool {
        static TABLE: OnceLock<Vec<bool>> = OnceLock::new();
        TABLE.get_or_init(|| Kind::ALL.iter().map(|k| k.dimensions()[4].is_some()).collect())[self as usize]
    }

    /// Whether the definition has a dissipation function (worked out once per kind).
    pub fn dissipative(self) -> bool {
        static TABLE: OnceLock<Vec<bool>> = OnceLock::new();
        TABLE.get_or_init(|| Kind::ALL.iter().map(|k| k.dimensions()[1].is_some()).collect())[self as usize]
    }

    /// Proves the definition homogeneous: its potential is an energy and its dissipation
    /// function (if any) a power, with no sum of unlike dimensions on the way.
    pub fn check_dimensions(self) -> Result<(), String> {
        let power = Dim::ENERGY / Dim::TIME;
        let wanted = [
            ("potential", Dim::ENERGY),
            ("dissipation function", power),
            ("dissipated power", power),
            ("velocity-dependent Lagrangian", Dim::ENERGY),
            ("share of the momentum", Dim([1, 1, -1, 0])),
            ("share of the angular momentum", Dim([1, 2, -1, 0])),
        ];
        for ((what, want), got) in wanted.into_iter().zip(self.dimensions()) {
            match got.map(|g| g.0) {
                None => {}
                Some(Ok(d)) if d == want => {}
                Some(Ok(d)) => return Err(format!("{}: {what} has dimension {d}, not {want}", self.name())),
                Some(Err(e)) => return Err(format!("{}: {what} is inhomogeneous ({e})", self.name())),
            }
        }
        Ok(())
    }

    /// The term selected by `keyword` among the terms whose shape satisfies `fits`, and among
    /// those by the value `chosen` of their variant's field (`None`: the first of them).
    pub fn lookup(keyword: &str, fits: impl Fn(Shape) -> bool, chosen: Option<&str>) -> Option<Kind> {
        Kind::ALL.iter().copied().find(|k| {
            k.spec().keyword == keyword
                && fits(k.spec().shape)
                && chosen.is_none_or(|c| k.variant().is_some_and(|v| v.value == c))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_keyword_is_unique_per_shape() {
        for a in Kind::ALL {
            for b in Kind::ALL {
                if a != b && a.spec().keyword == b.spec().keyword && a.spec().shape == b.spec().shape {
                    // one keyword, one shape: told apart by one field's values
                    let (Some(va), Some(vb)) = (a.variant(), b.variant()) else { panic!("{a:?} and {b:?} collide") };
                    assert!(va.field == vb.field && va.value != vb.value, "{a:?} and {b:?} collide");
                }
            }
        }
    }

    #[test]
    fn every_definition_is_homogeneous() {
        for k in Kind::ALL {
            assert_eq!(k.check_dimensions(), Ok(()));
        }
    }

    #[test]
    fn potentials_read_what_they_use() {
        let reading = |f: fn(Reads) -> bool| Kind::ALL.iter().copied().filter(|k| f(k.reads())).collect::<Vec<_>>();
        // drag and the magnetic field write their zero potential as m v² · 0, for its dimension
        assert_eq!(reading(|r| r.v), [Kind::Drag, Kind::MagneticField]);
        // (a fluid's density is a sum of masses)
        let massive = [
            Kind::Gravity,
            Kind::UniformAcceleration,
            Kind::GravityWell,
            Kind::Drag,
            Kind::MagneticField,
            Kind::Sph,
            Kind::SphCubicSpline,
        ];
        assert_eq!(reading(|r| r.m), massive);
        assert_eq!(reading(|r| r.q), [Kind::Coulomb, Kind::CoulombReactionField, Kind::Yukawa, Kind::ElectricField]);
        assert_eq!(reading(|r| r.colour), [Kind::QcdCoulomb]);
    }

    #[test]
    fn only_damped_bonds_drag_floors_and_viscous_fluids_dissipate() {
        let d: Vec<_> = Kind::ALL.iter().filter(|k| k.dissipative()).collect();
        assert_eq!(d, [&Kind::HarmonicBond, &Kind::Drag, &Kind::ContactFloor, &Kind::Sph, &Kind::SphCubicSpline]);
    }

    #[test]
    fn a_kernel_selects_among_the_fluids() {
        let fluid = |s: Shape| s == Shape::Density;
        assert_eq!(Kind::lookup("sph", fluid, None), Some(Kind::Sph));
        assert_eq!(Kind::lookup("sph", fluid, Some("wendland_c2")), Some(Kind::Sph));
        assert_eq!(Kind::lookup("sph", fluid, Some("cubic_spline")), Some(Kind::SphCubicSpline));
        assert_eq!(Kind::lookup("sph", fluid, Some("quintic")), None);
        assert_eq!(Kind::lookup("harmonic", |s| s == Shape::Bond(2), Some("cubic_spline")), None);
    }
}
