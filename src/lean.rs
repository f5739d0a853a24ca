//! Lean 4 export. The term definitions are printed from the checker's own generic definitions
//! through a [`Real`] instance whose values are Lean terms of type `Rat`; the numeric obligations
//! are a certificate's checkpoints with their binary64 endpoints written exactly as rationals.
//! Lean then checks both: `lean/check.sh`.

use lagra_checker::certificate::Certificate;
use lagra_checker::decision::{classify, Class};
use lagra_checker::real::Real;
use lagra_checker::terms::{Kind, Shape, Site};
use lagra_noether::parameter_names;
use rug::Integer;
use std::cell::RefCell;
use std::fmt::Write as _;
use std::ops::{Add, Div, Mul, Neg, Sub};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// The certificate whose certified claims become Lean theorems (omit with --definitions).
    certificate: Option<PathBuf>,
    /// Where to write the Lean file (default: stdout).
    #[arg(short, long, value_name = "FILE.lean")]
    out: Option<PathBuf>,
    /// Instead, write the term definitions and their invariance theorems into this folder
    /// (`lean/Lagra`: Terms.lean, Invariance.lean).
    #[arg(long, value_name = "DIR", conflicts_with = "certificate")]
    definitions: Option<PathBuf>,
}

pub fn main(a: Args) -> ExitCode {
    let result = match (&a.definitions, &a.certificate) {
        (Some(dir), _) => std::fs::write(dir.join("Terms.lean"), terms())
            .and_then(|_| std::fs::write(dir.join("Invariance.lean"), invariance()))
            .map_err(|e| format!("cannot write into {}: {e}", dir.display())),
        (None, Some(c)) => crate::reading::text(c, crate::reading::Limits::from_env().certificate)
            .and_then(|text| Certificate::read(&text).map_err(|e| format!("{}: {e}", c.display())))
            .and_then(|cert| obligations(&cert))
            .and_then(|lean| match &a.out {
                Some(path) => std::fs::write(path, lean).map_err(|e| format!("cannot write {}: {e}", path.display())),
                None => {
                    print!("{lean}");
                    Ok(())
                }
            }),
        (None, None) => Err("give a certificate, or --definitions DIR".into()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lagra: {e}");
            ExitCode::from(2)
        }
    }
}

/// A finite binary64 value as m·2^e, m odd (or zero): the exact dyadic rational it is.
pub fn dyadic(c: f64) -> (i64, i64) {
    assert!(c.is_finite(), "only finite values are exported");
    if c == 0.0 {
        return (0, 0);
    }
    let bits = c.to_bits();
    let (sign, exponent, fraction) = (bits >> 63, ((bits >> 52) & 0x7ff) as i64, bits & ((1 << 52) - 1));
    let (mut m, mut e) = if exponent == 0 { (fraction, -1074) } else { (fraction | (1 << 52), exponent - 1075) };
    while m % 2 == 0 {
        m /= 2;
        e += 1;
    }
    (if sign == 1 { -(m as i64) } else { m as i64 }, e)
}

/// Two binary64 values as integers over one power of two, `(a·2^-e, b·2^-e, e)` exactly: then
/// `a ≤ b` is decided on the integers alone, which is what keeps Lean's kernel (and the WASM
/// build's 4 GB) from computing a rational or a power per checkpoint.
pub fn common_exponent(a: f64, b: f64) -> (Integer, Integer, i64) {
    let ((am, ae), (bm, be)) = (dyadic(a), dyadic(b));
    // a zero's exponent is arbitrary: it takes the other's, so that no mantissa is shifted
    let e = match (am, bm) {
        (0, _) => be,
        (_, 0) => ae,
        _ => ae.min(be),
    };
    let scale = |m: i64, x: i64| Integer::from(m) << u32::try_from(if m == 0 { 0 } else { x - e }).expect("x ≥ e");
    (scale(am, ae), scale(bm, be), e)
}

