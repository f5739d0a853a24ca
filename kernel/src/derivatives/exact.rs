//! A term's force and its derivatives, from its one definition alone (never from the kernel's
//! fast code): the Euler–Lagrange force
//!
//!   Fᵢ = −∂V/∂xᵢ − ∂R/∂vᵢ + ∂L_g/∂xᵢ − (v·∇ₓ) ∂L_g/∂vᵢ
//!
//! (potential V, Rayleigh function R, the part L_g of the Lagrangian linear in v), generic over
//! the scalar: on `f64` it is the force, on `Dual<f64>` its derivative along any direction of
//! positions, velocities, masses, charges and parameters. A central pair term has a cheaper
//! form, `radial`: V along the distance, whose first two derivatives give the force and its
//! derivatives (`Radial`).

use super::dual::{Dual, Part};
use lagra_checker::terms::{Kind, Site};

/// Sites lifted to duals, coordinate (b, c) of the positions (or velocities) seeded with 1.
fn seeded<R: Part>(sites: &[Site<R>], b: usize, c: usize, velocity: bool) -> Vec<Site<Dual<R>>> {
    sites
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let seed = |k: usize, vel: bool| {
                let one = if i == b && k == c && vel == velocity { 1.0 } else { 0.0 };
                s.m.lift(one)
            };
            Site {
                x: std::array::from_fn(|k| Dual::new(s.x[k], seed(k, false))),
                v: std::array::from_fn(|k| Dual::new(s.v[k], seed(k, true))),
                m: Dual::constant(s.m),
                q: Dual::constant(s.q),
                colour: s.colour.map(Dual::constant),
            }
        })
        .collect()
}

/// The same sites with positions moved along `xd` (as the derivative) and velocities replaced
/// by `vel`.
fn transported<R: Part>(
    sites: &[Site<R>],
    xd: impl Fn(usize, usize) -> R,
    vel: impl Fn(usize, usize) -> R,
) -> Vec<Site<Dual<R>>> {
    sites
        .iter()
        .enumerate()
        .map(|(i, s)| Site {
            x: std::array::from_fn(|k| Dual::new(s.x[k], xd(i, k))),
            v: std::array::from_fn(|k| Dual::constant(vel(i, k))),
            m: Dual::constant(s.m),
            q: Dual::constant(s.q),
            colour: s.colour.map(Dual::constant),
        })
        .collect()
}

fn refs<T>(v: &[T]) -> Vec<&T> {
    v.iter().collect()
}

/// The Euler–Lagrange force of one instance (parameters `p`, constants included or not) on each
/// of its sites.
pub fn force<R: Part>(kind: Kind, p: &[R], sites: &[Site<R>]) -> Vec<[R; 3]> {
    let zero = sites[0].m.zero();
    let lifted: Vec<Dual<R>> = p.iter().map(|&c| Dual::constant(c)).collect();
    let probe = refs(sites);
    let velocity = kind.rayleigh(p, &probe).is_some();
    let gyroscopic = kind.gyroscopic(p, &probe).is_some();
    let unit = |b: usize, c: usize| move |i: usize, k: usize| if (i, k) == (b, c) { zero.lift(1.0) } else { zero };
    (0..sites.len())
        .map(|b| {
            std::array::from_fn(|c| {
                let at_x = seeded(sites, b, c, false);
                let mut f = -kind.potential(&lifted, &refs(&at_x)).d;
                if velocity {
                    let at_v = seeded(sites, b, c, true);
                    f = f - kind.rayleigh(&lifted, &refs(&at_v)).map_or(zero, |r| r.d);
                }
                if gyroscopic {
                    // ∂L_g/∂x_bc − (v·∇ₓ)∂L_g/∂v_bc; L_g is linear in v, so ∂L_g/∂v_bc is L_g at
                    // the unit velocity e_bc
                    let v = |i: usize, k: usize| sites[i].v[k];
                    let dx = transported(sites, unit(b, c), v);
                    let dv = transported(sites, v, unit(b, c));
                    let l = |s: &[Site<Dual<R>>]| kind.gyroscopic(&lifted, &refs(s)).map_or(zero, |g| g.d);
                    f = f + l(&dx) - l(&dv);
                }
                f
            })
        })
        .collect()
}

