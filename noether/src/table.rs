//! The derived table: for every term kind and every symmetry, whether the term's Lagrangian and
//! its dissipation function are invariant, and the term's share of the conserved charge.

use lagra_checker::terms::Kind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// A one-parameter group of motions of space and time, by its generator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Symmetry {
    /// δxᵢ = e (every body alike).
    TranslationX,
    TranslationY,
    TranslationZ,
    /// δxᵢ = e × xᵢ, δvᵢ = e × vᵢ: about the axis through the origin.
    RotationX,
    RotationY,
    RotationZ,
    /// t ↦ t + ε.
    Time,
    /// δxᵢ = t e, δvᵢ = e: a Galilean boost.
    BoostX,
    BoostY,
    BoostZ,
}

impl Symmetry {
    pub const ALL: [Symmetry; 10] = [
        Symmetry::TranslationX,
        Symmetry::TranslationY,
        Symmetry::TranslationZ,
        Symmetry::RotationX,
        Symmetry::RotationY,
        Symmetry::RotationZ,
        Symmetry::Time,
        Symmetry::BoostX,
        Symmetry::BoostY,
        Symmetry::BoostZ,
    ];

    /// The axis of a translation, rotation or boost.
    pub fn axis(self) -> Option<usize> {
        use Symmetry::*;
        match self {
            TranslationX | RotationX | BoostX => Some(0),
            TranslationY | RotationY | BoostY => Some(1),
            TranslationZ | RotationZ | BoostZ => Some(2),
            Time => None,
        }
    }

    pub fn name(self) -> &'static str {
        use Symmetry::*;
        match self {
            TranslationX => "translation_x",
            TranslationY => "translation_y",
            TranslationZ => "translation_z",
            RotationX => "rotation_x",
            RotationY => "rotation_y",
            RotationZ => "rotation_z",
            Time => "time",
            BoostX => "boost_x",
            BoostY => "boost_y",
            BoostZ => "boost_z",
        }
    }

    /// The conserved quantity, Noether's charge of this symmetry.
    pub fn charge(self) -> &'static str {
        use Symmetry::*;
        match self {
            TranslationX => "momentum_x",
            TranslationY => "momentum_y",
            TranslationZ => "momentum_z",
            RotationX => "angular_momentum_x",
            RotationY => "angular_momentum_y",
            RotationZ => "angular_momentum_z",
            Time => "energy",
            BoostX => "centre_of_mass_x",
            BoostY => "centre_of_mass_y",
            BoostZ => "centre_of_mass_z",
        }
    }
}

/// What a symmetry does to one part of a term.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The variation simplifies to zero.
    Invariant,
    /// The variation is the time derivative of `boundary` (a function of positions): still a
    /// symmetry, whose charge takes the boundary term off.
    UpToBoundary { boundary: String },
    /// Invariant when, for one of these sets, all its parameters are zero (a field with no
    /// component along the translation; a trap centred on the rotation's axis, or with k = 0).
    /// Each set is minimal: no smaller set does it.
    WhenZero { any_of: Vec<Vec<String>> },
    /// Not invariant for any value of the parameters short of the term vanishing.
    Broken,
}

/// The two parts of a term the table speaks of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The Lagrangian: −V plus any part linear in the velocities.
    Lagrangian,
    /// The Rayleigh dissipation function: for a charge to be conserved it must not change when
    /// the velocities move along the generator (Σ ξᵢ·∂F/∂vᵢ = 0); for time, its power must vanish.
    Dissipation,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TermSymmetries {
    pub lagrangian: BTreeMap<Symmetry, Verdict>,
    /// Only for terms with a dissipation function.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub dissipation: BTreeMap<Symmetry, Verdict>,
    /// The term's share of a charge beyond the free particles' (Σ m v, Σ m x × v, Σ ½mv²), as
    /// symbolica prints it, over the site symbols `x0, v0, m0, q0, ...` and the parameters.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub charge_share: BTreeMap<Symmetry, String>,
}

impl TermSymmetries {
    pub fn verdict(&self, part: Part, s: Symmetry) -> Verdict {
        let map = match part {
            Part::Lagrangian => &self.lagrangian,
            Part::Dissipation => &self.dissipation,
        };
        map.get(&s).cloned().unwrap_or(Verdict::Invariant)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Table {
    /// What wrote the table (`lagra-noether-derive`, its symbolica version).
    pub derived_by: String,
    /// By the term's canonical name.
    pub terms: BTreeMap<String, TermSymmetries>,
}

/// The checked-in table (`noether/derived.json`).
pub const DERIVED: &str = include_str!("../derived.json");

impl Table {
    /// The checked-in table, read once. Its completeness (every kind, every symmetry) is
    /// tested; a missing entry reads as broken, never as invariant.
    pub fn derived() -> &'static Table {
        static TABLE: OnceLock<Table> = OnceLock::new();
        TABLE
            .get_or_init(|| serde_json::from_str(DERIVED).expect("noether/derived.json is the derivation's own output"))
    }

    pub fn of(&self, kind: Kind) -> Option<&TermSymmetries> {
        self.terms.get(kind.name())
    }
}

/// The names of a kind's parameters, vector parameters by component (`g_0 g_1 g_2`), in the
/// order of the flattened parameter list: the names the derivation and the Lean export give them.
pub fn parameter_names(kind: Kind) -> Vec<String> {
    kind.spec()
        .params
        .iter()
        .flat_map(|p| {
            if p.len == 1 {
                vec![p.name.to_string()]
            } else {
                (0..p.len).map(|i| format!("{}_{i}", p.name)).collect()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checked_in_table_covers_every_kind_and_symmetry() {
        let t = Table::derived();
        for &k in Kind::ALL {
            let s = t.of(k).unwrap_or_else(|| panic!("{} is missing", k.name()));
            for sym in Symmetry::ALL {
                assert!(s.lagrangian.contains_key(&sym), "{} {}", k.name(), sym.name());
                assert_eq!(s.dissipation.contains_key(&sym), k.dissipative(), "{} {}", k.name(), sym.name());
            }
            for v in s.lagrangian.values().chain(s.dissipation.values()) {
                if let Verdict::WhenZero { any_of } = v {
                    assert!(!any_of.is_empty());
                    assert!(any_of.iter().flatten().all(|p| parameter_names(k).contains(p)), "{} {any_of:?}", k.name());
                }
            }
        }
    }

    #[test]
    fn symmetry_names_round_trip_through_json() {
        for s in Symmetry::ALL {
            let j = serde_json::to_string(&s).unwrap();
            assert_eq!(j, format!("\"{}\"", s.name()));
            assert_eq!(serde_json::from_str::<Symmetry>(&j).unwrap(), s);
        }
    }
}
