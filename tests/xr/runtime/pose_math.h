#pragma once
// Rigid poses for the test runtime, kept free of the project's libraries so the runtime stays a plain shared
// library.
#include <cmath>

namespace fpxr {

struct Vec {
  double x = 0, y = 0, z = 0;
  Vec operator+(const Vec& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec operator-(const Vec& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec operator-() const { return {-x, -y, -z}; }
};
inline Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(const Vec& a, const Vec& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
  Quat normalized() const {
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    return {w / n, x / n, y / n, z / n};
  }
  Quat conjugate() const { return {w, -x, -y, -z}; }
  Quat operator*(const Quat& o) const {
    return {w * o.w - x * o.x - y * o.y - z * o.z, w * o.x + x * o.w + y * o.z - z * o.y,
            w * o.y - x * o.z + y * o.w + z * o.x, w * o.z + x * o.y - y * o.x + z * o.w};
  }
  Vec operator*(const Vec& v) const {
    const Vec u{x, y, z};
    const Vec t = cross(u, v) * 2.0;
    return v + t * w + cross(u, t);
  }
  static Quat axisAngle(const Vec& axis, double angle) {
    const double s = std::sin(0.5 * angle);
    return Quat{std::cos(0.5 * angle), axis.x * s, axis.y * s, axis.z * s}.normalized();
  }
  /// the rotation whose matrix has these columns
  static Quat fromColumns(const Vec& c0, const Vec& c1, const Vec& c2) {
    const double m00 = c0.x, m11 = c1.y, m22 = c2.z, tr = m00 + m11 + m22;
    Quat q;
    if (tr > 0) {
      const double s = std::sqrt(tr + 1.0) * 2;
      q = {0.25 * s, (c1.z - c2.y) / s, (c2.x - c0.z) / s, (c0.y - c1.x) / s};
    } else if (m00 > m11 && m00 > m22) {
      const double s = std::sqrt(1.0 + m00 - m11 - m22) * 2;
      q = {(c1.z - c2.y) / s, 0.25 * s, (c1.x + c0.y) / s, (c2.x + c0.z) / s};
    } else if (m11 > m22) {
      const double s = std::sqrt(1.0 + m11 - m00 - m22) * 2;
      q = {(c2.x - c0.z) / s, (c1.x + c0.y) / s, 0.25 * s, (c2.y + c1.z) / s};
    } else {
      const double s = std::sqrt(1.0 + m22 - m00 - m11) * 2;
      q = {(c0.y - c1.x) / s, (c2.x + c0.z) / s, (c2.y + c1.z) / s, 0.25 * s};
    }
    return q.normalized();
  }
};

struct Pose {
  Quat q;
  Vec p;
  Pose operator*(const Pose& o) const { return {(q * o.q).normalized(), p + q * o.p}; }
  Pose inverse() const {
    const Quat c = q.conjugate();
    return {c, -(c * p)};
  }
};

inline Pose interpolate(const Pose& a, const Pose& b, double u) {
  Quat qb = b.q;
  double d = a.q.w * qb.w + a.q.x * qb.x + a.q.y * qb.y + a.q.z * qb.z;
  if (d < 0) {
    qb = {-qb.w, -qb.x, -qb.y, -qb.z};
    d = -d;
  }
  // normalised linear interpolation: close to slerp for the small steps between recorded frames
  const Quat q{(1 - u) * a.q.w + u * qb.w, (1 - u) * a.q.x + u * qb.x, (1 - u) * a.q.y + u * qb.y,
               (1 - u) * a.q.z + u * qb.z};
  return {q.normalized(), a.p * (1 - u) + b.p * u};
}

}  // namespace fpxr