/// A central pair potential along the distance: the force on body i is s·d (d = xⱼ − xᵢ) with
/// s = V′(r)/r, and its derivative along a change δd of d, a change δθ of the parameters (and
/// masses, charges) is s·δd + s_r·(d·δd)·d + Σ s_θ δθ·d, where s_r = (V″ − s)/r².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Radial {
    pub s: f64,
    pub s_r: f64,
}

/// Bodies i and j of a pair as the definition sees them: i at the origin, j at distance r along
/// x, with masses, charges and colours `bodies` ([mᵢ, mⱼ, qᵢ, qⱼ]) and `colour` ([cᵢ, cⱼ]).
pub fn pair_sites<R: Part>(r: R, bodies: [R; 4], colour: [[R; 2]; 2]) -> [Site<R>; 2] {
    let zero = r.zero();
    let at = |x: R, m: R, q: R, colour: [R; 2]| Site { x: [x, zero, zero], v: [zero; 3], m, q, colour };
    [at(zero, bodies[0], bodies[2], colour[0]), at(r, bodies[1], bodies[3], colour[1])]
}

/// V and V′ of a central pair term at distance r (bodies and colours as in `pair_sites`).
pub fn along(kind: Kind, p: &[f64], bodies: [f64; 4], colour: [[f64; 2]; 2], r: f64) -> (f64, f64) {
    let params: Vec<Dual<f64>> = p.iter().map(|&x| Dual::constant(x)).collect();
    let sites = pair_sites(Dual::new(r, 1.0), bodies.map(Dual::constant), colour.map(|k| k.map(Dual::constant)));
    let v = kind.potential(&params, &refs(&sites));
    (v.v, v.d)
}

type D2 = Dual<Dual<f64>>;

/// s and s_r of a central pair term at distance r, from V, V′ and V″ of its definition (one
/// evaluation on second-order duals).
pub fn radial(kind: Kind, p: &[f64], bodies: [f64; 4], colour: [[f64; 2]; 2], r: f64) -> Radial {
    let c = |x: f64| -> D2 { Dual::constant(Dual::constant(x)) };
    let jet = Dual::new(Dual::new(r, 1.0), Dual::new(1.0, 0.0));
    let sites = pair_sites(jet, bodies.map(c), colour.map(|k| k.map(c)));
    let params: Vec<D2> = p.iter().map(|&x| c(x)).collect();
    let v = kind.potential(&params, &refs(&sites));
    let (dv, ddv) = (v.v.d, v.d.d);
    let s = dv / r;
    Radial { s, s_r: (ddv - s) / (r * r) }
}

/// ∂s/∂θ for each of `wanted` (indices into the parameters, then `p.len() + k` for body
/// quantity k of [mᵢ, mⱼ, qᵢ, qⱼ]): V′ differentiated along it, over r.
pub fn radial_sensitivities(
    kind: Kind,
    p: &[f64],
    bodies: [f64; 4],
    colour: [[f64; 2]; 2],
    r: f64,
    wanted: &[usize],
) -> Vec<f64> {
    wanted
        .iter()
        .map(|&w| {
            let seed = |k: usize, x: f64| -> D2 {
                Dual::new(Dual::constant(x), Dual::constant(if k == w { 1.0 } else { 0.0 }))
            };
            let params: Vec<D2> = p.iter().enumerate().map(|(k, &x)| seed(k, x)).collect();
            let b: [D2; 4] = std::array::from_fn(|k| seed(p.len() + k, bodies[k]));
            let jet = Dual::new(Dual::new(r, 1.0), Dual::constant(0.0));
            let sites = pair_sites(jet, b, colour.map(|k| k.map(|x| Dual::constant(Dual::constant(x)))));
            kind.potential(&params, &refs(&sites)).d.d / r
        })
        .collect()
}

