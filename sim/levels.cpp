#include "sim/levels.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>

#include "sim/dfsph_solver.h"
#include "sim/kernels.h"
#include "sim/parallel.h"

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
// passes per step once phi exists: enough to follow a surface that moves less than a spacing per step
constexpr int kPassesPerStep = 2;
// Hysteresis of the optimal mass (docs/method.md, Levels): a new target within this share of the current
// m_opt leaves it unchanged. The share step of Adaptivity::adapt (sim/adaptivity.cpp) uses the same band.
constexpr double kTargetBand = 0.3;
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

namespace {

/// The cone test of one particle (see detectSurface). `away` and `volume` are the volume-weighted sum of the
/// directions away from its fluid neighbours and their volume, which the caller may gather in a loop it
/// shares with other sums.
bool isSurface(const ParticleSet& p, std::size_t i, Vec3 away, Real volume, const NeighborList& fluidNbrs,
               const NeighborList& boundaryNbrs, const BoundarySet& boundary) {
  const Vec3 xi = p.x[i];
  // Boundary particles count with their (pair-scaled) volumes: a wall is not a free surface.
  const Real sb = boundary.volumeScale(p.H[i]);
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
  if (count < kMinNeighbors)
    return true;
  const Real len = away.norm();
  // a balanced neighbourhood is interior; at a flat free surface the imbalance is about one half
  if (len <= kMinImbalance * volume)
    return false;
  const Vec3 dir = away / len;
  auto inCone = [&](const Vec3& xj) {
    const Vec3 d = xj - xi;
    return d.dot(dir) >= kConeCos * d.norm();
  };
  // A neighbour larger than the particle covers more of its view: the cone widens by the angle of the
  // neighbour's excess radius (r_j - r_i, from the supports 4 r), so that a fine particle in a pocket under
  // coarse ones is not taken for a surface particle (which would refine the water around it at rest).
  const Real ri = p.H[i] * Real(0.25);
  const Real kConeSin = Real(0.5);
  auto inWidenedCone = [&](std::uint32_t j) {
    const Vec3 d = p.x[j] - xi;
    const Real dist = d.norm();
    const Real excess = p.H[j] * Real(0.25) - ri;
    if (!(excess > Real(0)) || !(dist > Real(0)))
      return d.dot(dir) >= kConeCos * dist;
    const Real s = std::min(Real(1), excess / dist);
    const Real c = std::sqrt(Real(1) - s * s);
    // cos(30 degrees + asin(s))
    return d.dot(dir) >= (kConeCos * c - kConeSin * s) * dist;
  };
  for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
    if (inWidenedCone(fluidNbrs.neighbor(i, k)))
      return false;
  }
  for (std::uint32_t k = boundaryNbrs.offsets[i]; k < boundaryNbrs.offsets[i + 1]; ++k) {
    if (inCone(boundary.x[boundaryNbrs.indices[k]]))
      return false;
  }
  return true;
}

void setSurfaceFlag(ParticleSet& p, std::size_t i, bool surface) {
  if (surface)
    p.flags[i] |= kFlagSurface;
  else
    p.flags[i] &= ~std::uint32_t(kFlagSurface);
}

}  // namespace

void detectSurface(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
                   const BoundarySet& boundary, const Real* volume) {
  const std::size_t n = p.size();
  auto run = [&](auto volumeOf) {
    parallelFor(Range(0, n, kGrain), [&](const Range& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        const Vec3 xi = p.x[i];
        // Directions to the neighbours weighted by their volumes: with particles of different sizes an
        // unweighted sum points away from the many fine neighbours towards a few coarse ones and flags
        // interfaces as surface.
        Vec3 away = Vec3::Zero();
        Real sum = 0;
        for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
          const std::uint32_t j = fluidNbrs.neighbor(i, k);
          const Vec3 d = xi - p.x[j];
          const Real len = d.norm();
          const Real vj = volumeOf(j);
          sum += vj;
          if (len > Real(0))
            away += (vj / len) * d;
        }
        setSurfaceFlag(p, i, isSurface(p, i, away, sum, fluidNbrs, boundaryNbrs, boundary));
      }
    });
  };
  if (volume)
    run([volume](std::uint32_t j) { return volume[j]; });
  else
    run([&p](std::uint32_t j) { return p.m[j] / p.rho[j]; });
}

