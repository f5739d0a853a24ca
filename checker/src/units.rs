//! Dimensions as types: exponents of mass, length, time and charge.
//!
//! [`Dim`] is the type of a quantity. [`Dimension`] is a [`Real`] whose "value" is a dimension,
//! so that evaluating a term's one definition over it *proves* the definition homogeneous: every
//! sum adds like to like, every square root has even exponents, and the result is an energy.

use crate::real::Real;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Exponents of M, L, T, Q (charge).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Serialize, Deserialize)]
pub struct Dim(pub [i8; 4]);

impl Dim {
    pub const NONE: Dim = Dim([0, 0, 0, 0]);
    pub const MASS: Dim = Dim([1, 0, 0, 0]);
    pub const LENGTH: Dim = Dim([0, 1, 0, 0]);
    pub const TIME: Dim = Dim([0, 0, 1, 0]);
    pub const CHARGE: Dim = Dim([0, 0, 0, 1]);
    pub const VELOCITY: Dim = Dim([0, 1, -1, 0]);
    pub const ACCELERATION: Dim = Dim([0, 1, -2, 0]);
    pub const ENERGY: Dim = Dim([1, 2, -2, 0]);
    pub const STIFFNESS: Dim = Dim([1, 0, -2, 0]);
    pub const DAMPING: Dim = Dim([1, 0, -1, 0]);
    pub const GRAVITATIONAL: Dim = Dim([-1, 3, -2, 0]);
    pub const INVERSE_LENGTH: Dim = Dim([0, -1, 0, 0]);
    /// Energy × length: the strength of a 1/r potential between neutral bodies.
    pub const ENERGY_LENGTH: Dim = Dim([1, 3, -2, 0]);
    /// Coulomb's constant: energy × length / charge².
    pub const COULOMB: Dim = Dim([1, 3, -2, -2]);
    /// Electric field: force / charge.
    pub const ELECTRIC: Dim = Dim([1, 1, -2, -1]);
    /// Magnetic field: force / (charge × velocity); tesla = kg/(s·C).
    pub const MAGNETIC: Dim = Dim([1, 0, -1, -1]);
    /// Mass density, kg/m³.
    pub const DENSITY: Dim = Dim([1, -3, 0, 0]);

    pub fn pow(self, n: i8) -> Dim {
        Dim(self.0.map(|e| e * n))
    }

    /// A name for the common dimensions, used in error messages.
    pub fn describe(self) -> Option<&'static str> {
        const NAMES: [(Dim, &str); 18] = [
            (Dim::DENSITY, "mass/length³"),
            (Dim::MAGNETIC, "magnetic field"),
            (Dim::INVERSE_LENGTH, "1/length"),
            (Dim::ENERGY_LENGTH, "energy·length"),
            (Dim::COULOMB, "energy·length/charge²"),
            (Dim::ELECTRIC, "force/charge"),
            (Dim::NONE, "dimensionless"),
            (Dim::MASS, "mass"),
            (Dim::LENGTH, "length"),
            (Dim::TIME, "time"),
            (Dim::CHARGE, "charge"),
            (Dim::VELOCITY, "velocity"),
            (Dim::ACCELERATION, "acceleration"),
            (Dim::ENERGY, "energy"),
            (Dim::STIFFNESS, "energy/length²"),
            (Dim::DAMPING, "mass/time"),
            (Dim::GRAVITATIONAL, "length³/(mass·time²)"),
            (Dim([1, 1, -2, 0]), "force (energy/length)"),
        ];
        NAMES.iter().find(|(d, _)| *d == self).map(|(_, n)| *n)
    }
}

