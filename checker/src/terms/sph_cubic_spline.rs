//! The Tait fluid of `sph` smoothed by the cubic spline instead of Wendland's C² (`sph { kernel:
//! cubic_spline, .. }`): the same Lagrangian and viscosity (`sph`), another W (`smoothing`).

use super::smoothing::CubicSpline;
use super::sph::TaitFluid;

pub type SphCubicSpline = TaitFluid<CubicSpline>;
