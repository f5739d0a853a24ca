//! SPH's smoothing kernels W(r, h), both of support 2h, as functions of q = r/h: the density's
//! weights m W and the factor g = −W′(r)/r of the pair forces. A kernel is chosen in the source
//! (`sph { kernel: cubic_spline }`) and each one makes its own term (`Sph`, `SphCubicSpline`),
//! so that a certificate names the kernel its energy was computed with.

use crate::real::{select, Real};

/// W's support, in smoothing lengths.
pub const SUPPORT: f64 = 2.0;

pub trait Smoothing {
    /// The term's name, and the `kernel` value that selects it.
    const NAME: &'static str;
    const KERNEL: &'static str;
    /// m W(0).
    fn own<R: Real>(h: &R, m: R) -> R;
    /// m W(qh) for q < 2: the same bits as `own` at q = 0.
    fn weight<R: Real>(h: &R, m: R, q: R) -> R;
    /// g = −W′(r)/r at r = qh, q < 2.
    fn g<R: Real>(h: &R, q: R) -> R;
}

/// Wendland's C² kernel (Wendland 1995; Dehnen & Aly 2012): W = 21/(16πh³) (1 − q/2)⁴ (2q + 1),
/// smooth to its second derivative at the support and free of the pairing instability.
pub struct WendlandC2;

/// 21/(16π h³): Wendland's W at q = 0.
fn wendland_scale<R: Real>(h: &R) -> R {
    h.lift(21.0) / (h.lift(16.0 * std::f64::consts::PI) * h.clone().powi(3))
}

impl Smoothing for WendlandC2 {
    const NAME: &'static str = "Sph";
    const KERNEL: &'static str = "wendland_c2";

    fn own<R: Real>(h: &R, m: R) -> R {
        m * wendland_scale(h)
    }
    fn weight<R: Real>(h: &R, m: R, q: R) -> R {
        let t = q.lift(1.0) - q.lift(0.5) * q.clone();
        m * wendland_scale(h) * t.powi(4) * (q.lift(2.0) * q.clone() + q.lift(1.0))
    }
    /// W′ = −(5/h) W(0) q (1 − q/2)³, so g = 5 W(0)/h² (1 − q/2)³.
    fn g<R: Real>(h: &R, q: R) -> R {
        let t = q.lift(1.0) - q.lift(0.5) * q;
        h.lift(5.0) * wendland_scale(h) / h.clone().powi(2) * t.powi(3)
    }
}

/// The cubic B-spline (M4) of Monaghan & Lattanzio (1985): W = (1/πh³) (1 − 3q²/2 + 3q³/4) for
/// q < 1 and (1/πh³) (2 − q)³/4 for 1 ≤ q < 2 — the kernel of most SPH codes since, continuous
/// to its second derivative.
pub struct CubicSpline;

/// 1/(π h³): the cubic spline's W at q = 0.
fn spline_scale<R: Real>(h: &R) -> R {
    h.lift(1.0) / (h.lift(std::f64::consts::PI) * h.clone().powi(3))
}

impl Smoothing for CubicSpline {
    const NAME: &'static str = "SphCubicSpline";
    const KERNEL: &'static str = "cubic_spline";

    fn own<R: Real>(h: &R, m: R) -> R {
        m * spline_scale(h)
    }
    /// 1 − q²(3/2 − 3q/4) is exactly 1 at q = 0.
    fn weight<R: Real>(h: &R, m: R, q: R) -> R {
        let near = q.lt(&q.lift(1.0));
        let m = m * spline_scale(h);
        select(
            near,
            || m.clone() * (q.lift(1.0) - q.clone().powi(2) * (q.lift(1.5) - q.lift(0.75) * q.clone())),
            || m.clone() * q.lift(0.25) * (q.lift(2.0) - q.clone()).powi(3),
        )
    }
    /// W′ = (1/πh⁴)(−3q + 9q²/4) inside q = 1 and −(1/πh⁴) 3(2 − q)²/4 beyond, so
    /// g = (1/πh⁵)(3 − 9q/4) and (1/πh⁵) 3(2 − q)²/(4q): both 3/4 at q = 1.
    fn g<R: Real>(h: &R, q: R) -> R {
        let near = q.lt(&q.lift(1.0));
        let k = spline_scale(h) / h.clone().powi(2);
        select(
            near,
            || k.clone() * (q.lift(3.0) - q.lift(2.25) * q.clone()),
            || k.clone() * q.lift(0.75) * (q.lift(2.0) - q.clone()).powi(2) / q.clone(),
        )
    }
}