/// A binary64 value as the exact rational it is, a Lean literal: `(m : Rat)` or
/// `((m : Rat) / 2^k)` with 2^k spelled out, so Lean reads the very number.
pub fn exact(c: f64) -> String {
    let (m, e) = dyadic(c);
    if m == 0 {
        return "(0 : Rat)".into();
    }
    let (s, m) = (if m < 0 { "-" } else { "" }, m.unsigned_abs());
    if e >= 0 {
        format!("({s}{} : Rat)", Integer::from(m) << e as u32)
    } else {
        format!("(({s}{m} : Rat) / {})", Integer::from(1) << (-e) as u32)
    }
}

/// A Lean term of type `Rat`, built by the checker's definitions.
#[derive(Clone, Debug)]
struct Lean(String);

thread_local! {
    /// The conditions `lt` was asked and could not decide, innermost last: the `select` that
    /// asked is the next to call `hull`, which turns it into an `if`.
    static CONDITIONS: RefCell<Vec<String>> = const { RefCell::new(vec![]) };
}

macro_rules! binary {
    ($($tr:ident $f:ident $op:literal),*) => {$(
        impl $tr for Lean {
            type Output = Lean;
            fn $f(self, o: Lean) -> Lean {
                Lean(format!("({} {} {})", self.0, $op, o.0))
            }
        }
    )*};
}
binary!(Add add "+", Sub sub "-", Mul mul "*", Div div "/");

impl Neg for Lean {
    type Output = Lean;
    fn neg(self) -> Lean {
        Lean(format!("(-{})", self.0))
    }
}

impl Lean {
    fn call(f: &str, args: &[&Lean]) -> Lean {
        Lean(format!("({f} {})", args.iter().map(|a| a.0.as_str()).collect::<Vec<_>>().join(" ")))
    }
}

impl Real for Lean {
    fn lift(&self, c: f64) -> Self {
        Lean(exact(c))
    }
    fn sqrt(self) -> Self {
        Lean::call("Lagra.sqrt", &[&self])
    }
    /// As a product, so that the ring normaliser of Lean's `grind` sees through it.
    fn powi(self, n: i32) -> Self {
        let product = match n.unsigned_abs() {
            0 => "1".to_string(),
            k => format!("({})", vec![self.0.as_str(); k as usize].join(" * ")),
        };
        Lean(if n < 0 { format!("(1 / {product})") } else { product })
    }
    fn exp(self) -> Self {
        Lean::call("Lagra.exp", &[&self])
    }
    fn ln(self) -> Self {
        Lean::call("Lagra.log", &[&self])
    }
    fn acos(self) -> Self {
        Lean::call("Lagra.acos", &[&self])
    }
    fn cos(self) -> Self {
        Lean::call("Lagra.cos", &[&self])
    }
    fn sin(self) -> Self {
        Lean::call("Lagra.sin", &[&self])
    }
    fn atan2(self, x: Self) -> Self {
        Lean::call("Lagra.atan2", &[&self, &x])
    }
    fn lt(&self, bound: &Self) -> Option<bool> {
        CONDITIONS.with(|c| c.borrow_mut().push(format!("{} < {}", self.0, bound.0)));
        None
    }
    fn hull(self, o: Self) -> Self {
        let cond = CONDITIONS.with(|c| c.borrow_mut().pop()).expect("hull follows an undecided lt");
        Lean(format!("(if {cond} then {} else {})", self.0, o.0))
    }
}

const OPAQUE: &[&str] =
    &["Lagra.sqrt", "Lagra.exp", "Lagra.log", "Lagra.acos", "Lagra.cos", "Lagra.sin", "Lagra.atan2"];

fn site(i: usize) -> Site<Lean> {
    let f = |name: &str| Lean(format!("s{i}.{name}"));
    Site {
        x: [f("x"), f("y"), f("z")],
        v: [f("vx"), f("vy"), f("vz")],
        m: f("m"),
        q: f("q"),
        colour: [f("c1"), f("c2")],
    }
}

