#pragma once
/// SPH kernels with a per-pair support radius H_ij = (H_i + H_j) / 2 (symmetric, so pair forces stay
/// antisymmetric across resolutions). Support radius H is the distance at which the kernel reaches zero.

#include <cmath>

#include "sim/types.h"

namespace fp::sim {

/// Cubic spline (Monaghan 1992) in 3D, written in terms of the support radius H (q = r / H in [0, 1]).
struct CubicSpline {
  /// W(r, H) [1/m^3]; zero for r >= H
  static Real w(Real r, Real H) {
    const Real invH = Real(1) / H;
    return wScaled(r, invH, factor(invH));
  }

  /// (8 / pi) / H^3 from 1 / H, rounded as w() rounds it
  static Real factor(Real invH) { return Real(8.0 / kPi) * invH * invH * invH; }

  /// W(r, H) from 1 / H and factor(1 / H): the same value, bit for bit, for callers that evaluate many
  /// distances with one support
  static Real wScaled(Real r, Real invH, Real k) {
    const Real q = r * invH;
    if (q <= Real(0.5))
      return k * (Real(6) * q * q * (q - Real(1)) + Real(1));
    if (q < Real(1)) {
      const Real t = Real(1) - q;
      return k * Real(2) * t * t * t;
    }
    return Real(0);
  }

  /// W(0, H), the self contribution
  static Real w0(Real H) { return Real(8.0 / kPi) / (H * H * H); }

  /// s such that grad_i W(x_i - x_j, H) = s * (x_i - x_j), given r = |x_i - x_j| [1/m^5]; zero at r = 0 and r
  /// >= H
  static Real gradFactor(Real r, Real H) {
    const Real invH = Real(1) / H;
    const Real q = r * invH;
    if (q >= Real(1) || r <= Real(1e-9) * H)
      return Real(0);
    const Real l = Real(48.0 / kPi) * invH * invH * invH;
    // d W / d r divided by r, so the caller multiplies by the difference vector without normalising it
    const Real invRH = invH / r;
    if (q <= Real(0.5))
      return l * q * (Real(3) * q - Real(2)) * invRH;
    const Real t = Real(1) - q;
    return -l * t * t * invRH;
  }

  /// W(r, H) and gradFactor(r, H) in one evaluation
  static void evaluate(Real r, Real H, Real& w, Real& gradFactor) {
    const Real invH = Real(1) / H;
    const Real q = r * invH;
    const Real invH3 = invH * invH * invH;
    if (q >= Real(1)) {
      w = 0;
      gradFactor = 0;
      return;
    }
    const Real k = Real(8.0 / kPi) * invH3;
    const Real l = Real(48.0 / kPi) * invH3;
    const Real invRH = r > Real(1e-9) * H ? invH / r : Real(0);
    if (q <= Real(0.5)) {
      w = k * (Real(6) * q * q * (q - Real(1)) + Real(1));
      gradFactor = l * q * (Real(3) * q - Real(2)) * invRH;
    } else {
      const Real t = Real(1) - q;
      w = k * Real(2) * t * t * t;
      gradFactor = -l * t * t * invRH;
    }
  }

  /// gradient of W(x, H) with respect to x
  static Vec3 grad(const Vec3& x, Real H) { return gradFactor(x.norm(), H) * x; }
};

/// Symmetric pair support radius.
inline Real pairSupport(Real Hi, Real Hj) {
  return Real(0.5) * (Hi + Hj);
}

}  // namespace fp::sim
