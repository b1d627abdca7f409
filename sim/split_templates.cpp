#include "sim/split_templates.h"

#include <cmath>

#include "sim/parallel.h"

namespace fp::sim {

namespace {

/// cubic spline W(r, H) and dW/dr in double precision (the patterns are computed once, precisely)
void spline(double r, double H, double& w, double& dw) {
  const double q = r / H;
  const double k = 8.0 / (kPi * H * H * H);
  if (q >= 1.0) {
    w = 0.0;
    dw = 0.0;
  } else if (q <= 0.5) {
    w = k * (6.0 * q * q * (q - 1.0) + 1.0);
    dw = k * (18.0 * q * q - 12.0 * q) / H;
  } else {
    const double t = 1.0 - q;
    w = k * 2.0 * t * t * t;
    dw = -k * 6.0 * t * t / H;
  }
}

constexpr double kRepulsion = 0.01;

/// Density error of replacing one parent of a cubic lattice of equal particles (radius 1, spacing 2, support
/// 4, normalised volumes so the lattice is at rest density 1) by n children at positions x, each of volume
/// V/n and support 4 n^(-1/3), pairs using the mean support: the objective in docs/method.md, Adaptivity,
///   E = sum_j tau_j^2 + sum_s tau_s^2, tau_j = sum_s V_s W_js - V_o W_jo, tau_s = rho_s - 1.
struct Objective {
  std::vector<Vec3d> lattice;  // the parent's neighbours that can reach a child
  int n;
  double parentVolume = 0.0;
  double childVolume;
  double childSupport;
  double pairSupport;

  explicit Objective(int children)
      : n(children),
        childSupport(4.0 / std::cbrt(double(children))),
        pairSupport(0.5 * (4.0 + childSupport)) {
    double sum = 0.0;
    for (int z = -4; z <= 4; ++z)
      for (int y = -4; y <= 4; ++y)
        for (int x = -4; x <= 4; ++x) {
          const Vec3d p = 2.0 * Vec3d(x, y, z);
          double w = 0.0;
          double dw = 0.0;
          spline(p.norm(), 4.0, w, dw);
          sum += w;
          // children stay within 2 of the parent, so a neighbour further than 2 + the pair support is out of
          // reach
          if (p.norm() > 0.0 && p.norm() < 2.0 + pairSupport)
            lattice.push_back(p);
        }
    parentVolume = 1.0 / sum;
    childVolume = parentVolume / children;
  }