/// The potential of a kind as a Lean expression, and whether it stays within ℚ.
fn potential(kind: Kind) -> (String, bool) {
    let p: Vec<Lean> = parameter_names(kind).into_iter().map(Lean).collect();
    let sites: Vec<Site<Lean>> = (0..kind.spec().shape.arity()).map(site).collect();
    let refs: Vec<&Site<Lean>> = sites.iter().collect();
    let e = kind.potential(&p, &refs).0;
    let rational = !OPAQUE.iter().any(|f| e.contains(f));
    (e, rational)
}

fn signature(kind: Kind) -> String {
    let sites: Vec<String> = (0..kind.spec().shape.arity()).map(|i| format!("s{i}")).collect();
    format!("({} : Rat) ({} : Site)", parameter_names(kind).join(" "), sites.join(" "))
}

const HEADER: &str = "-- Generated by `lagra lean --definitions lean/Lagra` from the checker's term definitions:\n-- edit checker/src/terms, not this file.\n";

/// `Lagra/Terms.lean`: each term's potential, printed from its one definition.
pub fn terms() -> String {
    let mut out = format!("{HEADER}import Lagra.Basic\n\nset_option linter.unusedVariables false\n\nnamespace Lagra\n");
    for &kind in Kind::ALL {
        let (e, rational) = potential(kind);
        let over = if rational {
            "over ℚ exactly".to_string()
        } else {
            let used: Vec<&str> = OPAQUE.iter().filter(|f| e.contains(*f)).map(|f| &f[6..]).collect();
            format!("over ℚ with {} uninterpreted (not rational functions)", used.join(", "))
        };
        let _ = writeln!(out, "\n/-- {}: the potential, {over}. -/", kind.name());
        let _ = writeln!(out, "def {}.potential {} : Rat :=\n  {e}", kind.name(), signature(kind));
    }
    out + "\nend Lagra\n"
}

/// The symmetries stated of every pair and bond term: a common translation, and a quarter turn
/// about z (a rotation with rational entries, so it stays within ℚ).
const SYMMETRIES: &[(&str, &str, &str)] =
    &[("translation", "(dx dy dz : Rat)", ".shift dx dy dz"), ("quarter_turn_z", "", ".quarterTurnZ")];

/// Stated but not (yet) proved within Lean core: (kind, symmetry). Each is a `sorry` that
/// `lean/check.sh` counts, and `docs/lean.md` lists.
pub const OPEN: &[(&str, &str)] = &[];

/// The binder names the theorems use besides the parameters' (tested not to collide).
#[cfg(test)]
const BINDERS: &[&str] = &["dx", "dy", "dz", "s0", "s1", "s2", "s3"];

