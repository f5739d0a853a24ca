//! Bonded terms across domains: an instance (a bond, an angle, a dihedral) is kept whole on
//! every rank that owns one of its atoms, its other atoms there as ghosts; each rank keeps the
//! forces on its own atoms. The halo must reach as far as an instance's atoms can lie apart:
//! `span`, worked out at the start, and checked each time the ghosts are chosen.

use lagra_checker::model::{Cell, Model, TermInstance};
use lagra_checker::terms::Kind;
use std::collections::HashMap;

/// How much an instance's atoms may spread beyond their span at the start (a FENE bond never
/// beyond its R0).
const STRETCH: f64 = 1.5;

pub struct Bonded {
    /// The instances with listed atoms, in the model's order.
    terms: Vec<TermInstance>,
    /// For each atom, the instances it takes part in.
    of: Vec<Vec<u32>>,
    /// How far apart two atoms of one instance may lie (0 without any).
    pub span: f64,
}

impl Bonded {
    /// The model's bonded instances, at the positions `x` of the start.
    pub fn of(model: &Model, x: &[[f64; 3]]) -> Bonded {
        let terms: Vec<TermInstance> = model.terms.iter().filter(|t| !t.sites.is_empty()).cloned().collect();
        let mut of = vec![vec![]; x.len()];
        let mut span = 0.0f64;
        for (k, t) in terms.iter().enumerate() {
            t.sites.iter().for_each(|&i| of[i].push(k as u32));
            let mut widest = 0.0f64;
            for (a, &i) in t.sites.iter().enumerate() {
                for &j in &t.sites[a + 1..] {
                    let d = Cell::image(&model.cell, [0, 1, 2].map(|c| x[j][c] - x[i][c]));
                    widest = widest.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                }
            }
            span = span.max(match t.kind {
                Kind::FeneBond => t.params[1],
                _ => STRETCH * widest,
            });
        }
        of.iter_mut().for_each(|o| o.dedup());
        Bonded { terms, of, span }
    }

    /// The instances with an atom among `owned`, in the model's order, each with its number among
    /// the model's bonded instances and its atoms renumbered to their local places (`place`). An
    /// instance with an atom not local: its two atoms that are farthest apart along the
    /// instance, the one owned first.
    pub fn local(
        &self,
        owned: &[usize],
        place: &HashMap<usize, usize>,
    ) -> Result<Vec<(usize, TermInstance)>, [usize; 2]> {
        let mut ks: Vec<u32> = owned.iter().flat_map(|&i| self.of[i].iter().copied()).collect();
        ks.sort_unstable();
        ks.dedup();
        ks.iter()
            .map(|&k| {
                let t = &self.terms[k as usize];
                let sites = t.sites.iter().map(|i| place.get(i).copied().ok_or(*i)).collect::<Result<Vec<_>, _>>();
                match sites {
                    Ok(sites) => Ok((k as usize, TermInstance { sites, ..t.clone() })),
                    Err(missing) => {
                        Err([*t.sites.iter().find(|i| owned.binary_search(i).is_ok()).unwrap_or(&t.sites[0]), missing])
                    }
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lagra_checker::model::{Body, UnitSystem};

    fn chain() -> (Model, Vec<[f64; 3]>) {
        let body = Body { mass: 1.0, charge: 0.0, colour: [0.0; 2], moments: None, solid: None };
        let bond = |i: usize, p: Vec<f64>, kind| TermInstance { kind, sites: vec![i, i + 1], params: p };
        let model = Model {
            units: UnitSystem::Reduced,
            cell: Some(Cell { size: [10.0; 3], periodic: [true; 3] }),
            bodies: vec![body; 4],
            terms: vec![
                bond(0, vec![1.0, 1.0, 0.0], Kind::HarmonicBond),
                bond(1, vec![30.0, 1.5], Kind::FeneBond),
                bond(2, vec![1.0, 1.0, 0.0], Kind::HarmonicBond),
            ],
            constraints: vec![],
            thermostat: None,
            floor: None,
            pins: vec![],
        };
        // the last bond across the box's face: its nearest image is 1 long
        (model, vec![[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 0.0, 9.0]])
    }

    #[test]
    fn the_span_is_the_widest_bond_stretched_or_a_fene_bonds_reach() {
        let (model, x) = chain();
        assert_eq!(Bonded::of(&model, &x).span, 1.5);
        let wide = [x[0], x[1], x[2], [3.0, 0.0, 7.0]];
        assert_eq!(Bonded::of(&model, &wide).span, 4.5);
    }

    #[test]
    fn a_rank_keeps_the_instances_of_its_atoms_renumbered_and_names_a_missing_atom() {
        let (model, x) = chain();
        let b = Bonded::of(&model, &x);
        // atoms 1 and 2 owned, 0 and 3 ghosts
        let place = HashMap::from([(1, 0), (2, 1), (0, 2), (3, 3)]);
        let local = b.local(&[1, 2], &place).unwrap();
        let sites: Vec<_> = local.iter().map(|(k, t)| (*k, t.kind, t.sites.clone())).collect();
        assert_eq!(
            sites,
            [(0, Kind::HarmonicBond, vec![2, 0]), (1, Kind::FeneBond, vec![0, 1]), (2, Kind::HarmonicBond, vec![1, 3])]
        );
        let without = HashMap::from([(1, 0), (2, 1), (0, 2)]);
        assert_eq!(b.local(&[1, 2], &without).unwrap_err(), [2, 3]);
        assert_eq!(b.local(&[0], &without).unwrap().len(), 1);
    }
}