void LevelEstimator::surfaceAndRawDynamics(ParticleSet& p, const NeighborList& fluidNbrs,
                                           const NeighborList& boundaryNbrs, const BoundarySet& boundary) {
  // One pass over the neighbours for the surface test, the raw SPH curl and the raw velocity difference
  // (the volumes m / rho from m_volume, filled by compute()).
  const std::size_t n = p.size();
  const Real* volumes = m_volume.data();
  m_rawOmega.resize(n);
  m_rawNu.resize(n);
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3 xi = p.x[i];
      const Vec3 vi = p.v[i];
      Vec3 away = Vec3::Zero();
      Real volume = 0;
      Vec3 curl = Vec3::Zero();
      // the particle itself is in the denominator of nu (weight W(0)), so an isolated particle has nu = 0
      Real num = 0;
      Real den = volumes[i] * CubicSpline::w0(p.H[i]);
      for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
        const std::uint32_t j = fluidNbrs.neighbor(i, k);
        const Vec3 xij = xi - p.x[j];
        const Real len = xij.norm();
        const Real vj = volumes[j];
        volume += vj;
        if (len > Real(0))
          away += (vj / len) * xij;
        Real w = 0;
        Real g = 0;
        CubicSpline::evaluate(len, pairSupport(p.H[i], p.H[j]), w, g);
        const Vec3 vji = p.v[j] - vi;
        curl += p.m[j] * vji.cross(g * xij);
        num += vj * vji.norm() * w;
        den += vj * w;
      }
      m_rawOmega[i] = curl.norm() / p.rho[i];
      m_rawNu[i] = den > Real(0) ? num / den : Real(0);
      setSurfaceFlag(p, i, isSurface(p, i, away, volume, fluidNbrs, boundaryNbrs, boundary));
    }
  });
}

void LevelEstimator::startDistance(ParticleSet& p, Real cap, Real hop, int& passes) {
  // phi is kept from step to step (it moves with the particles and children inherit it), so a couple of
  // Jacobi passes of phi_i = min_j (phi_j + |x_ij|) per step follow the moving surface. The minimum runs over
  // the neighbours only, not the particle's own previous value: distances may then grow as well as shrink by
  // a hop per pass, and at rest the passes keep the exact graph distance (a minimum that included the old
  // value would only shrink, and the earlier remedy, adding a hop to every particle before the passes, left
  // every particle beyond the passes' reach one hop too far). A particle without a previous value (infinity)
  // starts at the cap, and the first call runs to convergence.
  const std::size_t n = p.size();
  m_phiNext.resize(n);
  std::atomic<bool> fresh{false};
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    bool local = false;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      if (p.flags[i] & kFlagSurface) {
        p.phi[i] = 0;
      } else if (!(p.phi[i] < cap)) {
        local |= !std::isfinite(p.phi[i]);
        p.phi[i] = cap;
      }
    }
    if (local)
      fresh = true;
  });
  passes = fresh ? std::min(kMaxPropagationPasses, int(std::ceil(cap / hop)) + 1) : kPassesPerStep;
}

Real LevelEstimator::distanceAt(const ParticleSet& p, std::size_t i, const NeighborList& fluidNbrs,
                                Real cap) {
  if (p.flags[i] & kFlagSurface)
    return 0;
  Real best = cap;
  for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
    const std::uint32_t j = fluidNbrs.neighbor(i, k);
    if (p.phi[j] >= best)
      continue;  // cannot improve
    best = std::min(best, p.phi[j] + (p.x[i] - p.x[j]).norm());
  }
  return best;
}

bool LevelEstimator::distancePass(ParticleSet& p, const NeighborList& fluidNbrs, Real cap,
                                  const Real* rawOmega, const Real* rawNu) {
  const std::size_t n = p.size();
  std::atomic<bool> changed{false};
  const Real* volume = m_volume.data();
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    bool local = false;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Real best = rawOmega ? distanceAndDynamicsAt(p, i, fluidNbrs, cap, rawOmega, rawNu, volume)
                                 : distanceAt(p, i, fluidNbrs, cap);
      local |= best != p.phi[i];
      m_phiNext[i] = best;
    }
    if (local)
      changed = true;
  });
  p.phi.swap(m_phiNext);
  return changed;
}

