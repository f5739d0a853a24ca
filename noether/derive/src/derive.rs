//! The derivation: each term's definition, instantiated over symbolic sites and parameters, is
//! varied along the generator of each symmetry; the variation is simplified and either vanishes
//! (invariant), is the time derivative of a function of positions (invariant up to a boundary
//! term, which then enters the charge), vanishes once some parameters are zero, or does not.

use crate::sym::Sym;
use lagra_checker::terms::{Kind, Site};
use lagra_noether::{Symmetry, Table, TermSymmetries, Verdict};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use symbolica::prelude::*;

/// The symbols of a term's bodies and parameters.
struct Vars {
    /// Per site: position, velocity.
    x: Vec<[Symbol; 3]>,
    v: Vec<[Symbol; 3]>,
    sites: Vec<Site<Sym>>,
    /// (name in the table, symbol), in the order of the flattened parameter list.
    params: Vec<(String, Symbol)>,
    t: Symbol,
}

fn var(s: Symbol) -> Sym {
    Sym(Atom::var(s))
}

impl Vars {
    fn new(kind: Kind) -> Vars {
        let n = kind.spec().shape.arity();
        let x: Vec<[Symbol; 3]> = (0..n).map(|i| std::array::from_fn(|c| symbol!(&format!("x{i}_{c}")))).collect();
        let v: Vec<[Symbol; 3]> = (0..n).map(|i| std::array::from_fn(|c| symbol!(&format!("v{i}_{c}")))).collect();
        let sites = (0..n)
            .map(|i| Site {
                x: x[i].map(var),
                v: v[i].map(var),
                m: var(symbol!(&format!("m{i}"))),
                q: var(symbol!(&format!("q{i}"))),
                colour: std::array::from_fn(|k| var(symbol!(&format!("colour{i}_{k}")))),
            })
            .collect();
        let params = lagra_noether::parameter_names(kind)
            .into_iter()
            .map(|name| {
                let s = symbol!(&format!("par_{name}"));
                (name, s)
            })
            .collect();
        Vars { x, v, sites, params, t: symbol!("t") }
    }

    fn param_values(&self) -> Vec<Sym> {
        self.params.iter().map(|(_, s)| var(*s)).collect()
    }

    /// The generator of `s` at site i: (δx, δv), or `None` for time.
    fn generator(&self, s: Symmetry, i: usize) -> Option<([Atom; 3], [Atom; 3])> {
        let e = |a: usize| -> [Atom; 3] { std::array::from_fn(|c| Atom::num(i64::from(c == a))) };
        let cross = |a: usize, w: &[Symbol; 3]| -> [Atom; 3] {
            // e_a × w
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let mut out: [Atom; 3] = std::array::from_fn(|_| Atom::num(0));
            out[c] = Atom::var(w[b]);
            out[b] = -Atom::var(w[c]);
            out
        };
        let zero = || std::array::from_fn(|_| Atom::num(0));
        use Symmetry::*;
        Some(match s {
            TranslationX | TranslationY | TranslationZ => (e(s.axis()?), zero()),
            RotationX | RotationY | RotationZ => (cross(s.axis()?, &self.x[i]), cross(s.axis()?, &self.v[i])),
            BoostX | BoostY | BoostZ => (e(s.axis()?).map(|c| c * Atom::var(self.t)), e(s.axis()?)),
            Time => return None,
        })
    }

    /// δf along the generator: Σᵢ δxᵢ·∂f/∂xᵢ + δvᵢ·∂f/∂vᵢ.
    fn vary(&self, f: &Atom, s: Symmetry) -> Atom {
        let mut terms = vec![];
        for i in 0..self.x.len() {
            let (dx, dv) = self.generator(s, i).expect("a generator");
            for c in 0..3 {
                terms.push(&dx[c] * f.derivative(self.x[i][c]));
                terms.push(&dv[c] * f.derivative(self.v[i][c]));
            }
        }
        Atom::add_many(terms.iter())
    }

