#include "sim/levels.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "sim/kernels.h"

namespace fp::sim {

namespace {
using Range = tbb::blocked_range<std::size_t>;
constexpr std::size_t kGrain = 1024;
// Winchenbach et al. 2017: a particle is on the surface when no neighbour lies in a cone of this half angle
// around the direction pointing away from its neighbours, or when it has too few neighbours.
const Real kConeCos = Real(std::cos(30.0 * kPi / 180.0));
constexpr std::uint32_t kMinNeighbors = 5;
// |sum_j V_j x_ij / |x_ij|| / sum_j V_j below this: a balanced, interior neighbourhood
constexpr Real kMinImbalance = Real(0.1);
// Jacobi passes of the distance propagation are bounded: beyond this many hops the distance is capped anyway.
constexpr int kMaxPropagationPasses = 24;
}  // namespace

double levelRamp(double x, double lo, double hi) {
  return std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
}

double visibleLevel(double phi, double lo, double hi) {
  return levelRamp(phi, lo, hi);
}

double refinementLevel(double x, double lo, double hi, double rmax) {
  return 1.0 + (rmax - 1.0) * levelRamp(x, lo, hi);
}

double optimalMass(double rPhi, double rOmega, double rNu, double mFine, double mBase) {
  return mFine + rPhi / (rOmega * rNu) * (mBase - mFine);
}

Real supportForMass(Real m, Real mFine, Real fineRadius) {
  return Real(4) * fineRadius * std::cbrt(m / mFine);
}

void LevelEstimator::detectSurface(ParticleSet& p, const NeighborList& fluidNbrs,
                                   const NeighborList& boundaryNbrs, const BoundarySet& boundary) {
  const std::size_t n = p.size();
  const Real Hb = boundary.support();
  tbb::parallel_for(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3 xi = p.x[i];
      // Directions to the neighbours weighted by their volumes: with particles of different sizes an
      // unweighted sum points away from the many fine neighbours towards a few coarse ones and flags
      // interfaces as surface. Boundary particles count with their (pair-scaled) volumes: a wall is not a
      // free surface.
      Vec3 away = Vec3::Zero();
      Real volume = 0;
      for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
        const std::uint32_t j = fluidNbrs.indices[k];
        const Vec3 d = xi - p.x[j];
        const Real len = d.norm();
        const Real vj = p.m[j] / p.rho[j];
        volume += vj;
        if (len > Real(0))
          away += (vj / len) * d;
      }
      const Real sb = pairSupport(p.H[i], Hb) / Hb;
      for (std::uint32_t k = boundaryNbrs.offsets[i]; k < boundaryNbrs.offsets[i + 1]; ++k) {
        const std::uint32_t b = boundaryNbrs.indices[k];
        const Vec3 d = xi - boundary.x[b];
        const Real len = d.norm();
        const Real vb = sb * boundary.psi[b];
        volume += vb;
        if (len > Real(0))
          away += (vb / len) * d;
      }
      const std::uint32_t count = fluidNbrs.count(i) + boundaryNbrs.count(i);
      bool surface = count < kMinNeighbors;
      const Real len = away.norm();
      // a balanced neighbourhood is interior; at a flat free surface the imbalance is about one half
      if (!surface && len > kMinImbalance * volume) {
        const Vec3 dir = away / len;
        bool covered = false;
        auto inCone = [&](const Vec3& xj) {
          const Vec3 d = xj - xi;
          return d.dot(dir) >= kConeCos * d.norm();
        };
        for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1] && !covered; ++k)
          covered = inCone(p.x[fluidNbrs.indices[k]]);
        for (std::uint32_t k = boundaryNbrs.offsets[i]; k < boundaryNbrs.offsets[i + 1] && !covered; ++k)
          covered = inCone(boundary.x[boundaryNbrs.indices[k]]);
        surface = !covered;
      }
      if (surface)
        p.flags[i] |= kFlagSurface;
      else
        p.flags[i] &= ~std::uint32_t(kFlagSurface);
    }
  });
}