impl Mul for Dim {
    type Output = Dim;
    fn mul(self, o: Dim) -> Dim {
        Dim(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl Div for Dim {
    type Output = Dim;
    fn div(self, o: Dim) -> Dim {
        Dim(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}

impl fmt::Display for Dim {
    /// `M·L²·T⁻²`; the dimensionless type prints as `1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
        let mut parts = Vec::new();
        for (sym, &e) in ["M", "L", "T", "Q"].iter().zip(&self.0) {
            if e == 0 {
                continue;
            }
            let mut s = sym.to_string();
            if e != 1 {
                if e < 0 {
                    s.push('⁻');
                }
                for c in e.unsigned_abs().to_string().chars() {
                    s.push(SUP[c.to_digit(10).unwrap_or(0) as usize]);
                }
            }
            parts.push(s);
        }
        if parts.is_empty() {
            write!(f, "1")
        } else {
            write!(f, "{}", parts.join("·"))
        }
    }
}

/// A dimension computed through a definition, or the first inhomogeneity met on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct Dimension(pub Result<Dim, String>);

impl Dimension {
    pub fn of(d: Dim) -> Self {
        Dimension(Ok(d))
    }
    fn zip(self, o: Self, f: impl FnOnce(Dim, Dim) -> Result<Dim, String>) -> Self {
        Dimension(self.0.and_then(|a| o.0.and_then(|b| f(a, b))))
    }
    fn same(self, o: Self, op: &str) -> Self {
        self.zip(o, |a, b| if a == b { Ok(a) } else { Err(format!("{op} of {a} and {b}")) })
    }
}

impl Add for Dimension {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        self.same(o, "sum")
    }
}
impl Sub for Dimension {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        self.same(o, "difference")
    }
}
impl Mul for Dimension {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| Ok(a * b))
    }
}
impl Div for Dimension {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        self.zip(o, |a, b| Ok(a / b))
    }
}
impl Neg for Dimension {
    type Output = Self;
    fn neg(self) -> Self {
        self
    }
}

impl Real for Dimension {
    /// Literal constants in a definition are pure numbers.
    fn lift(&self, _c: f64) -> Self {
        Dimension::of(Dim::NONE)
    }
    fn sqrt(self) -> Self {
        Dimension(self.0.and_then(|d| {
            if d.0.iter().all(|e| e % 2 == 0) {
                Ok(Dim(d.0.map(|e| e / 2)))
            } else {
                Err(format!("square root of {d}"))
            }
        }))
    }
    fn powi(self, n: i32) -> Self {
        Dimension(self.0.map(|d| d.pow(n as i8)))
    }
    fn exp(self) -> Self {
        self.pure("exp")
    }
    fn ln(self) -> Self {
        self.pure("ln")
    }
    fn acos(self) -> Self {
        self.pure("acos")
    }
    fn cos(self) -> Self {
        self.pure("cos")
    }
    fn sin(self) -> Self {
        self.pure("sin")
    }
    /// An angle from two lengths of one dimension.
    fn atan2(self, x: Self) -> Self {
        Dimension(self.same(x, "atan2").0.map(|_| Dim::NONE))
    }
    /// A dimension has no value to compare; both branches of a cutoff are checked.
    fn lt(&self, _: &Self) -> Option<bool> {
        None
    }
    fn hull(self, o: Self) -> Self {
        self.same(o, "choice")
    }
}

impl Dimension {
    /// A transcendental function takes and gives pure numbers.
    fn pure(self, f: &str) -> Self {
        Dimension(self.0.and_then(|d| if d == Dim::NONE { Ok(d) } else { Err(format!("{f} of {d}")) }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_uses_superscripts() {
        assert_eq!(Dim::STIFFNESS.to_string(), "M·T⁻²");
        assert_eq!(Dim::GRAVITATIONAL.to_string(), "M⁻¹·L³·T⁻²");
        assert_eq!(Dim::NONE.to_string(), "1");
    }

    #[test]
    fn inhomogeneous_sum_is_caught() {
        let s = Dimension::of(Dim::LENGTH) + Dimension::of(Dim::TIME);
        assert_eq!(s.0, Err("sum of L and T".into()));
    }

    #[test]
    fn sqrt_needs_even_exponents() {
        assert_eq!(Dimension::of(Dim::LENGTH.pow(2)).sqrt().0, Ok(Dim::LENGTH));
        assert!(Dimension::of(Dim::LENGTH).sqrt().0.is_err());
    }
}
