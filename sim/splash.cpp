#include "sim/splash.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sim/kernels.h"
#include "sim/levels.h"
#include "sim/parallel.h"
#include "sim/simulation.h"

namespace fp::sim {

namespace {
using Range = tbb::blocked_range<std::size_t>;
constexpr std::size_t kGrain = 1024;
// The splash grid never exceeds this many cells: a domain far larger than the particles gets larger cells
// (still correct, the search reaches as many cells as the supports need), never an InputError mid-run.
constexpr double kMaxGridCells = double(std::size_t(1) << 26);
// |xhat_i| below this share of sum_j |x_ij| V_j W_ij: the neighbours cancel out and give no direction
// (round-off of a balanced sum is far below it, a real imbalance far above it).
constexpr Real kMinImbalance = Real(1e-3);

// splitmix64 finaliser: a counter-based generator, so every (seed, id, frame, k, stream) has its own number
// whatever the order or thread of evaluation
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// uniform numbers in [0, 1) of splash particle k of particle `id` in `frame`
class SplashRandom {
 public:
  SplashRandom(std::uint64_t seed, std::uint32_t id, std::uint64_t frame, std::uint32_t k)
      : m_key(mix(mix(mix(seed) ^ id) ^ frame) ^ (std::uint64_t(k) << 8)) {}
  /// number of stream `s` (each use draws its own stream)
  Real uniform(std::uint32_t s) const { return Real(double(mix(m_key ^ s) >> 11) * 0x1.0p-53); }

 private:
  std::uint64_t m_key;
};

}  // namespace

void SplashParticles::clear() {
  x.clear();
  radius.clear();
  source.clear();
}

void SplashGenerator::copyInOrder(const ParticleSet& p) {
  const std::size_t n = m_order.size();
  m_sorted.x.resize(n);
  m_sorted.m.resize(n);
  m_sorted.H.resize(n);
  m_sorted.rho.resize(n);
  m_sorted.flags.assign(n, 0);
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t s = r.begin(); s < r.end(); ++s) {
      const std::uint32_t i = m_order[s];
      m_sorted.x[s] = p.x[i];
      m_sorted.m[s] = p.m[i];
      m_sorted.H[s] = p.H[i];
      m_sorted.rho[s] = p.rho[i];
    }
  });
}

void SplashGenerator::searchNeighbors(const ParticleSet& p, const BoundarySet& boundary, const Aabb& domain) {
  const std::size_t n = p.size();
  const std::size_t nb = boundary.size();
  Real minH = p.H[0];
  Real maxH = p.H[0];
  for (Real h : p.H) {
    minH = std::min(minH, h);
    maxH = std::max(maxH, h);
  }
  const Real fluidMaxH = maxH;
  if (nb > 0)
    maxH = std::max(maxH, boundary.support());
  const Vec3d extent = domain.sizes().array() + 2.0 * double(minH);
  const Real cell = std::max(minH, Real(std::cbrt(extent.prod() / kMaxGridCells)));
  const bool gridChanged =
      cell != m_gridCell || domain.min() != m_gridDomain.min() || domain.max() != m_gridDomain.max();
  if (gridChanged) {
    m_grid.setup(domain, cell);
    m_gridCell = cell;
    m_gridDomain = domain;
  }

  // fluid: our own sorted copy of the fields the search and detectSurface read
  m_grid.sort(p.x.data(), n, m_order, m_fluidCells);
  copyInOrder(p);
  const GridPoints fluidSrc{m_sorted.x.data(), m_sorted.H.data(), 0, &m_fluidCells, 0};
  if (minH < fluidMaxH)  // mixed sizes: each particle searches only as far as its own support (same lists)
    m_search.buildSymmetric(m_grid, m_sorted.x, m_sorted.H, m_fluidCells, fluidMaxH, m_fluidNbrs);
  else
    m_search.build(m_grid, m_sorted.x, m_sorted.H, {fluidSrc}, 0, maxH, m_fluidNbrs);

  // boundary: the static part sorted once per boundary and grid, the kinematic part every call
  const std::size_t nStatic = boundary.staticCount();
  const std::size_t nKinematic = nb - nStatic;
  if (gridChanged || boundary.staticVersion() != m_staticVersion) {
    if (nStatic > 0)
      m_grid.sort(boundary.x.data(), nStatic, m_staticOrder, m_staticCells);
    m_staticX.resize(nStatic);
    parallelFor(Range(0, nStatic, kGrain), [&](const Range& r) {
      for (std::size_t s = r.begin(); s < r.end(); ++s)
        m_staticX[s] = boundary.x[m_staticOrder[s]];
    });
    m_staticBounds = pointBounds(m_staticX.data(), nStatic);
    m_staticVersion = boundary.staticVersion();
  }
  if (nKinematic > 0)
    m_grid.sort(boundary.x.data() + nStatic, nKinematic, m_kinematicOrder, m_kinematicCells);
  m_kinematicX.resize(nKinematic);
  parallelFor(Range(0, nKinematic, kGrain), [&](const Range& r) {
    for (std::size_t s = r.begin(); s < r.end(); ++s)
      m_kinematicX[s] = boundary.x[nStatic + m_kinematicOrder[s]];
  });
  const std::vector<GridPoints> walls =
      wallSources(boundary.support(), m_staticX.data(), nStatic, m_staticCells, &m_staticBounds, nullptr,
                  m_kinematicX.data(), nKinematic, m_kinematicCells);
  m_search.build(m_grid, m_sorted.x, m_sorted.H, walls, -1, maxH, m_boundaryNbrs);
  // back to the caller's boundary indices, which detectSurface and the volumes index
  parallelFor(Range(0, m_boundaryNbrs.indices.size(), 4 * kGrain), [&](const Range& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      std::uint32_t& b = m_boundaryNbrs.indices[k];
      b = b < nStatic ? m_staticOrder[b] : std::uint32_t(nStatic) + m_kinematicOrder[b - nStatic];
    }
  });
}