  /// E(x) and, when grad is given, its gradient
  double evaluate(const std::vector<Vec3d>& x, std::vector<Vec3d>* grad) const {
    const std::size_t nc = x.size();
    // gradient of W(|a - b|, H) with respect to a
    auto u = [](const Vec3d& a, const Vec3d& b, double H) -> Vec3d {
      const Vec3d d = a - b;
      const double r = d.norm();
      if (r <= 1e-12)
        return Vec3d::Zero();
      double w = 0.0;
      double dw = 0.0;
      spline(r, H, w, dw);
      return dw / r * d;
    };
    auto W = [](const Vec3d& a, const Vec3d& b, double H) {
      double w = 0.0;
      double dw = 0.0;
      spline((a - b).norm(), H, w, dw);
      return w;
    };
    std::vector<double> tauJ(lattice.size());
    std::vector<double> tauS(nc);
    double e = 0.0;
    for (std::size_t j = 0; j < lattice.size(); ++j) {
      double t = -parentVolume * W(lattice[j], Vec3d::Zero(), 4.0);
      for (const Vec3d& c : x)
        t += childVolume * W(lattice[j], c, pairSupport);
      tauJ[j] = t;
      e += t * t;
    }
    for (std::size_t s = 0; s < nc; ++s) {
      double t = -1.0;
      for (const Vec3d& c : x)
        t += childVolume * W(x[s], c, childSupport);
      for (const Vec3d& p : lattice)
        t += parentVolume * W(x[s], p, pairSupport);
      tauS[s] = t;
      e += t * t;
    }
    // Children closer than 0.8 of their own spacing are pushed apart: without this the optimum of large n
    // stacks children onto each other (a heavier child in disguise).
    const double minDistance = 0.8 * 2.0 / std::cbrt(double(n));
    std::vector<Vec3d> repulsion(nc, Vec3d::Zero());
    for (std::size_t s = 0; s < nc; ++s)
      for (std::size_t t = s + 1; t < nc; ++t) {
        const Vec3d d = x[s] - x[t];
        const double r = d.norm();
        if (r >= minDistance)
          continue;
        const double gap = 1.0 - r / minDistance;
        e += kRepulsion * gap * gap;
        if (r > 1e-12) {
          const Vec3d g = -2.0 * kRepulsion * gap / (minDistance * r) * d;
          repulsion[s] += g;
          repulsion[t] -= g;
        }
      }
    if (grad) {
      grad->assign(repulsion.begin(), repulsion.end());
      for (std::size_t s = 0; s < nc; ++s) {
        Vec3d g = Vec3d::Zero();
        Vec3d own = Vec3d::Zero();
        for (std::size_t j = 0; j < lattice.size(); ++j) {
          const Vec3d us = u(x[s], lattice[j], pairSupport);
          g += 2.0 * tauJ[j] * childVolume * us;
          own += parentVolume * us;
        }
        for (std::size_t t = 0; t < nc; ++t) {
          if (t == s)
            continue;
          const Vec3d us = u(x[s], x[t], childSupport);
          own += childVolume * us;
          g += 2.0 * tauS[t] * childVolume * us;
        }
        g += 2.0 * tauS[s] * own;
        (*grad)[s] += g;
      }
    }
    return e;
  }
};

void centre(std::vector<Vec3d>& x) {
  Vec3d mean = Vec3d::Zero();
  for (const Vec3d& c : x)
    mean += c;
  mean /= double(x.size());
  for (Vec3d& c : x)
    c -= mean;
}

/// the cubic lattice of k^3 children of spacing 2 / k (the children's own spacing for a parent of radius 1)
std::vector<Vec3d> cubicLattice(int k) {
  std::vector<Vec3d> x;
  const double spacing = 2.0 / double(k);
  const double half = 0.5 * double(k - 1);
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < k; ++y)
      for (int c = 0; c < k; ++c)
        x.push_back(spacing * Vec3d(c - half, y - half, z - half));
  return x;
}

/// n points filling a ball evenly: radii by volume, directions on a Fibonacci sphere
std::vector<Vec3d> fibonacciBall(int n) {
  std::vector<Vec3d> x;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double t = (k + 0.5) / n;
    const double y = 1.0 - 2.0 * t;
    const double ring = std::sqrt(std::max(0.0, 1.0 - y * y));
    const double a = golden * k;
    const double radius = 0.9 * std::cbrt((k + 1.0) / n);
    x.push_back(radius * Vec3d(ring * std::cos(a), y, ring * std::sin(a)));
  }
  centre(x);
  return x;
}

/// gradient descent with a backtracking step; deterministic
std::vector<Vec3d> optimise(const Objective& obj, std::vector<Vec3d> x, int iterations) {
  std::vector<Vec3d> grad;
  std::vector<Vec3d> trial(x.size());
  double f = obj.evaluate(x, &grad);
  double step = 0.05;
  for (int it = 0; it < iterations; ++it) {
    double gmax = 0.0;
    for (const Vec3d& g : grad)
      gmax = std::max(gmax, g.norm());
    if (gmax <= 0.0)
      break;
    bool accepted = false;
    for (int tries = 0; tries < 20 && !accepted; ++tries) {
      // the largest move of a child is `step` (in parent radii)
      for (std::size_t s = 0; s < x.size(); ++s)
        trial[s] = x[s] - step / gmax * grad[s];
      centre(trial);
      const double ft = obj.evaluate(trial, nullptr);
      if (ft < f) {
        x.swap(trial);
        f = obj.evaluate(x, &grad);
        step *= 1.3;
        accepted = true;
      } else {
        step *= 0.5;
      }
    }
    if (!accepted || step < 1e-7)
      break;
  }
  return x;
}

}  // namespace

SplitTemplates::SplitTemplates() {
  m_offsets.resize(kMaxChildren + 1);
  m_residual.assign(kMaxChildren + 1, 0.0);
  parallelFor(kMinChildren, kMaxChildren + 1, [&](int n) {
    const Objective obj(n);
    const int k = int(std::lround(std::cbrt(double(n))));
    std::vector<Vec3d> x = optimise(obj, k * k * k == n ? cubicLattice(k) : fibonacciBall(n), 200);
    m_residual[std::size_t(n)] = obj.evaluate(x, nullptr);
    m_offsets[std::size_t(n)] = std::move(x);
  });
}

const SplitTemplates& SplitTemplates::get() {
  static const SplitTemplates templates;
  return templates;
}

}  // namespace fp::sim
