//! Verdicts as one line of text each; `lagra run` and a re-check print the same lines.

use crate::claims::{Claim, ClaimKind};
use crate::decision::{Precision, Verdict, BINARY64, PARTS};
use crate::terms::Kind;

/// `x` in scientific notation with a two-digit exponent (`1e-05`), exactly as given.
pub fn sci(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let s = format!("{x:e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.unsigned_abs())
}

/// `interval` for binary64 intervals, `mpfr N` for MPFR intervals of N bits.
pub fn method(p: Precision) -> String {
    match p {
        BINARY64 => "interval".into(),
        PARTS => "interval, the ranks' parts added".into(),
        p => format!("mpfr {p}"),
    }
}

/// `x` with two significant digits, rounded *up*, so a printed bound is still a bound.
pub fn up(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let s = format!("{x:.1e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let (mut m, mut e): (f64, i32) = (m.parse().unwrap_or(x), e.parse().unwrap_or(0));
    if m * 10f64.powi(e) < x {
        m = (m * 10.0 + 1.0).round() / 10.0;
        if m >= 10.0 {
            (m, e) = (m / 10.0, e + 1);
        }
    }
    format!("{m:.1}e{}{:02}", if e < 0 { '-' } else { '+' }, e.unsigned_abs())
}

/// The quantity a claim bounds, as printed: e.g. `|ΔH|/|H₀|`; H′ is a thermostat's extended
/// energy.
fn measure(kind: ClaimKind, balance: bool, extended: bool) -> &'static str {
    match kind {
        ClaimKind::EnergyConservation if balance && extended => "|H′+Q−H′₀|/|H′₀|",
        ClaimKind::EnergyConservation if balance => "|H+Q−H₀|/|H₀|",
        ClaimKind::EnergyConservation if extended => "|ΔH′|/|H′₀|",
        ClaimKind::EnergyConservation => "|ΔH|/|H₀|",
        ClaimKind::MomentumConservation => "|ΔP|",
        ClaimKind::AngularMomentumConservation => "|ΔL|",
        ClaimKind::Distance => "max(min−d, d−max)",
        ClaimKind::ConstraintSatisfied => "|d−ℓ|/ℓ",
        ClaimKind::Resting => " point speed",
        ClaimKind::NoPenetration => " depth",
        ClaimKind::JointSatisfied => " gap",
        ClaimKind::DimensionalConsistency => "",
    }
}

/// The verdict line of every claim, in the order of the claims: what `lagra run` prints and
/// what a re-check must reproduce. `dissipators` name the terms an energy balance accounts for;
/// `extended`: the energy is a thermostat's extended H′ = H + the chain's share.
pub fn lines(verdicts: &[Verdict], claims: &[Claim], dissipators: &[Kind], extended: bool) -> Vec<String> {
    let names: Vec<&str> = dissipators.iter().map(|k| k.name()).collect();
    verdicts
        .iter()
        .zip(claims)
        .map(|(v, c)| line(v, c, if c.kind == ClaimKind::EnergyConservation { &names } else { &[] }, extended))
        .collect()
}

/// One verdict line.
fn line(v: &Verdict, c: &Claim, balance: &[&str], extended: bool) -> String {
    let name = c.label();
    let extended = extended && c.kind == ClaimKind::EnergyConservation;
    let q = measure(c.kind, !balance.is_empty(), extended);
    let tol = |t: f64| match (c.kind, c.tol) {
        (ClaimKind::Distance, _) => "0".to_string(),
        (_, Some(_)) => format!("tol {}", sci(t)),
        (_, None) => format!("round-off budget {}", up(t)),
    };
    let mut via = if balance.is_empty() { String::new() } else { format!(", Q dissipated by {}", balance.join(", ")) };
    if extended {
        via += ", H′ = H + the Nosé–Hoover chain's energy";
    }
    match (v, &c.between) {
        (Verdict::Pass(_), _) if c.kind == ClaimKind::DimensionalConsistency => {
            format!("{name} PASS  every term is homogeneous and energy-valued")
        }
        // The bound is −(the margin), rounded up: so the printed margin is rounded down.
        (Verdict::Pass(p), Some(b)) => format!(
            "{name} PASS  stays in [{}, {}] with margin ≥ {} certified ({}) over {} checkpoints",
            b.min,
            b.max,
            up(p.bound()).trim_start_matches('-'),
            method(p.precision()),
            p.checkpoints()
        ),
        (Verdict::Pass(p), None) => format!(
            "{name} PASS  max{q} ≤ {} certified ({}) over {} checkpoints ({}{via})",
            up(p.bound()),
            method(p.precision()),
            p.checkpoints(),
            tol(p.tol())
        ),
        (Verdict::Fail(b), _) => {
            format!("{name} FAIL  at step {}: {q} ∈ [{}, {}] > {}{via}", b.step, sci(b.lower), up(b.upper), tol(b.tol))
        }
        // the judge's record of a claim that saw no checkpoint (the run stopped before its first)
        (Verdict::Undecided(b), _) if b.lower.is_nan() && b.step == 0 => {
            format!("{name} UNDECIDED  no checkpoint was judged: the run stopped before its first")
        }
        (Verdict::Undecided(b), _) if b.lower.is_nan() => {
            format!("{name} UNDECIDED  at step {}: the quantity could not be enclosed", b.step)
        }
        (Verdict::Undecided(b), _) => format!(
            "{name} UNDECIDED  at step {}: {q} ∈ [{}, {}] straddles {}{via}, even at {}",
            b.step,
            sci(b.lower),
            up(b.upper),
            tol(b.tol),
            method(b.precision)
        ),
        (Verdict::Refuted { reason, .. }, _) => format!("{name} FAIL  {reason}"),
    }
}

#[cfg(test)]
mod tests {
    use super::{sci, up};

    #[test]
    fn exact_values_keep_every_digit() {
        assert_eq!(sci(1e-5), "1e-05");
        assert_eq!(sci(1.0090128104926887e-5), "1.0090128104926887e-05");
        assert_eq!(sci(0.0), "0");
    }

    #[test]
    fn printed_bounds_round_up() {
        assert_eq!(up(2.1e-7), "2.1e-07");
        assert_eq!(up(2.11e-7), "2.2e-07");
        assert_eq!(up(9.96), "1.0e+01");
        assert_eq!(up(1e-5), "1.0e-05");
        for x in [1.234567e-9, 3.33333e3, 0.99999, 7.0000001] {
            assert!(up(x).parse::<f64>().unwrap() >= x, "{x}");
        }
    }
}