const SplashParticles& SplashGenerator::generate(const ParticleSet& p, const BoundarySet& boundary,
                                                 const SimParams& params, const Aabb& domain,
                                                 std::uint64_t frame) {
  m_out.clear();
  if (off(params, p.size()))
    return m_out;
  searchNeighbors(p, boundary, domain);
  return spawn(p, boundary, params, frame, m_fluidNbrs, m_boundaryNbrs);
}

const SplashParticles& SplashGenerator::spawn(const ParticleSet& p, const BoundarySet& boundary,
                                              const SimParams& params, std::uint64_t frame,
                                              const NeighborList& fluidNbrs,
                                              const NeighborList& boundaryNbrs) {
  const std::size_t n = p.size();
  detectSurface(m_sorted, fluidNbrs, boundaryNbrs, boundary);

  // spawning particles and their outward directions, by the caller's index
  const std::uint32_t maxNeighbors = std::uint32_t(std::max(params.splashNeighbors, 0));
  const Real Hb = boundary.support();
  m_outward.resize(n);
  m_spawns.resize(n);
  parallelFor(Range(0, n, kGrain), [&](const Range& range) {
    for (std::size_t s = range.begin(); s < range.end(); ++s) {
      const std::uint32_t i = m_order[s];
      const bool spawns = (m_sorted.flags[s] & kFlagSurface) && fluidNbrs.count(s) < maxNeighbors;
      m_spawns[i] = spawns;
      m_outward[i] = Vec3::Zero();
      if (!spawns)
        continue;
      const Vec3 xi = m_sorted.x[s];
      const Real Hi = m_sorted.H[s];
      Vec3 xhat = Vec3::Zero();
      Real magnitude = 0;  // sum of |terms|, the scale of round-off in xhat
      for (std::uint32_t k = fluidNbrs.offsets[s]; k < fluidNbrs.offsets[s + 1]; ++k) {
        const std::uint32_t j = fluidNbrs.neighbor(s, k);
        const Vec3 xij = xi - m_sorted.x[j];
        const Real rho = m_sorted.rho[j];
        const Real vj = rho > Real(0) ? m_sorted.m[j] / rho : Real(0);
        const Real r = xij.norm();
        const Real w = vj * CubicSpline::w(r, pairSupport(Hi, m_sorted.H[j]));
        xhat += w * xij;
        magnitude += w * r;
      }
      if (boundaryNbrs.count(s) > 0) {
        const Real Hib = pairSupport(Hi, Hb);
        const Real scale = Hib / Hb;  // the pair-scaled Akinci volume, as in detectSurface
        for (std::uint32_t k = boundaryNbrs.offsets[s]; k < boundaryNbrs.offsets[s + 1]; ++k) {
          const std::uint32_t b = boundaryNbrs.indices[k];
          const Vec3 xib = xi - boundary.x[b];
          const Real r = xib.norm();
          const Real w = scale * boundary.psi[b] * CubicSpline::w(r, Hib);
          xhat += w * xib;
          magnitude += w * r;
        }
      }
      const Real len = xhat.norm();
      if (len > kMinImbalance * magnitude && len > Real(0)) {
        m_outward[i] = xhat / len;
      } else {
        const Real speed = p.v[i].norm();
        if (speed > Real(0) && std::isfinite(speed))
          m_outward[i] = p.v[i] / speed;
      }
    }
  });

  // output ranges by the caller's index, so the order does not depend on the grid or the threads
  m_first.resize(n + 1);
  m_first[0] = 0;
  for (std::size_t i = 0; i < n; ++i)
    m_first[i + 1] = m_first[i] + m_spawns[i];
  const std::uint32_t count = std::uint32_t(params.splashCount);
  const std::size_t total = std::size_t(m_first[n]) * count;
  m_out.x.resize(total);
  m_out.radius.resize(total);
  m_out.source.resize(total);
  const Real alphaMin = Real(params.splashAlphaMin);
  const Real alphaSpan = Real(params.splashAlphaMax - params.splashAlphaMin);
  const Real noise = Real(params.splashNoise);
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      if (!m_spawns[i])
        continue;
      const Real ri = Real(0.25) * p.H[i];
      for (std::uint32_t k = 0; k < count; ++k) {
        const SplashRandom rnd(params.seed, p.id[i], frame, k);
        const Real alpha = alphaMin + alphaSpan * rnd.uniform(0);
        // n_r: uniform in the ball of radius n_r_max (uniform direction, radius n_r_max u^(1/3))
        const Real cosTheta = Real(2) * rnd.uniform(1) - Real(1);
        const Real sinTheta = std::sqrt(std::max(Real(0), Real(1) - cosTheta * cosTheta));
        const Real azimuth = Real(2.0 * kPi) * rnd.uniform(2);
        const Vec3 unit(sinTheta * std::cos(azimuth), sinTheta * std::sin(azimuth), cosTheta);
        const Vec3 d = m_outward[i] + noise * std::cbrt(rnd.uniform(3)) * unit;
        const Real dLen = d.norm();
        // d vanishes with no direction and no noise, or when the noise cancels the direction exactly
        const Vec3 dir = dLen > Real(1e-6) ? Vec3(d / dLen) : unit;
        const std::size_t o = std::size_t(m_first[i]) * count + k;
        m_out.x[o] = p.x[i] + alpha * ri * dir;
        m_out.radius[o] = kSplashRadiusFraction * ri;
        m_out.source[o] = std::uint32_t(i);
      }
    }
  });
  return m_out;
}