/// V′(r) of a central pair term, and ∂V/∂θ for each of `wanted` (numbered as in
/// `radial_sensitivities`): what the potential energy's own gradient needs.
pub fn radial_potential(
    kind: Kind,
    p: &[f64],
    bodies: [f64; 4],
    colour: [[f64; 2]; 2],
    r: f64,
    wanted: &[usize],
) -> (f64, Vec<f64>) {
    let at = |seed_r: f64, w: Option<usize>| -> f64 {
        let seed = |k: usize, x: f64| Dual::new(x, if Some(k) == w { 1.0 } else { 0.0 });
        let params: Vec<Dual<f64>> = p.iter().enumerate().map(|(k, &x)| seed(k, x)).collect();
        let b: [Dual<f64>; 4] = std::array::from_fn(|k| seed(p.len() + k, bodies[k]));
        let sites = pair_sites(Dual::new(r, seed_r), b, colour.map(|k| k.map(Dual::constant)));
        kind.potential(&params, &refs(&sites)).d
    };
    (at(1.0, None), wanted.iter().map(|&w| at(0.0, Some(w))).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn site(x: [f64; 3], v: [f64; 3], m: f64, q: f64) -> Site<f64> {
        Site { x, v, m, q, colour: [0.3, -0.1] }
    }

    /// The definition's force on f64 is the force the kernel's fast code computes (held there
    /// by the kernel's own dual tests); here: a harmonic bond and a magnetic field by hand.
    #[test]
    fn the_euler_lagrange_force_of_a_spring_and_a_field() {
        let s = [site([0.0; 3], [0.0; 3], 1.0, 0.0), site([1.5, 0.0, 0.0], [0.0; 3], 1.0, 0.0)];
        let f = force(Kind::HarmonicBond, &[2.0, 1.0, 0.0], &s);
        assert!((f[0][0] - 1.0).abs() < 1e-15 && (f[1][0] + 1.0).abs() < 1e-15, "{f:?}");
        let q = [site([0.2, 0.1, 0.0], [1.0, 2.0, 3.0], 1.0, 2.0)];
        let f = force(Kind::MagneticField, &[0.0, 0.0, 0.5], &q);
        // q v × B = 2·(2·0.5, −1·0.5, 0)
        assert!((f[0][0] - 2.0).abs() < 1e-15 && (f[0][1] + 1.0).abs() < 1e-15 && f[0][2].abs() < 1e-15, "{f:?}");
    }

    /// The radial form gives the same force and force derivative as the full definition.
    #[test]
    fn the_radial_form_is_the_full_derivative() {
        let (p, b, col) = ([1.0, 1.0, 2.5], [1.0, 2.0, 0.5, -1.0], [[0.0; 2]; 2]);
        let r = 1.13;
        let k = radial(Kind::LennardJones, &p, b, col, r);
        // along x: F_i = s·r, dF_i/dx_j = s + s_r r²
        let at = |dx: f64| -> Vec<Site<Dual<f64>>> {
            vec![
                Site {
                    x: [Dual::constant(0.0); 3],
                    v: [Dual::constant(0.0); 3],
                    m: Dual::constant(1.0),
                    q: Dual::constant(0.5),
                    colour: [Dual::constant(0.0); 2],
                },
                Site {
                    x: [Dual::new(r, dx), Dual::constant(0.0), Dual::constant(0.0)],
                    v: [Dual::constant(0.0); 3],
                    m: Dual::constant(2.0),
                    q: Dual::constant(-1.0),
                    colour: [Dual::constant(0.0); 2],
                },
            ]
        };
        let params: Vec<Dual<f64>> = p.iter().map(|&c| Dual::constant(c)).collect();
        let f = force(Kind::LennardJones, &params, &at(1.0));
        assert!((f[0][0].v - k.s * r).abs() < 1e-12 * k.s.abs());
        assert!((f[0][0].d - (k.s + k.s_r * r * r)).abs() < 1e-11 * (k.s.abs() + (k.s_r * r * r).abs()));
        // ∂s/∂ε = s/ε for LJ
        let ds = radial_sensitivities(Kind::LennardJones, &p, b, col, r, &[0]);
        assert!((ds[0] - k.s).abs() < 1e-12 * k.s.abs(), "{ds:?} {}", k.s);
    }
}
