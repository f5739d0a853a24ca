//! One scene through the table: for each symmetry, whether every term instance respects it (so
//! its charge is conserved), or which terms break it.

use crate::table::{parameter_names, Part, Symmetry, Table, Verdict};
use lagra_checker::claims::{Claim, ClaimKind};
use lagra_checker::model::{Model, TermInstance};
use lagra_checker::terms::Kind;

/// What Noether's theorem says of one symmetry in one scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Every term respects it: its charge is conserved. `shares` are the kinds whose own share
    /// enters the charge (a magnetic field's q B × x in the momentum).
    Conserved { shares: Vec<Kind> },
    /// The Lagrangian respects it but these terms dissipate: for time, energy is a balance
    /// H + Q = H₀ (the checker's energy claim is one).
    Balance { by: Vec<Kind> },
    /// These break it: term names, or "the periodic box".
    Broken { by: Vec<String> },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Law {
    pub symmetry: Symmetry,
    pub status: Status,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    pub laws: Vec<Law>,
}

/// Whether one instance respects the symmetry in one part; a kind missing from the table
/// counts as breaking everything.
fn respects(table: &Table, t: &TermInstance, part: Part, s: Symmetry) -> bool {
    let Some(entry) = table.of(t.kind) else { return false };
    match entry.verdict(part, s) {
        Verdict::Invariant | Verdict::UpToBoundary { .. } => true,
        Verdict::WhenZero { any_of } => {
            let names = parameter_names(t.kind);
            let zero = |p: &String| names.iter().position(|n| n == p).is_some_and(|i| t.params[i] == 0.0);
            any_of.iter().any(|set| set.iter().all(zero))
        }
        Verdict::Broken => false,
    }
}

/// Each kind once, in the vocabulary's order.
fn kinds_of<'a>(terms: impl Iterator<Item = &'a TermInstance>) -> Vec<Kind> {
    let present: Vec<Kind> = terms.map(|t| t.kind).collect();
    Kind::ALL.iter().copied().filter(|k| present.contains(k)).collect()
}

/// The scene's laws, from the table (normally `Table::derived()`).
pub fn analyse(model: &Model, table: &Table) -> Analysis {
    let laws = Symmetry::ALL
        .into_iter()
        .map(|s| {
            let lagrangian = |t: &&TermInstance| !respects(table, t, Part::Lagrangian, s);
            let dissipation = |t: &&TermInstance| !respects(table, t, Part::Dissipation, s);
            // Minimum image is not rotation invariant: a periodic axis other than the rotation's
            // breaks it.
            let by_box = match (model.cell, s.axis()) {
                (Some(cell), Some(a))
                    if matches!(s, Symmetry::RotationX | Symmetry::RotationY | Symmetry::RotationZ) =>
                {
                    (0..3).any(|b| b != a && cell.periodic[b])
                }
                _ => false,
            };
            let status = if s == Symmetry::Time
                && !model.terms.iter().any(|t| lagrangian(&t))
                && contacts_break(model, s).is_empty()
            {
                let by = kinds_of(model.terms.iter().filter(dissipation));
                if by.is_empty() {
                    Status::Conserved { shares: vec![] }
                } else {
                    Status::Balance { by }
                }
            } else {
                let mut by: Vec<String> = kinds_of(model.terms.iter().filter(|t| lagrangian(t) || dissipation(t)))
                    .iter()
                    .map(|k| k.name().to_string())
                    .collect();
                if by_box {
                    by.push("the periodic box".into());
                }
                by.extend(contacts_break(model, s));
                if by.is_empty() {
                    let sharing = |t: &&TermInstance| table.of(t.kind).is_some_and(|e| e.charge_share.contains_key(&s));
                    Status::Conserved { shares: kinds_of(model.terms.iter().filter(sharing)) }
                } else {
                    Status::Broken { by }
                }
            };
            Law { symmetry: s, status }
        })
        .collect();
    Analysis { laws }
}