    /// Σᵢ ξᵢ(x)·∂F/∂vᵢ: how the dissipation function changes when the velocities move along the
    /// generator's position field; a charge is conserved against dissipation exactly when this
    /// vanishes (dQ/dt = −Σ ξᵢ·∂F/∂vᵢ).
    fn vary_velocities(&self, f: &Atom, s: Symmetry) -> Atom {
        let mut terms = vec![];
        for i in 0..self.x.len() {
            let (dx, _) = self.generator(s, i).expect("a generator");
            for c in 0..3 {
                terms.push(&dx[c] * f.derivative(self.v[i][c]));
            }
        }
        Atom::add_many(terms.iter())
    }

    /// The dissipated power Σ vᵢ·∂F/∂vᵢ: what time translation leaves of a dissipation function.
    fn power(&self, f: &Atom) -> Atom {
        let mut terms = vec![];
        for i in 0..self.x.len() {
            for c in 0..3 {
                terms.push(Atom::var(self.v[i][c]) * f.derivative(self.v[i][c]));
            }
        }
        Atom::add_many(terms.iter())
    }

    /// If δL = Σ Cᵢ·vᵢ with constant Cᵢ, the boundary term K = Σ Cᵢ·xᵢ (dK/dt = δL).
    fn boundary(&self, dl: &Atom) -> Option<Atom> {
        let mut k = vec![];
        let mut linear = vec![dl.clone()];
        for i in 0..self.x.len() {
            for c in 0..3 {
                let coeff = simplify(&dl.derivative(self.v[i][c]));
                let constant = (0..self.x.len()).all(|j| {
                    (0..3).all(|d| is_zero(&coeff.derivative(self.x[j][d])) && is_zero(&coeff.derivative(self.v[j][d])))
                }) && is_zero(&coeff.derivative(self.t));
                if !constant {
                    return None;
                }
                linear.push(-(&coeff * Atom::var(self.v[i][c])));
                k.push(&coeff * Atom::var(self.x[i][c]));
            }
        }
        is_zero(&Atom::add_many(linear.iter())).then(|| simplify(&Atom::add_many(k.iter())))
    }

    /// The minimal sets of parameters (up to three each) whose vanishing makes `f` vanish.
    fn when_zero(&self, f: &Atom) -> Vec<Vec<String>> {
        let n = self.params.len();
        let mut found: Vec<Vec<usize>> = vec![];
        for size in 1..=n.min(3) {
            for set in subsets(n, size) {
                if found.iter().any(|smaller| smaller.iter().all(|p| set.contains(p))) {
                    continue;
                }
                let mut g = f.clone();
                for &p in &set {
                    g = g.replace(Atom::var(self.params[p].1).to_pattern()).with(Atom::num(0).to_pattern());
                }
                if is_zero(&g) {
                    found.push(set);
                }
            }
        }
        found.iter().map(|set| set.iter().map(|&p| self.params[p].0.clone()).collect()).collect()
    }

    /// The verdict on a variation, with its boundary term if `boundary` is allowed.
    fn verdict(&self, variation: &Atom, boundary: bool) -> (Verdict, Option<Atom>) {
        if is_zero(variation) {
            return (Verdict::Invariant, None);
        }
        if let Some(k) = boundary.then(|| self.boundary(variation)).flatten() {
            return (Verdict::UpToBoundary { boundary: printed(&k) }, Some(k));
        }
        let any_of = self.when_zero(variation);
        if any_of.is_empty() {
            (Verdict::Broken, None)
        } else {
            (Verdict::WhenZero { any_of }, None)
        }
    }
}

/// The index sets of `size` out of `n`, in lexicographic order.
fn subsets(n: usize, size: usize) -> Vec<Vec<usize>> {
    if size == 0 {
        return vec![vec![]];
    }
    (0..n)
        .flat_map(|first| {
            subsets(n, size - 1).into_iter().filter(move |r| r.first().is_none_or(|&f| f > first)).map(move |mut r| {
                r.insert(0, first);
                r
            })
        })
        .collect()
}

