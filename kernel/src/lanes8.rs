//! Eight binary64 lanes in one AVX-512 register, for the cluster kernel's AVX-512 build
//! (`forces::pipelined`): a cluster pair's sixteen body pairs as two of them.
//!
//! Every operation is the IEEE operation lane by lane, as `F64x4`'s are, so lane k of a term's
//! formula is bit for bit the scalar formula on lane k's input (a test holds every pair term to
//! it on a CPU that has AVX-512).
//!
//! The type exists only for code compiled for AVX-512 and entered after the CPU was seen to
//! have it (`std::is_x86_feature_detected!`): that is the invariant the `unsafe` blocks below
//! rest on. It is private to the crate, and only `forces::pipelined` and the tests make one.

use crate::lanes::{F64x4, Lane};
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug)]
pub(crate) struct F64x8(pub(crate) __m512d);

macro_rules! lanewise {
    ($trait:ident, $f:ident, $intrinsic:ident) => {
        impl $trait for F64x8 {
            type Output = F64x8;
            #[inline(always)]
            fn $f(self, o: F64x8) -> F64x8 {
                // SAFETY: an F64x8 exists only where the CPU has AVX-512 (the module's invariant)
                F64x8(unsafe { $intrinsic(self.0, o.0) })
            }
        }
        impl $trait<f64> for F64x8 {
            type Output = F64x8;
            #[inline(always)]
            fn $f(self, o: f64) -> F64x8 {
                self.$f(F64x8::splat(o))
            }
        }
    };
}
lanewise!(Add, add, _mm512_add_pd);
lanewise!(Sub, sub, _mm512_sub_pd);
lanewise!(Mul, mul, _mm512_mul_pd);
lanewise!(Div, div, _mm512_div_pd);

impl Neg for F64x8 {
    type Output = F64x8;
    /// The sign bit flipped, as `F64x4`'s negation does (so −(+0) is −0).
    #[inline(always)]
    fn neg(self) -> F64x8 {
        // SAFETY: as above
        unsafe {
            let sign = _mm512_set1_epi64(i64::MIN);
            F64x8(_mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(self.0), sign)))
        }
    }
}

impl Lane for F64x8 {
    #[inline(always)]
    fn splat(x: f64) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_set1_pd(x) })
    }
    #[inline(always)]
    fn sqrt(self) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_sqrt_pd(self.0) })
    }
    /// Lane by lane through the scalar exp, as `F64x4`'s.
    #[inline(always)]
    fn exp(self) -> F64x8 {
        F64x8::new(self.to_array().map(f64::exp))
    }
    #[inline(always)]
    fn mul_add(self, a: F64x8, b: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_fmadd_pd(self.0, a.0, b.0) })
    }
}