Real LevelEstimator::distanceAndDynamicsAt(ParticleSet& p, std::size_t i, const NeighborList& fluidNbrs,
                                           Real cap, const Real* rawOmega, const Real* rawNu,
                                           const Real* volume) {
  // The raw values are averaged over the kernel (Shepard): the SPH curl of a disordered particle set carries
  // noise of the order of the velocity fluctuation over the support, which the raw values would mistake for
  // vortices. The distance's minimum (distanceAt) shares the pair distances.
  const bool surface = (p.flags[i] & kFlagSurface) != 0;
  Real best = cap;
  const Vec3 xi = p.x[i];
  const Real Hi = p.H[i];
  const Real self = volume[i] * CubicSpline::w0(Hi);
  Real omega = self * rawOmega[i];
  Real nu = self * rawNu[i];
  Real den = self;
  for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
    const std::uint32_t j = fluidNbrs.neighbor(i, k);
    const Real len = (xi - p.x[j]).norm();
    if (p.phi[j] < best)
      best = std::min(best, p.phi[j] + len);
    const Real w = volume[j] * CubicSpline::w(len, pairSupport(Hi, p.H[j]));
    omega += w * rawOmega[j];
    nu += w * rawNu[j];
    den += w;
  }
  p.omega[i] = omega / den;
  p.nu[i] = nu / den;
  return surface ? Real(0) : best;
}

