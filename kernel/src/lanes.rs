//! The number type a pair term's formula is written for: `f64` for one pair, `F64x4` for four
//! pairs at once in the cluster kernel (`clusters`). One formula per term, compiled twice.
//!
//! `F64x4` is four binary64 lanes with element-wise IEEE operations (`wide`'s f64x4), so lane k
//! of any formula is bit for bit the scalar formula on lane k's input (a test holds every pair
//! term to it). The build's baseline already has AVX and FMA (inari needs FMA, which implies
//! AVX: `.cargo/config.toml`), so each operation is one 256-bit instruction on every machine
//! that runs this build; a build without AVX gets `wide`'s SSE2 or portable code, with the same
//! bits. (No runtime switch is needed for that: a machine without FMA cannot run Lagra at all.)
//! Where the CPU has AVX-512, the cluster kernels take two rows a register instead
//! (`lanes8::F64x8`, `forces::pipelined`), each lane still the scalar formula: the same bits.

use std::ops::{Add, BitAnd, Div, Mul, Neg, Sub};
use wide::f64x4;

/// What a term's radial formula may use: the four operations (with an `f64` constant on the
/// right of `*`, `+` and `-`), splat, square root, exponential and fused multiply-add (one
/// rounding, the same in every lane type: the build has FMA).
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
{
    fn splat(x: f64) -> Self;
    fn sqrt(self) -> Self;
    fn exp(self) -> Self;
    /// self·a + b, rounded once.
    fn mul_add(self, a: Self, b: Self) -> Self;
}

/// |d|², as every pair loop computes it: d₂² + (d₁² + d₀²), two of the three products fused.
#[inline(always)]
pub fn norm2<L: Lane>(d: &[L; 3]) -> L {
    d[2].mul_add(d[2], d[1].mul_add(d[1], d[0] * d[0]))
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn exp(self) -> f64 {
        f64::exp(self)
    }
    #[inline(always)]
    fn mul_add(self, a: f64, b: f64) -> f64 {
        f64::mul_add(self, a, b)
    }
}

/// Four lanes: `wide`'s f64x4, one AVX register where the build has AVX (the baseline here),
/// two SSE2 registers or an array elsewhere.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F64x4(f64x4);

/// A lane-wise truth value, from a comparison (all bits set where true).
#[derive(Clone, Copy, Debug)]
pub struct Mask4(f64x4);

macro_rules! lanewise {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for F64x4 {
            type Output = F64x4;
            #[inline(always)]
            fn $f(self, o: F64x4) -> F64x4 {
                F64x4(self.0 $op o.0)
            }
        }
        impl $trait<f64> for F64x4 {
            type Output = F64x4;
            #[inline(always)]
            fn $f(self, o: f64) -> F64x4 {
                F64x4(self.0 $op f64x4::splat(o))
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Neg for F64x4 {
    type Output = F64x4;
    #[inline(always)]
    fn neg(self) -> F64x4 {
        F64x4(-self.0)
    }
}

impl Lane for F64x4 {
    #[inline(always)]
    fn splat(x: f64) -> F64x4 {
        F64x4(f64x4::splat(x))
    }
    #[inline(always)]
    fn sqrt(self) -> F64x4 {
        F64x4(self.0.sqrt())
    }
    /// Lane by lane through the scalar exp, for the scalar formula's bits (`wide`'s own exp is
    /// a different polynomial; no term with a finite reach, the only ones the cluster kernel
    /// runs, calls it today).
    #[inline(always)]
    fn exp(self) -> F64x4 {
        F64x4::new(self.to_array().map(f64::exp))
    }
    #[inline(always)]
    fn mul_add(self, a: F64x4, b: F64x4) -> F64x4 {
        F64x4(self.0.mul_add(a.0, b.0))
    }
}

impl F64x4 {
    #[inline(always)]
    pub fn new(a: [f64; 4]) -> F64x4 {
        F64x4(f64x4::new(a))
    }
    #[inline(always)]
    pub fn to_array(self) -> [f64; 4] {
        self.0.to_array()
    }
    #[inline(always)]
    pub fn lane(&self, k: usize) -> f64 {
        self.0.as_array()[k]
    }
    /// b − self·a, rounded once.
    #[inline(always)]
    pub fn mul_neg_add(self, a: F64x4, b: F64x4) -> F64x4 {
        F64x4(self.0.mul_neg_add(a.0, b.0))
    }
    #[inline(always)]
    pub fn lt(self, o: F64x4) -> Mask4 {
        Mask4(self.0.simd_lt(o.0))
    }
    #[inline(always)]
    pub fn min(self, o: F64x4) -> F64x4 {
        F64x4(self.0.fast_min(o.0))
    }
    /// The lanes' sum in a fixed order, (a₀ + a₁) + (a₂ + a₃), whatever the build.
    #[inline(always)]
    pub fn sum(self) -> f64 {
        let a = self.to_array();
        (a[0] + a[1]) + (a[2] + a[3])
    }
}

impl Mask4 {
    pub fn new(m: [bool; 4]) -> Mask4 {
        Mask4(f64x4::new(m.map(|b| f64::from_bits(if b { u64::MAX } else { 0 }))))
    }
    /// `x` where the mask holds, 0 elsewhere (whatever x is there, NaN included).
    #[inline(always)]
    pub fn and(self, x: F64x4) -> F64x4 {
        F64x4(self.0 & x.0)
    }
    /// Whether any lane holds.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.any()
    }
}

impl BitAnd for Mask4 {
    type Output = Mask4;
    #[inline(always)]
    fn bitand(self, o: Mask4) -> Mask4 {
        Mask4(self.0 & o.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mask_keeps_its_lanes_and_clears_the_rest_nan_included() {
        let a = F64x4::new([1.0, 2.0, 3.0, f64::NAN]);
        assert_eq!(a.lt(F64x4::splat(2.5)).and(a).to_array(), [1.0, 2.0, 0.0, 0.0]);
        let m = Mask4::new([true, false, true, true]) & a.lt(F64x4::splat(3.5));
        assert_eq!(m.and(a).to_array(), [1.0, 0.0, 3.0, 0.0]);
        assert!(m.any() && !a.lt(F64x4::splat(0.5)).any());
    }

    #[test]
    fn the_lanes_sum_in_a_fixed_order() {
        let a = F64x4::new([1e16, 1.0, -1e16, 1.0]);
        assert_eq!(a.sum(), (1e16 + 1.0) + (-1e16 + 1.0));
    }
}