impl F64x8 {
    #[inline(always)]
    pub(crate) fn new(a: [f64; 8]) -> F64x8 {
        // SAFETY: as above; `a` is eight f64
        F64x8(unsafe { _mm512_loadu_pd(a.as_ptr()) })
    }
    #[inline(always)]
    pub(crate) fn to_array(self) -> [f64; 8] {
        let mut a = [0.0; 8];
        // SAFETY: as above; `a` holds eight f64
        unsafe { _mm512_storeu_pd(a.as_mut_ptr(), self.0) };
        a
    }
    /// Four lanes twice over: [x, x].
    #[inline(always)]
    pub(crate) fn twice(x: F64x4) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_broadcast_f64x4(m256(x)) })
    }
    /// Lanes a and a + 1 of x, each four times over: [xₐ ×4, xₐ₊₁ ×4] (a even).
    #[inline(always)]
    pub(crate) fn rows(x: F64x4, a: usize) -> F64x8 {
        let a = a as i64;
        // SAFETY: as above
        unsafe {
            let pick = _mm512_set_epi64(a + 1, a + 1, a + 1, a + 1, a, a, a, a);
            F64x8(_mm512_permutexvar_pd(pick, _mm512_castpd256_pd512(m256(x))))
        }
    }
    /// The low four lanes and the high four.
    #[inline(always)]
    pub(crate) fn halves(self) -> [F64x4; 2] {
        let a = self.to_array();
        [F64x4::new([a[0], a[1], a[2], a[3]]), F64x4::new([a[4], a[5], a[6], a[7]])]
    }
    /// self · a subtracted from b, rounded once (`F64x4::mul_neg_add`).
    #[inline(always)]
    pub(crate) fn mul_neg_add(self, a: F64x8, b: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_fnmadd_pd(self.0, a.0, b.0) })
    }
    /// The lanes below `r` (an ordered comparison: false where either is NaN), as bits.
    #[inline(always)]
    pub(crate) fn below(self, r: F64x8) -> u8 {
        // SAFETY: as above
        unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, r.0) }
    }
    /// self + x in the lanes of `on`, self in the others.
    #[inline(always)]
    pub(crate) fn add_on(self, on: u8, x: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_mask_add_pd(self.0, on, self.0, x.0) })
    }
    /// self − x in the lanes of `on`, self in the others.
    #[inline(always)]
    pub(crate) fn sub_on(self, on: u8, x: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_mask_sub_pd(self.0, on, self.0, x.0) })
    }
    /// a·b + self (rounded once) in the lanes of `on`, self in the others.
    #[inline(always)]
    pub(crate) fn mul_add_on(self, on: u8, a: F64x8, b: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_mask3_fmadd_pd(a.0, b.0, self.0, on) })
    }
    /// self − a·b (rounded once) in the lanes of `on`, self in the others.
    #[inline(always)]
    pub(crate) fn mul_sub_on(self, on: u8, a: F64x8, b: F64x8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_mask3_fnmadd_pd(a.0, b.0, self.0, on) })
    }
    /// The lanes in `keep`, +0 elsewhere (whatever was there, NaN included).
    #[inline(always)]
    pub(crate) fn keep(self, keep: u8) -> F64x8 {
        // SAFETY: as above
        F64x8(unsafe { _mm512_maskz_mov_pd(keep, self.0) })
    }
}

#[inline(always)]
fn m256(x: F64x4) -> __m256d {
    let a = x.to_array();
    // SAFETY: as above; `a` is four f64
    unsafe { _mm256_loadu_pd(a.as_ptr()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn avx512() -> bool {
        let has = std::is_x86_feature_detected!("avx512f");
        if !has {
            eprintln!("no AVX-512 on this CPU: F64x8 is never made here");
        }
        has
    }

    #[test]
    fn rows_and_twice_place_the_lanes_as_the_kernel_reads_them() {
        if !avx512() {
            return;
        }
        let x = F64x4::new([1.0, 2.0, 3.0, 4.0]);
        assert_eq!(F64x8::twice(x).to_array(), [1.0, 2.0, 3.0, 4.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(F64x8::rows(x, 2).to_array(), [3.0, 3.0, 3.0, 3.0, 4.0, 4.0, 4.0, 4.0]);
        let [a, b] = F64x8::rows(x, 0).halves();
        assert_eq!((a.to_array(), b.to_array()), ([1.0; 4], [2.0; 4]));
        assert_eq!((-F64x8::splat(0.0)).to_array()[3].to_bits(), (-0.0f64).to_bits());
        let y = F64x8::new([1.0, f64::NAN, 3.0, 0.5, 9.0, 2.0, 2.0, 1.0]);
        assert_eq!(y.below(F64x8::splat(2.0)), 0b1000_1001);
        let (one, two) = (F64x8::splat(1.0), F64x8::splat(2.0));
        assert_eq!(one.add_on(0b0000_0110, two).to_array(), [1.0, 3.0, 3.0, 1.0, 1.0, 1.0, 1.0, 1.0]);
        assert_eq!(one.sub_on(0b1000_0000, two).to_array()[6..], [1.0, -1.0]);
        assert_eq!(one.mul_add_on(0b0000_0001, two, two).to_array()[..2], [5.0, 1.0]);
        assert_eq!(one.mul_sub_on(0b0000_0010, two, two).to_array()[..2], [1.0, -3.0]);
        assert_eq!(y.keep(0b0000_0101).to_array()[..3], [1.0, 0.0, 3.0]);
    }
}