/// `Lagra/Invariance.lean`: the invariance of each pair and bond term under the symmetries, as
/// theorems over the definitions in `Terms.lean`.
pub fn invariance() -> String {
    // one simp set serves every kind, so some of its lemmas go unused for some of them
    let mut out = format!(
        "{HEADER}import Lagra.Terms\n\nset_option linter.unusedVariables false\nset_option linter.unusedSimpArgs false\n\nnamespace Lagra\n"
    );
    for &kind in Kind::ALL.iter().filter(|k| !matches!(k.spec().shape, Shape::External)) {
        let n = kind.spec().shape.arity();
        let params = parameter_names(kind).join(" ");
        for (name, binders, act) in SYMMETRIES {
            let moved: Vec<String> = (0..n).map(|i| format!("(s{i}{act})")).collect();
            let plain: Vec<String> = (0..n).map(|i| format!("s{i}")).collect();
            let proof = if OPEN.contains(&(kind.name(), name)) {
                "sorry".to_string()
            } else {
                // A translation leaves differences of positions alone: `shift_sub` rewrites them
                // back and the two sides meet. A quarter turn leaves the x, y part of every dot
                // product of differences alone (`dot_quarterTurnZ`) and z as it was; what is
                // left (cross products, in the dihedral) goes to `grind`'s ring normaliser.
                match *name {
                    "translation" => format!("simp only [{}.potential, Site.shift, shift_sub]", kind.name()),
                    _ => format!(
                        "simp only [{}.potential, Site.dot_quarterTurnZ, Site.quarterTurnZ_z, Site.quarterTurnZ_m,\n    Site.quarterTurnZ_q, Site.quarterTurnZ_c1, Site.quarterTurnZ_c2]\n  all_goals simp only [Site.quarterTurnZ]\n  all_goals grind",
                        kind.name()
                    ),
                }
            };
            let _ = writeln!(
                out,
                "\ntheorem {k}.{name} ({params} : Rat) {binders} ({s} : Site) :\n    {k}.potential {params} {m} = {k}.potential {params} {p} := by\n  {proof}",
                k = kind.name(),
                s = plain.join(" "),
                m = moved.join(" "),
                p = plain.join(" "),
            );
        }
    }
    out + "\nend Lagra\n"
}

/// Marks per definition: Lean elaborates long list literals slowly, so a trail is cut up; the
/// whole trail is their concatenation. All `noncomputable`: only Lean's kernel evaluates them,
/// and compiling them would cost the WASM build memory it does not have (and its code
/// generator lacks `List.append`'s compiled form).
const CHUNK: usize = 200;

/// The Lean file of a certificate's obligations: for each claim the checker certified, the
/// checkpoints' upper bounds and tolerances, exactly, and the theorems that every one holds.
pub fn obligations(cert: &Certificate) -> Result<String, String> {
    let space = lean_name(&cert.scene);
    let mut out = format!(
        "-- Generated by `lagra lean` from the certificate of scene `{}` ({}, {}): do not edit.\n\
         import Lagra.Basic\n\nset_option linter.unusedVariables false\n\nnamespace Lagra.Generated.{space}\n\nopen Lagra\n",
        cert.scene, cert.source_digest, cert.checksum
    );
    let mut exported = 0;
    for (claim, trail) in cert.claims.iter().zip(&cert.trails) {
        let certified = !trail.marks.is_empty()
            && trail.marks.iter().all(|m| classify(m.lo, m.hi, m.tol) == Class::Within && m.hi.is_finite());
        if !certified {
            continue;
        }
        exported += 1;
        let name = claim.kind.name();
        let mut parts = vec![];
        for (k, chunk) in trail.marks.chunks(CHUNK).enumerate() {
            let rows: Vec<String> = chunk
                .iter()
                .map(|m| {
                    let (hm, tm, e) = common_exponent(m.hi, m.tol);
                    format!("⟨{}, {hm}, {tm}, {e}⟩", m.step)
                })
                .collect();
            let _ = writeln!(out, "\nnoncomputable def {name}_{k} : List Mark := [\n  {}]", rows.join(",\n  "));
            // decided a chunk at a time: the kernel's memory is per declaration
            let _ = writeln!(out, "theorem {name}_{k}_ok : {name}_{k}.all Mark.ok = true := by decide +kernel");
            parts.push(format!("{name}_{k}"));
        }
        let steps = trail.marks.len();
        // joined by one term per chunk: `simp` over an append chain of a long trail took Lean
        // past 10 GB
        let checked = parts.iter().rev().fold("rfl".to_string(), |acc, p| format!("Mark.chunk {p}_ok ({acc})"));
        let _ = writeln!(
            out,
            "\nnoncomputable def {name}_chunks : List (List Mark) := [{}]\n\n\
             /-- Every checkpoint of `{name}` ({steps} of them), as the checker certified it. -/\n\
             noncomputable def {name} : List Mark := {name}_chunks.flatten\n\n\
             theorem {name}_checked : {name}_chunks.all (fun l => l.all Mark.ok) = true :=\n  {checked}\n\n\
             /-- {name} holds at every checkpoint of the run: the deviation's certified upper bound\n\
             is within the tolerance, and so is every value it bounds (`Mark.bounds`). -/\n\
             theorem {name}_holds : ∀ m ∈ {name}, m.hi ≤ m.tol := Mark.flatten_ok {name}_checked",
            parts.join(", "),
        );
    }
    if exported == 0 {
        return Err(format!("the certificate of {} has no certified claim with checkpoints to export", cert.scene));
    }
    Ok(out + &format!("\nend Lagra.Generated.{space}\n"))
}