/// What the contacts, which are no terms, break: a rigid floor (normal y) every symmetry that
/// moves its plane, and with friction the others along it, since it pushes against the bodies'
/// sliding; and any contact the energy, since it is inelastic. Contacts between solids
/// alone push equally and oppositely at one point, so they keep both momenta, and so do joints
/// between solids; a joint to the world holds its points in place, breaking every translation
/// and boost, and every rotation about an axis (through the origin) that does not pass through
/// all of them.
fn contacts_break(model: &Model, s: Symmetry) -> Vec<String> {
    use Symmetry::*;
    // (walked only where asked, and no further than needed: called once a symmetry, over bodies
    // that may number millions)
    let solids = || model.bodies.iter().filter_map(|b| b.solid.map(|s| s.friction));
    let mut by = vec![];
    if let Some(floor) = model.floor {
        let gripped = floor.friction.map_or_else(|| solids().any(|mu| mu > 0.0), |mu| mu > 0.0);
        if matches!(s, TranslationY | RotationX | RotationZ | BoostY) {
            by.push("the rigid floor".to_string());
        } else if gripped && matches!(s, TranslationX | TranslationZ | RotationY | BoostX | BoostZ) {
            by.push("the rigid floor's friction".to_string());
        }
    }
    let anchored: Vec<[f64; 3]> = model.pins.iter().filter(|p| p.a.is_none()).map(|p| p.on_a).collect();
    let on_axis = |k: usize| anchored.iter().all(|p| (0..3).all(|c| c == k || p[c] == 0.0));
    let held = match s {
        RotationX => on_axis(0),
        RotationY => on_axis(1),
        RotationZ => on_axis(2),
        Time => true,
        _ => anchored.is_empty(),
    };
    if !held {
        by.push("the joints to the world".to_string());
    }
    if s == Time && (model.floor.is_some() || solids().nth(1).is_some()) {
        by.push("the contacts (inelastic)".to_string());
    }
    by
}

/// The claim kind a symmetry's charge is certified by, if the checker has one.
fn claim_kind(s: Symmetry) -> Option<ClaimKind> {
    use Symmetry::*;
    match s {
        TranslationX | TranslationY | TranslationZ => Some(ClaimKind::MomentumConservation),
        RotationX | RotationY | RotationZ => Some(ClaimKind::AngularMomentumConservation),
        Time => Some(ClaimKind::EnergyConservation),
        // The centre of mass moving uniformly follows from momentum; no claim of its own.
        BoostX | BoostY | BoostZ => None,
    }
}

impl Analysis {
    pub fn law(&self, s: Symmetry) -> &Law {
        self.laws.iter().find(|l| l.symmetry == s).expect("every symmetry is analysed")
    }

    /// The symmetries a claim speaks of: energy's is time, a momentum claim's the translations
    /// along its axes, an angular momentum claim's the rotations about them.
    fn symmetries_of(c: &Claim) -> Vec<Symmetry> {
        let axes = c.axes.unwrap_or([true; 3]);
        Symmetry::ALL
            .into_iter()
            .filter(|s| claim_kind(*s) == Some(c.kind) && s.axis().is_none_or(|a| axes[a]))
            .collect()
    }

    /// The conservation claims Noether's theorem supports and `declared` does not already make:
    /// energy (a balance where terms dissipate) with the relative `tol`, and the momenta along
    /// the axes whose symmetry holds. A charge with a term's share (a magnetic field's) is not
    /// conserved to round-off by the integrator, so it is held to `share_tol(symmetry kind)`;
    /// the others get the checker's round-off budget.
    pub fn claims(&self, tol: f64, every: u64, declared: &[Claim], share_tol: impl Fn(ClaimKind) -> f64) -> Vec<Claim> {
        let mut out = vec![];
        for kind in
            [ClaimKind::EnergyConservation, ClaimKind::MomentumConservation, ClaimKind::AngularMomentumConservation]
        {
            if declared.iter().any(|c| c.kind == kind) {
                continue;
            }
            let held: Vec<&Law> = self
                .laws
                .iter()
                .filter(|l| claim_kind(l.symmetry) == Some(kind) && !matches!(l.status, Status::Broken { .. }))
                .collect();
            if held.is_empty() {
                continue;
            }
            let mut claim = Claim::new(kind, None, every);
            if kind == ClaimKind::EnergyConservation {
                claim.tol = Some(tol);
            } else {
                let mut axes = [false; 3];
                held.iter().for_each(|l| axes[l.symmetry.axis().expect("an axis")] = true);
                claim.axes = (axes != [true; 3]).then_some(axes);
                if held.iter().any(|l| matches!(&l.status, Status::Conserved { shares } if !shares.is_empty())) {
                    claim.tol = Some(share_tol(kind));
                }
            }
            out.push(claim);
        }
        out
    }

