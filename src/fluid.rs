//! What `lagra run` says of a fluid before it runs: whether its particles are close enough for
//! the kernel's support to hold a density sum at all. SPH's density at a particle is a sum over
//! the particles within 2h (Wendland C2's support); with only a few of them it is a coarse
//! sampling of W and the pressure is noise. Usual resolutions give dozens (the dam break, h = 1.3
//! spacings in 3-D: 80 for the median particle, 31 for the fewest); the warning is for a scene
//! that gives a few.

use lagra_checker::model::Cell;
use lagra_checker::terms::{sph::SUPPORT, Shape};
use lagra_kernel::traverse;
use lagra_lang::{Diagnostic, Scene};

/// Fewer neighbours than this within the support, for the median particle, is a warning.
pub const FEWEST_NEIGHBOURS: usize = 10;

/// How many other bodies lie within `reach` of each body (minimum image in a periodic box).
pub fn neighbour_counts(x: &[[f64; 3]], cell: &Option<Cell>, reach: f64) -> Vec<usize> {
    let mut counts = vec![0; x.len()];
    traverse::pairs::<()>(x, cell, Some(reach), |i, j, d| {
        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach {
            counts[i] += 1;
            counts[j] += 1;
        }
        Ok(())
    })
    .expect("the visitor does not fail");
    counts
}

/// A warning at each `sph` term whose support holds fewer than `FEWEST_NEIGHBOURS` other
/// particles around the median particle at the initial state, rendered as `file:line:col`.
pub fn warnings(scene: &Scene, path: &str, source: &str) -> Vec<String> {
    let model = &scene.model;
    model
        .terms
        .iter()
        .zip(&scene.spans.terms)
        .filter(|(t, _)| t.kind.spec().shape == Shape::Density)
        .filter_map(|(t, at)| {
            let h = t.params[0];
            let mut counts = neighbour_counts(&scene.x0, &model.cell, SUPPORT * h);
            counts.sort_unstable();
            let median = counts[counts.len() / 2];
            (median < FEWEST_NEIGHBOURS).then(|| {
                let message = format!(
                    "warning: the median particle has {median} neighbour{} within the kernel's support \
                     (2h = {}), fewest {}: SPH's density needs at least {FEWEST_NEIGHBOURS}; raise h or \
                     place the particles closer (h of about 1.3 spacings is usual)",
                    if median == 1 { "" } else { "s" },
                    SUPPORT * h,
                    counts[0],
                );
                Diagnostic::new(*at, message).render(path, source).to_string()
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice(n: usize, spacing: f64) -> Vec<[f64; 3]> {
        (0..n * n * n)
            .map(|k| [(k % n) as f64, ((k / n) % n) as f64, (k / (n * n)) as f64].map(|c| c * spacing))
            .collect()
    }

    #[test]
    fn a_cubic_lattice_counts_its_nearest_neighbours() {
        // reach between 1 and √2 spacings: six neighbours inside, three at a corner
        let c = neighbour_counts(&lattice(5, 0.5), &None, 0.6);
        assert_eq!((c[0], c[62], *c.iter().max().unwrap()), (3, 6, 6));
        // the same lattice in a periodic box of its own size: every body has six
        let cell = Some(Cell { size: [2.5; 3], periodic: [true; 3] });
        assert!(neighbour_counts(&lattice(5, 0.5), &cell, 0.6).iter().all(|&n| n == 6));
    }

    #[test]
    fn the_dam_breaks_particles_have_dozens_of_neighbours() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/dam_break.lagra");
        let source = std::fs::read_to_string(path).unwrap();
        let scene = lagra_lang::compile(&source).unwrap();
        let h = scene.model.terms.iter().find(|t| t.kind.spec().shape == Shape::Density).unwrap().params[0];
        let mut counts = neighbour_counts(&scene.x0, &scene.model.cell, SUPPORT * h);
        counts.sort_unstable();
        assert_eq!((counts[0], counts[counts.len() / 2]), (31, 80));
        assert!(warnings(&scene, path, &source).is_empty());
    }

    #[test]
    fn a_fluid_too_sparse_for_its_kernel_is_warned_of_where_it_is_written() {
        let entities: String = lattice(4, 0.1)
            .iter()
            .map(|p| format!("  entity {{ mass: 0.001, position: [{}, {}, {}] }}\n", p[0], p[1], p[2]))
            .collect();
        let scene = |h: f64| {
            format!(
                "scene s {{\n{entities}  sph {{ h: {h}, rest_density: 1000, sound_speed: 10 }}\n  solver {{ dt: 0.001, steps: 1 }}\n}}\n"
            )
        };
        // support 2h = 0.12 reaches the six nearest: warned, at the term's keyword
        let sparse = scene(0.06);
        let w = warnings(&lagra_lang::compile(&sparse).unwrap(), "f.lagra", &sparse);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("f.lagra:66:3: warning: the median particle has 5 neighbours"), "{}", w[0]);
        assert!(w[0].contains("fewest 3"), "{}", w[0]);
        // 2h = 0.3 holds the 3×3×3 block around an interior particle and more: no warning
        let dense = scene(0.15);
        assert!(warnings(&lagra_lang::compile(&dense).unwrap(), "f.lagra", &dense).is_empty());
    }
}