void LevelEstimator::propagateDistance(const ParticleSet& p, const NeighborList& fluidNbrs, Real cap,
                                       Real hop) {
  const std::size_t n = p.size();
  m_phi.resize(n);
  m_phiNext.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    m_phi[i] = (p.flags[i] & kFlagSurface) ? Real(0) : cap;
  // Jacobi passes of phi_i = min_j (phi_j + |x_ij|): deterministic whatever the thread count. Each pass moves
  // the front by at least one neighbour hop, so cap / hop passes reach the cap.
  const int passes = std::min(kMaxPropagationPasses, int(std::ceil(cap / hop)) + 1);
  for (int pass = 0; pass < passes; ++pass) {
    std::atomic<bool> changed{false};
    tbb::parallel_for(Range(0, n, kGrain), [&](const Range& r) {
      bool local = false;
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        Real best = m_phi[i];
        for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
          const std::uint32_t j = fluidNbrs.indices[k];
          if (m_phi[j] >= best)
            continue;  // cannot improve
          best = std::min(best, m_phi[j] + (p.x[i] - p.x[j]).norm());
        }
        best = std::min(best, cap);
        local |= best != m_phi[i];
        m_phiNext[i] = best;
      }
      if (local)
        changed = true;
    });
    m_phi.swap(m_phiNext);
    if (!changed)
      break;
  }
}

void LevelEstimator::vorticityAndVelocityDifference(const ParticleSet& p, const NeighborList& fluidNbrs) {
  const std::size_t n = p.size();
  m_omega.resize(n);
  m_nu.resize(n);
  tbb::parallel_for(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3 xi = p.x[i];
      const Vec3 vi = p.v[i];
      Vec3 curl = Vec3::Zero();
      // the particle itself is in the denominator of nu (weight W(0)), so an isolated particle has nu = 0
      Real num = 0;
      Real den = p.m[i] / p.rho[i] * CubicSpline::w0(p.H[i]);
      for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
        const std::uint32_t j = fluidNbrs.indices[k];
        const Vec3 xij = xi - p.x[j];
        const Real Hij = pairSupport(p.H[i], p.H[j]);
        Real w = 0;
        Real g = 0;
        CubicSpline::evaluate(xij.norm(), Hij, w, g);
        const Vec3 vji = p.v[j] - vi;
        curl += p.m[j] * vji.cross(g * xij);
        const Real volume = p.m[j] / p.rho[j];
        num += volume * vji.norm() * w;
        den += volume * w;
      }
      m_omega[i] = curl.norm() / p.rho[i];
      m_nu[i] = den > Real(0) ? num / den : Real(0);
    }
  });
}

void LevelEstimator::compute(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
                             const BoundarySet& boundary, const SimParams& params, AdaptivityMode mode,
                             Real mFine, std::vector<Real>& target) {
  const std::size_t n = p.size();
  const Real r = Real(params.particleRadius);
  const double mBase = double(mFine) * params.massRatio;
  detectSurface(p, fluidNbrs, boundaryNbrs, boundary);
  const double lo = params.surfaceDistanceLo * r;
  const double hi = params.surfaceDistanceHi * r;
  propagateDistance(p, fluidNbrs, Real(hi), Real(2) * r);
  const bool dynamic = mode == AdaptivityMode::FluidPlaying;
  if (dynamic) {
    vorticityAndVelocityDifference(p, fluidNbrs);
  } else {
    m_omega.assign(n, Real(0));
    m_nu.assign(n, Real(0));
  }
  target.resize(n);
  tbb::parallel_for(Range(0, n, kGrain), [&](const Range& rg) {
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
      const double rPhi = visibleLevel(m_phi[i], lo, hi);
      double rOmega = 1.0;
      double rNu = 1.0;
      if (dynamic) {
        rOmega = refinementLevel(m_omega[i], params.vorticityLo, params.vorticityHi, params.vorticityRmax);
        rNu = refinementLevel(m_nu[i], params.velocityDifferenceLo, params.velocityDifferenceHi,
                              params.velocityDifferenceRmax);
      }
      p.levelPhi[i] = Real(rPhi);
      p.levelOmega[i] = Real(rOmega);
      p.levelNu[i] = Real(rNu);
      target[i] = Real(optimalMass(rPhi, rOmega, rNu, double(mFine), mBase));
    }
  });
}

std::size_t LevelEstimator::memoryBytes() const {
  return (m_phi.capacity() + m_phiNext.capacity() + m_omega.capacity() + m_nu.capacity()) * sizeof(Real);
}

}  // namespace fp::sim