    /// Why a declared claim cannot hold, if the symmetries say so: the first broken symmetry it
    /// speaks of and what breaks it (`momentum_y: broken by ContactFloor, UniformAcceleration`).
    pub fn contradiction(&self, c: &Claim) -> Option<String> {
        let broken: Vec<String> = Self::symmetries_of(c)
            .into_iter()
            .filter_map(|s| match &self.law(s).status {
                Status::Broken { by } => Some(format!("{}: broken by {}", s.charge(), by.join(", "))),
                _ => None,
            })
            .collect();
        (!broken.is_empty()).then(|| broken.join("; "))
    }

    /// Whether the symmetries support a declared conservation claim: then a certified FAIL of it
    /// points at the integrator or a force, not at the physics.
    pub fn supports(&self, c: &Claim) -> bool {
        c.kind.is_conservation() && self.contradiction(c).is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, Cell, UnitSystem};

    fn model(terms: Vec<TermInstance>, cell: Option<Cell>) -> Model {
        let bodies = vec![Body { mass: 1.0, charge: 1.0, colour: [0.0; 2], moments: None, solid: None }; 3];
        Model {
            units: UnitSystem::Reduced,
            cell,
            bodies,
            terms,
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        }
    }

    fn term(kind: Kind, params: &[f64]) -> TermInstance {
        let sites = if matches!(kind.spec().shape, lagra_checker::terms::Shape::Bond(_)) { vec![0, 1] } else { vec![] };
        TermInstance { kind, sites, params: params.to_vec() }
    }

    fn broken_by(a: &Analysis, s: Symmetry) -> Vec<String> {
        match &a.law(s).status {
            Status::Broken { by } => by.clone(),
            _ => vec![],
        }
    }

    #[test]
    fn a_floor_and_gravity_break_the_vertical_and_keep_the_rest() {
        let m = model(
            vec![
                term(Kind::UniformAcceleration, &[0.0, -9.8, 0.0]),
                term(Kind::ContactFloor, &[0.0, 1e4, 5.0, 0.5, 0.05]),
            ],
            None,
        );
        let a = analyse(&m, Table::derived());
        assert_eq!(broken_by(&a, Symmetry::TranslationY), ["UniformAcceleration", "ContactFloor"]);
        // the floor's friction breaks the horizontal momenta too (it pushes against v_t)
        assert_eq!(broken_by(&a, Symmetry::TranslationX), ["ContactFloor"]);
        assert_eq!(a.law(Symmetry::Time).status, Status::Balance { by: vec![Kind::ContactFloor] });
        let c = Claim { axes: Some([false, true, false]), ..Claim::new(ClaimKind::MomentumConservation, None, 1) };
        assert_eq!(a.contradiction(&c).unwrap(), "momentum_y: broken by UniformAcceleration, ContactFloor");
    }

    /// Contacts are no terms, but they break what they break: a rigid floor the vertical, its
    /// friction the horizontal; contacts between solids only the energy (they are inelastic).
    #[test]
    fn contacts_break_what_the_floor_and_its_friction_move() {
        use lagra_checker::model::{Extent, Floor, Solid};
        let solid = |friction| Body {
            moments: Some([1.0; 3]),
            solid: Some(Solid { extent: Extent::Ball(0.5), friction }),
            ..model(vec![], None).bodies[0].clone()
        };
        let solids = |friction, floor| Model { bodies: vec![solid(friction); 2], floor, ..model(vec![], None) };
        let free = analyse(&solids(0.5, None), Table::derived());
        assert!(Symmetry::ALL.iter().filter(|&&s| s != Symmetry::Time).all(|&s| broken_by(&free, s).is_empty()));
        assert_eq!(broken_by(&free, Symmetry::Time), ["the contacts (inelastic)"]);
        let floored = analyse(&solids(0.5, Some(Floor { y: 0.0, friction: None })), Table::derived());
        assert_eq!(broken_by(&floored, Symmetry::TranslationY), ["the rigid floor"]);
        assert_eq!(broken_by(&floored, Symmetry::TranslationX), ["the rigid floor's friction"]);
        let slippery = analyse(&solids(0.5, Some(Floor { y: 0.0, friction: Some(0.0) })), Table::derived());
        assert!(
            broken_by(&slippery, Symmetry::TranslationX).is_empty()
                && broken_by(&slippery, Symmetry::RotationY).is_empty()
        );
        assert_eq!(broken_by(&slippery, Symmetry::RotationX), ["the rigid floor"]);
        // a ball joint to the world on the y axis keeps only the turn about y (and the energy);
        // a joint between the two solids keeps everything the free pair keeps
        use lagra_checker::model::Pin;
        let pin = |a, on_a| Pin { a, b: 1, on_a, on_b: [0.0, 0.5, 0.0] };
        let hung = Model { pins: vec![pin(None, [0.0, 3.0, 0.0])], ..solids(0.5, None) };
        let a = analyse(&hung, Table::derived());
        let world = ["the joints to the world"];
        assert_eq!(broken_by(&a, Symmetry::TranslationX), world);
        assert_eq!(broken_by(&a, Symmetry::BoostZ), world);
        assert_eq!(broken_by(&a, Symmetry::RotationX), world);
        assert!(broken_by(&a, Symmetry::RotationY).is_empty());
        let off_axis = Model { pins: vec![pin(None, [1.0, 3.0, 0.0])], ..solids(0.5, None) };
        assert_eq!(broken_by(&analyse(&off_axis, Table::derived()), Symmetry::RotationY), world);
        let linked = analyse(&Model { pins: vec![pin(Some(0), [0.0; 3])], ..solids(0.5, None) }, Table::derived());
        assert!(Symmetry::ALL.iter().filter(|&&s| s != Symmetry::Time).all(|&s| broken_by(&linked, s).is_empty()));
    }