/// `lj_liquid` → `LjLiquid`.
fn lean_name(scene: &str) -> String {
    scene
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| w[..1].to_ascii_uppercase() + &w[1..])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The exact rational printed for a binary64 value parses back, by rug, to that value.
        #[test]
        fn exact_is_exact(c in any::<f64>().prop_filter("finite", |c| c.is_finite())) {
            let s = exact(c);
            let digits: Vec<&str> = s.split(|ch: char| !(ch.is_ascii_digit() || ch == '-')).filter(|w| !w.is_empty() && *w != "-").collect();
            let value = match digits.as_slice() {
                [n] => rug::Rational::from(n.parse::<Integer>().unwrap()),
                [n, d] => rug::Rational::from((n.parse::<Integer>().unwrap(), d.parse::<Integer>().unwrap())),
                _ => panic!("{s}"),
            };
            prop_assert_eq!(value, rug::Rational::from_f64(c).unwrap());
        }

        /// Over their common exponent two values are the same rationals, and compare as the
        /// binary64 values do: what `Mark.ok` decides is the checker's comparison.
        #[test]
        fn a_common_exponent_keeps_values_and_order(
            a in any::<f64>().prop_filter("finite", |c| c.is_finite()),
            b in prop_oneof![Just(0.0), any::<f64>().prop_filter("finite", |c| c.is_finite())],
        ) {
            let (am, bm, e) = common_exponent(a, b);
            let two_e = rug::Rational::from(Integer::from(1) << 1100u32) >> (1100 - e) as u32;
            prop_assert_eq!(rug::Rational::from(am.clone()) * &two_e, rug::Rational::from_f64(a).unwrap());
            prop_assert_eq!(rug::Rational::from(bm.clone()) * &two_e, rug::Rational::from_f64(b).unwrap());
            prop_assert_eq!(am <= bm, a <= b);
        }
    }

    #[test]
    fn a_cutoff_becomes_an_if_and_sqrt_stays_uninterpreted() {
        let (lj, rational) = potential(Kind::LennardJones);
        assert!(rational && lj.starts_with("(if ") && lj.contains(" < "), "{lj}");
        let (bond, rational) = potential(Kind::HarmonicBond);
        assert!(!rational && bond.contains("Lagra.sqrt"), "{bond}");
        assert_eq!(exact(0.5), "((1 : Rat) / 2)");
        assert_eq!(exact(-3.0), "(-3 : Rat)");
    }

    /// A parameter named like a binder of the theorems would be captured by it (Morse's `a` once
    /// was, by the translation's `a b c`), and the theorem would say less than it seems to.
    #[test]
    fn no_parameter_is_shadowed_by_a_binder() {
        for &kind in Kind::ALL {
            for p in parameter_names(kind) {
                assert!(!BINDERS.contains(&p.as_str()), "{}: parameter {p} is also a binder", kind.name());
            }
        }
        assert!(invariance().contains("(D a r0 : Rat) (dx dy dz : Rat)"));
    }

    #[test]
    fn scene_names_become_lean_names() {
        assert_eq!(lean_name("lj_liquid"), "LjLiquid");
        assert_eq!(lean_name("oscillator"), "Oscillator");
    }
}