/// Expanded, and over a common denominator when that is what cancels.
pub fn simplify(e: &Atom) -> Atom {
    let x = e.expand();
    if x.is_zero() {
        return x;
    }
    let t = x.together().expand();
    if t.is_zero() {
        t
    } else {
        x
    }
}

pub fn is_zero(e: &Atom) -> bool {
    simplify(e).is_zero()
}

/// As symbolica prints it, with the internal `par_` prefix taken off parameter names.
pub fn printed(e: &Atom) -> String {
    e.to_string().replace("par_", "")
}

/// One kind's row of the table.
pub fn term(kind: Kind) -> TermSymmetries {
    let vars = Vars::new(kind);
    let p = vars.param_values();
    let refs: Vec<&Site<Sym>> = vars.sites.iter().collect();
    let gyro = kind.gyroscopic(&p, &refs).map(|g| g.0);
    let lagrangian = {
        let v = kind.potential(&p, &refs).0;
        match &gyro {
            Some(g) => g - &v,
            None => -v,
        }
    };
    let rayleigh = kind.rayleigh(&p, &refs).map(|f| f.0);
    let mut row =
        TermSymmetries { lagrangian: BTreeMap::new(), dissipation: BTreeMap::new(), charge_share: BTreeMap::new() };
    for s in Symmetry::ALL {
        // time: no term depends on t explicitly, so its Lagrangian is invariant by construction
        let (verdict, boundary) = match s {
            Symmetry::Time => {
                (if lagrangian.contains_symbol(vars.t) { Verdict::Broken } else { Verdict::Invariant }, None)
            }
            _ => vars.verdict(
                &vars.vary(&lagrangian, s),
                !matches!(s, Symmetry::BoostX | Symmetry::BoostY | Symmetry::BoostZ),
            ),
        };
        row.lagrangian.insert(s, verdict.clone());
        if let Some(f) = &rayleigh {
            let variation = match s {
                Symmetry::Time => vars.power(f),
                _ => vars.vary_velocities(f, s),
            };
            row.dissipation.insert(s, vars.verdict(&variation, false).0);
        }
        // the share of the charge: Σ ∂L_gyro/∂vᵢ·ξᵢ − K, for the symmetries that have one
        if let (Some(g), false, true) = (
            &gyro,
            verdict == Verdict::Broken,
            s.axis().is_some() && !matches!(s, Symmetry::BoostX | Symmetry::BoostY | Symmetry::BoostZ),
        ) {
            let mut terms = vec![];
            for i in 0..vars.x.len() {
                let (dx, _) = vars.generator(s, i).expect("a generator");
                for c in 0..3 {
                    terms.push(&dx[c] * g.derivative(vars.v[i][c]));
                }
            }
            if let Some(k) = boundary {
                terms.push(-k);
            }
            let share = simplify(&Atom::add_many(terms.iter()));
            if !share.is_zero() {
                row.charge_share.insert(s, printed(&share));
            }
        }
    }
    row
}

/// The rows of `kinds`, each handed to `done` with the time it took as soon as it is derived
/// (the fluid's row takes minutes: `lagra-derive` reports progress through it).
pub fn rows(kinds: &[Kind], mut done: impl FnMut(Kind, Duration)) -> BTreeMap<String, TermSymmetries> {
    kinds
        .iter()
        .map(|&k| {
            let start = Instant::now();
            let row = term(k);
            done(k, start.elapsed());
            (k.name().to_string(), row)
        })
        .collect()
}

/// What the table says derived it.
pub fn derived_by() -> String {
    format!("lagra-noether-derive {} with symbolica 3.0.0", env!("CARGO_PKG_VERSION"))
}

/// The whole table.
pub fn table() -> Table {
    Table { derived_by: derived_by(), terms: rows(Kind::ALL, |_, _| ()) }
}