void LevelEstimator::compute(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
                             const BoundarySet& boundary, const SimParams& params, AdaptivityMode mode,
                             Real mFine, std::vector<Real>& target, LevelSums* sums) {
  const std::size_t n = p.size();
  const Real r = Real(params.particleRadius);
  const double mBase = double(mFine) * params.massRatio;
  const bool dynamic = mode == AdaptivityMode::FluidPlaying;
  // Three passes over the neighbours in all: surface, raw curl and velocity difference; their kernel average
  // with the first distance pass; the second distance pass. With the density pass's sums (the steps) the
  // first evaluates no kernel: it is the surface test alone.
  const Real* rawOmega = nullptr;
  const Real* rawNu = nullptr;
  const bool given = dynamic && sums && sums->filled;
  const bool useSums =
      given && sums->curl.size() == n && sums->nuSum.size() == n && sums->weightSum.size() == n;
  // sums filled for another particle set are a caller's error (the fallback below would hide it)
  assert(useSums == given);
  // One pass over the particles: the surface of the previous computation, for the hysteresis of the targets
  // (phi is 0 only there); the volumes m / rho the neighbour passes read; and with the density pass's sums,
  // those finished with the densities of now (a split child's may have been blended since the pass), in
  // place: curl becomes omega, nuSum becomes nu.
  m_wasSurface.resize(n);
  m_volume.resize(n);
  parallelFor(Range(0, n, kGrain), [&](const Range& rg) {
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
      m_wasSurface[i] = p.phi[i] == Real(0);
      m_volume[i] = p.m[i] / p.rho[i];
      if (useSums) {
        sums->curl[i] /= p.rho[i];
        // the particle itself is in the denominator (weight m_i / rho_i W(0)), so an isolated particle has
        // nu = 0
        const Real den = m_volume[i] * CubicSpline::w0(p.H[i]) + sums->weightSum[i];
        sums->nuSum[i] = den > Real(0) ? sums->nuSum[i] / den : Real(0);
      }
    }
  });
  if (useSums) {
    detectSurface(p, fluidNbrs, boundaryNbrs, boundary, m_volume.data());
    rawOmega = sums->curl.data();
    rawNu = sums->nuSum.data();
  } else if (dynamic) {
    // (the start's levels and tests: the steps give the sums)
    surfaceAndRawDynamics(p, fluidNbrs, boundaryNbrs, boundary);
    rawOmega = m_rawOmega.data();
    rawNu = m_rawNu.data();
  } else {
    detectSurface(p, fluidNbrs, boundaryNbrs, boundary, m_volume.data());
    std::fill(p.omega.begin(), p.omega.end(), Real(0));
    std::fill(p.nu.begin(), p.nu.end(), Real(0));
  }
  const double lo = params.surfaceDistanceLo * r;
  const double hi = params.surfaceDistanceHi * r;
  const Real cap = Real(hi);
  int passes = 0;
  startDistance(p, cap, Real(2) * r, passes);
  // (the first pass always runs: it also averages omega and nu)
  for (int pass = 0; pass < passes; ++pass) {
    if (!distancePass(p, fluidNbrs, cap, pass == 0 ? rawOmega : nullptr, rawNu))
      break;
  }
  // CFL-aware refinement: the fine particles at the surface set the time step (dt = cfl 2 r / v there), and
  // a particle refined for its vorticity or velocity difference must not force a smaller one. A particle
  // moving at v takes the surface's step at a radius of r v / v_surface, a mass of m_fine (v / v_surface)^3:
  // the dynamic levels refine it down to that mass, no further.
  const bool cflLimit = dynamic && params.cflLimitedRefinement;
  double surfaceSpeed2 = 0.0;
  if (cflLimit) {
    // a maximum: exact in any order
    surfaceSpeed2 = parallelReduce(
        Range(0, n, kGrain), 0.0,
        [&](const Range& rg, double acc) {
          for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
            if (p.phi[i] <= Real(lo))
              acc = std::max(acc, double(p.v[i].squaredNorm()));
          }
          return acc;
        },
        [](double a, double b) { return std::max(a, b); });
  }
  // the step a fine particle allows at unit speed, and the target step: the surface's, at most dt_max
  const double fineLimit = params.cflFactor * 2.0 * double(r);
  const double dtTarget =
      surfaceSpeed2 > 0.0 ? std::min(params.dtMax, fineLimit / std::sqrt(surfaceSpeed2)) : params.dtMax;
  // the own pass's raw values are not kept (the steps' levels use the density pass's sums), and the sums are
  // spent
  std::vector<Real>().swap(m_rawOmega);
  std::vector<Real>().swap(m_rawNu);
  if (sums)
    sums->filled = false;
  target.resize(n);
  parallelFor(Range(0, n, kGrain), [&](const Range& rg) {
    for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
      const double rPhi = visibleLevel(p.phi[i], lo, hi);
      double rOmega = 1.0;
      double rNu = 1.0;
      if (dynamic) {
        rOmega = refinementLevel(p.omega[i], params.vorticityLo, params.vorticityHi, params.vorticityRmax);
        rNu = refinementLevel(p.nu[i], params.velocityDifferenceLo, params.velocityDifferenceHi,
                              params.velocityDifferenceRmax);
      }
      p.levelPhi[i] = Real(rPhi);
      p.levelOmega[i] = Real(rOmega);
      p.levelNu[i] = Real(rNu);
      double m = optimalMass(rPhi, rOmega, rNu, double(mFine), mBase);
      if (cflLimit) {
        const double mSurface = optimalMass(rPhi, 1.0, 1.0, double(mFine), mBase);
        if (m < mSurface) {
          // the radius over the fine one at which this particle allows the target step
          const double ratio =
              kCflSpeedMargin * std::sqrt(double(p.v[i].squaredNorm())) * dtTarget / fineLimit;
          const double mCfl = double(mFine) * std::min(1e6, ratio * ratio * ratio);
          m = std::max(m, std::min(mSurface, mCfl));
        }
      }
      // Hysteresis: a target within the band around the current optimal mass keeps it, so that the small
      // motions of water at rest (a surface flag that comes and goes, a distance that wavers) do not move the
      // resolution. The coarsest target is always followed, so that the deep water ends as coarse as the
      // levels ask (a held target would stop the coarsening short, up to the band below m_base), and so is
      // the finest of a particle on the surface at this computation and the one before, so that the surface
      // that stays ends fine.
      const double held = double(p.mOpt[i]);
      const bool coarsest = m >= mBase * (1.0 - 1e-6);
      const bool finest = p.phi[i] == Real(0) && m_wasSurface[i];
      if (!coarsest && !finest && std::abs(m - held) <= kTargetBand * held)
        m = held;
      target[i] = Real(m);
    }
  });
}

std::size_t LevelEstimator::memoryBytes() const {
  return (m_phiNext.capacity() + m_rawOmega.capacity() + m_rawNu.capacity() + m_volume.capacity()) *
             sizeof(Real) +
         m_wasSurface.capacity();
}

}  // namespace fp::sim
