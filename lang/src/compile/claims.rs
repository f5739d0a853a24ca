//! Claims: `@expect` blocks, each checked against what its kind takes, and the claims a
//! Langevin bath refuses.

use super::{err, Compiler};
use crate::block::{value_span, word, Block, Field};
use crate::diagnostic::{Diagnostic, Span};
use crate::scene::NoetherRequest;
use crate::Pair;
use lagra_checker::claims::{Between, Claim, ClaimKind};
use lagra_checker::units::Dim;

impl<'a> Compiler<'a> {
    pub(super) fn expect(&mut self, name: Pair, mut b: Block) -> Result<(), Diagnostic> {
        let at: Span = name.as_span().into();
        if name.as_str() == "noether" {
            return self.noether(at, b);
        }
        let kind = ClaimKind::from_name(name.as_str()).ok_or_else(|| {
            let known: Vec<_> = ClaimKind::ALL.iter().map(|k| k.name()).chain(["noether"]).collect();
            Diagnostic::new(at, format!("unknown claim `{}`; known claims: {}", name.as_str(), known.join(", ")))
        })?;
        if !kind.repeatable() && self.claims.iter().any(|c| c.kind == kind) {
            return err(at, format!("{} is declared twice", kind.name()));
        }
        let owner = kind.name();
        let mut claim = Claim::new(kind, None, 1);
        // a resting claim's tolerance is a speed, written `max_speed`
        let tol_name = if kind == ClaimKind::Resting { "max_speed" } else { "tol" };
        if let (Some(f), Some(dim)) = (b.take(tol_name), kind.tol_dim()) {
            claim.tol = Some(self.rd.positive(&f, owner, dim)?);
        }
        if kind.needs_tol() && claim.tol.is_none() {
            let example = match kind {
                ClaimKind::Resting => "`{ max_speed: 0.01, after: 2 }` (a speed, a time)",
                ClaimKind::NoPenetration | ClaimKind::JointSatisfied => "`{ tol: 0.001 }` (a length)",
                _ => "`{ tol: 1e-5 }` (relative)",
            };
            return err(at, format!("{owner} needs a tolerance: {example}"));
        }
        if kind == ClaimKind::Resting {
            if let Some(f) = b.take("after") {
                let t = self.rd.numbers(&f, owner, Dim::TIME, 1)?[0];
                if !(t >= 0.0) {
                    return err(value_span(&f), format!("resting.after must be a time ≥ 0, got {t}"));
                }
                claim.after = Some(t);
            }
        }
        if kind.is_dynamic() {
            if let Some(f) = b.take("every") {
                claim.every = self.rd.count(&f, owner)?;
            }
        }
        let mut allowed = match kind {
            ClaimKind::DimensionalConsistency => vec![],
            ClaimKind::Distance => vec!["between", "min", "max", "every"],
            ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation => vec!["tol", "every", "axes"],
            ClaimKind::EnergyConservation
            | ClaimKind::ConstraintSatisfied
            | ClaimKind::NoPenetration
            | ClaimKind::JointSatisfied => {
                vec!["tol", "every"]
            }
            ClaimKind::Resting => vec!["every"],
        };
        if allowed.contains(&"axes") {
            if let Some(f) = b.take("axes") {
                claim.axes = Some(axes(&f, owner)?);
            }
        }
        if kind == ClaimKind::Distance {
            let pair = b.take("between").ok_or_else(|| Diagnostic::new(at, "distance needs `between: [i, j]`"))?;
            let bodies = self.rd.indices(&pair, owner, 2)?;
            let mut bound = |name: &str| -> Result<f64, Diagnostic> {
                let f =
                    b.take(name).ok_or_else(|| Diagnostic::new(at, format!("distance needs `{name}` (a length)")))?;
                let x = self.rd.numbers(&f, owner, Dim::LENGTH, 1)?[0];
                if x < 0.0 {
                    return err(value_span(&f), format!("distance.{name} must not be negative"));
                }
                Ok(x)
            };
            let (min, max) = (bound("min")?, bound("max")?);
            if min > max {
                return err(at, format!("distance: min {min} is above max {max}"));
            }
            if bodies[0].0 == bodies[1].0 {
                return err(bodies[1].1, "distance needs two different bodies");
            }
            claim.between = Some(Between { bodies: [bodies[0].0, bodies[1].0], min, max });
            self.indices.push(bodies);
            allowed.clear();
        }
        b.check_names(owner, &allowed)?;
        self.claims.push(claim);
        self.claim_spans.push(at);
        Ok(())
    }

    /// `@expect noether { tol, every }`.
    fn noether(&mut self, at: Span, mut b: Block) -> Result<(), Diagnostic> {
        if self.noether.is_some() {
            return err(at, "noether is declared twice");
        }
        let tol = b.take("tol").map(|f| self.rd.positive(&f, "noether", Dim::NONE)).transpose()?;
        let every = b.take("every").map(|f| self.rd.count(&f, "noether")).transpose()?.unwrap_or(1);
        b.check_names("noether", &["tol", "every"])?;
        self.noether = Some(NoetherRequest { at, tol, every });
        Ok(())
    }
}

/// A Langevin bath exchanges energy and momentum with the bodies at random: the claims that
/// they are conserved cannot hold, and the checker would have no record of the noise to state
/// the balance with, so they are refused where they are declared.
pub(super) fn refuse_under_langevin(
    claims: &[Claim],
    at: &[Span],
    noether: &Option<NoetherRequest>,
) -> Result<(), Diagnostic> {
    let why = "a Langevin thermostat exchanges energy and momentum with its bath at random, so it cannot be conserved; remove the claim, or use `thermostat nose_hoover`, whose extended energy is certified";
    for (c, s) in claims.iter().zip(at) {
        if matches!(
            c.kind,
            ClaimKind::EnergyConservation | ClaimKind::MomentumConservation | ClaimKind::AngularMomentumConservation
        ) {
            return err(*s, format!("{}: {why}", c.kind.name()));
        }
    }
    if let Some(n) = noether {
        return err(n.at, format!("noether: {why}"));
    }
    Ok(())
}

/// `axes: "xz"`: the momentum components a claim is about.
fn axes(f: &Field, owner: &str) -> Result<[bool; 3], Diagnostic> {
    let (text, at) = word(f, owner)?;
    let mut a = [false; 3];
    for c in text.chars() {
        match "xyz".find(c) {
            Some(i) if !a[i] => a[i] = true,
            _ => return err(at, format!("{owner}.axes takes some of x, y, z once each, got `{text}`")),
        }
    }
    if a == [false; 3] {
        return err(at, format!("{owner}.axes names no axis"));
    }
    Ok(a)
}