const SplashParticles& SplashGenerator::generate(const Simulation& simulation, std::uint64_t frame) {
  const ParticleSet& p = simulation.particles();
  const SimParams& params = simulation.params();
  if (!simulation.neighborsCurrent())
    return generate(p, simulation.boundary(), params, simulation.scene().domain, frame);
  // the simulation's lists are those of its current state (Simulation::prepareNeighbors): no search here
  m_out.clear();
  if (off(params, p.size()))
    return m_out;
  const std::size_t n = p.size();
  m_order.resize(n);
  std::iota(m_order.begin(), m_order.end(), 0u);
  copyInOrder(p);
  return spawn(p, simulation.boundary(), params, frame, simulation.fluidNeighbors(),
               simulation.boundaryNeighbors());
}

std::size_t SplashGenerator::memoryBytes() const {
  const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return bytes(m_out.x) + bytes(m_out.radius) + bytes(m_out.source) + m_search.memoryBytes() +
         m_fluidNbrs.memoryBytes() + m_boundaryNbrs.memoryBytes() + m_sorted.memoryBytes() + bytes(m_order) +
         bytes(m_fluidCells) + bytes(m_staticOrder) + bytes(m_staticCells) + bytes(m_staticX) +
         bytes(m_kinematicOrder) + bytes(m_kinematicCells) + bytes(m_kinematicX) + bytes(m_outward) +
         bytes(m_spawns) + bytes(m_first);
}

}  // namespace fp::sim