    #[test]
    fn gravity_alone_keeps_the_horizontal_momenta_and_energy() {
        let a = analyse(&model(vec![term(Kind::UniformAcceleration, &[0.0, -9.8, 0.0])], None), Table::derived());
        assert_eq!(broken_by(&a, Symmetry::TranslationY), ["UniformAcceleration"]);
        assert!(broken_by(&a, Symmetry::TranslationX).is_empty() && broken_by(&a, Symmetry::TranslationZ).is_empty());
        assert!(broken_by(&a, Symmetry::RotationY).is_empty(), "a rotation about g keeps g");
        assert_eq!(a.law(Symmetry::Time).status, Status::Conserved { shares: vec![] });
        let claims = a.claims(1e-4, 1, &[], |_| unreachable!());
        assert_eq!(claims.len(), 3);
        assert_eq!(claims[1].axes, Some([true, false, true]));
        assert_eq!(claims[2].axes, Some([false, true, false]));
    }

    #[test]
    fn a_periodic_box_breaks_rotations_but_not_translations() {
        let cell = Cell { size: [10.0; 3], periodic: [true, true, false] };
        let a = analyse(&model(vec![term(Kind::LennardJonesShifted, &[1.0, 1.0, 2.5])], Some(cell)), Table::derived());
        assert!(broken_by(&a, Symmetry::TranslationX).is_empty());
        assert_eq!(broken_by(&a, Symmetry::RotationZ), ["the periodic box"]);
        assert_eq!(broken_by(&a, Symmetry::RotationX), ["the periodic box"]);
    }

    #[test]
    fn a_declared_claim_is_not_generated_again_and_a_bond_is_free_of_contradiction() {
        let a = analyse(&model(vec![term(Kind::HarmonicBond, &[2.0, 1.0, 0.1])], None), Table::derived());
        assert_eq!(a.law(Symmetry::Time).status, Status::Balance { by: vec![Kind::HarmonicBond] });
        let declared = [Claim::new(ClaimKind::EnergyConservation, Some(1e-5), 1)];
        let claims = a.claims(1e-4, 1, &declared, |_| unreachable!());
        assert_eq!(
            claims.iter().map(|c| c.kind).collect::<Vec<_>>(),
            [ClaimKind::MomentumConservation, ClaimKind::AngularMomentumConservation]
        );
        assert!(claims.iter().all(|c| c.axes.is_none() && a.supports(c)));
    }

    #[test]
    fn a_magnetic_field_shares_in_the_momentum_it_keeps() {
        let a = analyse(&model(vec![term(Kind::MagneticField, &[0.0, 0.0, 2.0])], None), Table::derived());
        for s in [Symmetry::TranslationX, Symmetry::TranslationY, Symmetry::RotationZ] {
            assert_eq!(a.law(s).status, Status::Conserved { shares: vec![Kind::MagneticField] }, "{}", s.name());
        }
        assert_eq!(broken_by(&a, Symmetry::RotationX), ["MagneticField"]);
    }
}
