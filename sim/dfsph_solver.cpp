#include "sim/dfsph_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/kernels.h"
#include "sim/parallel.h"

namespace fp::sim {

namespace {

constexpr std::size_t kGrain = 1024;  // fixed grain: reductions split the same way whatever the thread count
constexpr Real kEps = Real(1e-6);
// Divergence solve only where the neighbourhood is full by volume: the particle's own volume sum sum_j V_j
// W_ij (its density over the rest density, boundary included) at least this. SPlisHSPlasH counts neighbours
// (20 in 3D), which skips a fine interior particle next to coarse ones (about 10 neighbours, each of many
// times its volume); 0.72 is the ratio that best reproduces the 20-neighbour rule on a uniform tank at rest
// (docs/method.md, Divergence solve).
constexpr Real kMinDensityRatioForDivergence = Real(0.72);
// The divergence solve's warm start only where the neighbourhood is also full by count: at least this many
// neighbours, fluid and boundary, each fluid one counted as its mass over the particle's own (SPlisHSPlasH's
// count at one mass). The volume rule also solves spray that has just reached a wall (3 fluid and 13 wall
// neighbours read rho0): the stiffness that stopped it belongs to the impact, and half of it applied again in
// the next step threw the particle back faster than it came (mechanical energy gained in the dam break).
constexpr Real kMinNeighborsForWarmStart = Real(20);
// The factor's denominator |sum_j V_j grad W_ij|^2 + sum_j V_i V_j |grad W_ij|^2 counts the boundary in its
// first term only (walls do not move). Where boundary gradients cancel around a particle with few fluid
// neighbours (a pocket of a closing hand), it collapses to a few percent of a full neighbourhood's, and the
// particle's stiffness grows ten to twenty times (it was thrown out at 25-35 m/s, docs/robustness.md). The
// denominator is floored at this share of the same sum of squares with the boundary pairs counted as if
// they moved: a local under-relaxation that leaves the solution the solve converges to unchanged. It binds
// nowhere in the dam break, in 1.1e-4 of the particle-steps of the r = 5 mm hand tank with the splash hand
// (at its walls) and in 2.1e-4 of the propeller's (at its blades), whose run it takes from 481 steps to 511
// (0.2: 488), and 0.2 left 6 of 36 runs of the fist replay on the r = 5 mm tank above 5 m/s where 0.3 left
// one (docs/method.md, The factor's floor).
constexpr Real kMinFactorDenominatorShare = Real(0.3);
// A particle whose boundary neighbours alone fill this share of its rest density, and its fluid neighbours
// less than kCagedFluidDensity, is caged: shut in by boundary on nearly every side, as water in a closing
// fist is (water at a flat wall typically reads about 0.5 from it, in a corner of the tank 0.7). Over the
// first seconds of the dam break, the propeller and the hand tank with the splash and aggressive hands (20
// million particle-steps), the boundary reached 0.8 three times, each with more than 4 fluid neighbours; in
// the two-hand replay whose left hand closes into a fist under water, 64 particle-steps in 1.25 million did,
// all with 1-4 fluid neighbours giving at most 0.2. Such a particle cannot lower its density by moving (the
// cage is smaller than its spacing), and the solves made it rattle between the fist's walls ever faster as
// its speed shrank the step: 20-55 m/s, or an instability. It exerts no stiffness (its factor is zero) and
// moves with the cage (carryCaged). (Heavy particles jittered into the corners of a tank read 0.8-0.95 from
// the walls, but 0.6-0.8 from their fluid neighbours: they are not caged.) The cage must also hold a moving
// collider's particles: static walls cannot close, and a particle at them can always lower its density by
// leaving. A lone fine particle reads 0.8 from a flat wall at 0.8 r from its particles (at a tank's edge
// within about 1.4 r of both walls, in a corner within 1.65 r): caged by static walls, it would take their
// zero velocity and never leave, a droplet that a hand pressed on the tank's wall hanging on it for good.
// (Pressed on a moving collider alone, a palm, it would still be carried with it; no run has shown either:
// docs/method.md, A cage moves.)
constexpr Real kCagedBoundaryDensity = Real(0.8);
constexpr Real kCagedFluidDensity = Real(0.5);
// A small cluster shut in together (the fist replay on the r = 5 mm tank, seed 35: four particles, each with
// 1-3 fluid neighbours and the boundary giving 0.4-0.8 of the rest density, 1.1-1.25 in all): once the
// boundary alone cages some of it, the others count those neighbours as cage. A particle needs this much of
// its rest density from the boundary itself to be caged that way, so a cage never spreads into water that no
// boundary touches (a flat wall gives about 0.5). Only particles that the boundary alone caged count as cage
// (kFlagCaged): a cluster whose members counted each other would hold itself caged on one wall of an opened
// cage (a palm) and be carried with it.
constexpr Real kCagedClusterBoundaryDensity = Real(0.3);

using Range = tbb::blocked_range<std::size_t>;

/// Deterministic parallel sum of f(i) over [0, n).
template <class T, class F>
T deterministicSum(std::size_t n, T zero, F&& f) {
  return parallelDeterministicReduce(
      Range(0, n, kGrain), zero,
      [&](const Range& r, T acc) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
          acc += f(i);
        return acc;
      },
      [](T a, const T& b) { return a + b; });
}

/// Akinci 2013 cohesion spline C(r) with support h.
Real cohesion(Real r, Real h) {
  if (r >= h || r <= Real(0))
    return 0;
  const Real h3 = h * h * h;
  const Real k = Real(32.0 / kPi) / (h3 * h3 * h3);
  const Real t = (h - r) * (h - r) * (h - r) * r * r * r;
  if (Real(2) * r > h)
    return k * t;
  return k * (Real(2) * t - h3 * h3 / Real(64));
}

}  // namespace

double DfsphSolver::computeDensityAndFactor(SolverContext& ctx, LevelSums* levels) {
  if (ctx.params.viscosity > 0.0)
    return levels ? densityAndFactor<true, true>(ctx, levels) : densityAndFactor<false, true>(ctx, nullptr);
  return levels ? densityAndFactor<true, false>(ctx, levels) : densityAndFactor<false, false>(ctx, nullptr);
}

template <bool kLevelSums, bool kXsph>
double DfsphSolver::densityAndFactor(SolverContext& ctx, LevelSums* levels) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  m_xsphSize = kXsph ? n : kNoXsph;
  m_factor.resize(n);
  m_rate.resize(n);
  m_full.resize(n);
  m_caged.resize(n);
  resizeCache(m_gradF, ctx.fluidNbrs.entries());
  resizeCache(m_gradB, ctx.boundaryNbrs.entries());
  const Real rho0 = Real(ctx.params.restDensity);
  const Real invRho0 = Real(1) / rho0;
  const Real Hb = ctx.boundary.support();
  const Vec3* x = p.x.data();
  const Vec3* v = p.v.data();
  const Real* m = p.m.data();
  const Real* H = p.H.data();
  const std::uint32_t* flags = p.flags.data();
  const Vec3* xb = ctx.boundary.x.data();
  const Real* psi = ctx.boundary.psi.data();
  const std::uint32_t* fo = ctx.fluidNbrs.offsets.data();
  const std::uint32_t* bo = ctx.boundaryNbrs.offsets.data();
  const std::uint32_t* bi = ctx.boundaryNbrs.indices.data();
  // boundary particles from this index on belong to moving colliders (a list holds the static ones first:
  // its last entry says whether it holds a moving one)
  const std::uint32_t firstMoving = std::uint32_t(ctx.boundary.staticCount());
  Real* gF = m_gradF.data();
  Real* gB = m_gradB.data();
  [[maybe_unused]] const Real* rhoBefore = nullptr;
  if constexpr (kLevelSums) {
    levels->curl.resize(n);
    levels->nuSum.resize(n);
    levels->weightSum.resize(n);
    levels->rhoBefore.assign(p.rho.begin(), p.rho.end());
    rhoBefore = levels->rhoBefore.data();
  }
  // XSPH's neighbour sum (see nonPressureForces) from the kernel values of this pass, into fluid.a, with the
  // pair's volume m_j (1 / rho_i + 1 / rho_j) / 2 at the densities before the pass (which it overwrites;
  // their inverses are held in the stiffness scratch, free until the divergence solve). A density that no
  // pass gave (a state restored with a density of zero) counts as the rest density.
  [[maybe_unused]] const Real* invRhoPrev = nullptr;
  [[maybe_unused]] Vec3* xsph = p.a.data();
  if constexpr (kXsph) {
    m_k.resize(n);
    parallelFor(Range(0, n, kGrain), [&](const Range& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i)
        m_k[i] = p.rho[i] > Real(0) ? Real(1) / p.rho[i] : invRho0;
    });
    invRhoPrev = m_k.data();
  }
  // One pass evaluates every pair's kernel for the whole step: density, factor, the density rate the
  // divergence solve starts from, and V_j grad W_ij / (x_i - x_j) cached for the solves' ~12 further passes
  // (positions do not change until the step's end); on the steps that compute the levels, their sums too.
  // (fj(i, k): the neighbour of entry k of row i, for wide or narrow lists)
  const double compression = ctx.fluidNbrs.visit([&](auto fj) {
    return deterministicSum(n, 0.0, [&](std::size_t i) {
      const Vec3 xi = x[i];
      const Vec3 vi = v[i];
      const Real Hi = H[i];
      const Real Vi = m[i] * invRho0;
      const Real self = Vi * CubicSpline::w0(Hi);
      Real density = self;
      Vec3 gradSum = Vec3::Zero();
      Real sqSum = 0;
      Real rate = 0;
      Real neighborMass = 0;
      // the levels' sums (kLevelSums only)
      [[maybe_unused]] Vec3 curl = Vec3::Zero();
      [[maybe_unused]] Real nuSum = 0;
      [[maybe_unused]] Real weightSum = 0;
      [[maybe_unused]] Vec3 smooth = Vec3::Zero();  // (kXsph)
      [[maybe_unused]] const Real invRhoI = kXsph ? invRhoPrev[i] : Real(0);
      // (the neighbours' arrays addressed from the row's base: (x + i)[d] for narrow lists)
      const std::ptrdiff_t base = fj.base(i);
      const Real* mr = m + base;
      const Vec3* xr = x + base;
      const Real* Hr = H + base;
      const Vec3* vr = v + base;
      for (std::uint32_t k = fo[i]; k < fo[i + 1]; ++k) {
        const auto j = fj.offset(k);
        neighborMass += mr[j];
        const Vec3 xij = xi - xr[j];
        Real w, g;
        const Real r2 = xij.squaredNorm();
        CubicSpline::evaluate(std::sqrt(r2), pairSupport(Hi, Hr[j]), w, g);
        const Real Vj = mr[j] * invRho0;
        density += Vj * w;
        const Real vg = Vj * g;
        gF[k] = vg;
        const Vec3 gv = vg * xij;
        gradSum += gv;
        rate += gv.dot(vi - vr[j]);
        if constexpr (kXsph)
          smooth += (mr[j] * (invRhoI + invRhoPrev[base + j]) * w) * (vr[j] - vi);
        if constexpr (kLevelSums) {
          const Vec3 vji = vr[j] - vi;
          curl += vji.cross(gv);
          const Real wj = mr[j] / rhoBefore[base + j] * w;
          nuSum += wj * vji.norm();
          weightSum += wj;
        }
        // k_i moves neighbour j by V_i grad W (the pair update is symmetric), so the second term of alpha is
        // V_i V_j |grad W|^2, not V_j^2 |grad W|^2: the two differ as soon as masses do, and the latter
        // over-drives heavy particles among light. (As V_i (V_j g) g |x_ij|^2: written with the ratio V_i /
        // V_j times |V_j grad W|^2, its division a pair cost the density pass 14 % of its time.)
        sqSum += Vi * (vg * g) * r2;
      }
      const Real hb = pairSupport(Hi, Hb);
      const Real sb = ctx.boundary.volumeScale(Hi);
      Real sqBoundary = 0;  // the boundary pairs' V_i V_b |grad W|^2, for the floor only
      Real boundaryDensity = 0;
      for (std::uint32_t k = bo[i]; k < bo[i + 1]; ++k) {
        const std::uint32_t b = bi[k];
        const Vec3 xib = xi - xb[b];
        Real w, g;
        CubicSpline::evaluate(xib.norm(), hb, w, g);
        const Real wb = sb * psi[b] * w;
        density += wb;
        boundaryDensity += wb;
        const Real vg = sb * psi[b] * g;
        gB[k] = vg;
        const Vec3 gv = vg * xib;
        gradSum += gv;
        rate += gv.dot(vi - ctx.boundary.velocity(b));
        sqBoundary += Vi * (vg * g) * xib.squaredNorm();
      }
      p.rho[i] = density * rho0;
      m_rate[i] = rate;
      if constexpr (kXsph)
        xsph[i] = Real(0.5) * smooth;
      // the count, with half a neighbour of margin: equal masses give the integer count
      // whatever the rounding of their sum
      const Real boundaryCount = Real(bo[i + 1] - bo[i]);
      m_full[i] = neighborMass >= (kMinNeighborsForWarmStart - Real(0.5) - boundaryCount) * m[i];
      const Real denom =
          std::max(gradSum.squaredNorm() + sqSum, kMinFactorDenominatorShare * (sqSum + sqBoundary));
      // 1: caged by the boundary alone; 2: caged with a cluster that the boundary cages (see
      // kCagedClusterBoundaryDensity)
      std::uint8_t caged = boundaryDensity >= kCagedBoundaryDensity &&
                           density - boundaryDensity - self < kCagedFluidDensity &&
                           bi[bo[i + 1] - 1] >= firstMoving;  // (a share of 0.8 needs a non-empty list)
      if (!caged && boundaryDensity >= kCagedClusterBoundaryDensity &&
          density - self >= kCagedBoundaryDensity) {
        // fluid neighbours that the boundary alone caged in the last step move with the cage, not with this
        // particle's stiffness: their share counts as cage
        Real cage = 0;
        const std::uint32_t* fr = flags + base;
        for (std::uint32_t k = fo[i]; k < fo[i + 1]; ++k) {
          const auto j = fj.offset(k);
          if (fr[j] & kFlagCaged)
            cage += mr[j] * invRho0 * CubicSpline::w((xi - xr[j]).norm(), pairSupport(Hi, Hr[j]));
        }
        // (without such a neighbour this is the rule above, less its conditions on the cage itself)
        if (cage > Real(0) && boundaryDensity + cage >= kCagedBoundaryDensity &&
            density - boundaryDensity - self - cage < kCagedFluidDensity)
          caged = 2;
      }
      m_caged[i] = caged;
      m_factor[i] = denom > kEps && !m_caged[i] ? Real(1) / denom : Real(0);
      if (m_caged[i]) {  // nor a warm start: the stiffness it had when it was caged no longer pushes
        p.kappa[i] = 0;
        p.kappaV[i] = 0;
      }
      if constexpr (kLevelSums) {
        // curl sums m_j / rho0 (v_j - v_i) x grad W_ij
        levels->curl[i] = rho0 * curl.norm();
        levels->nuSum[i] = nuSum;
        levels->weightSum[i] = weightSum;
      }
      // (a held particle's density is not evaluated: its list is empty; it adds nothing here, and the caller
      // counts it with the density it was held with)
      return ctx.held && ctx.held[i] ? 0.0 : double(std::max(density - Real(1), Real(0)));
    });
  });
  if constexpr (kLevelSums) {
    std::vector<Real>().swap(levels->rhoBefore);
    levels->filled = true;
  }
  return compression / double(std::max<std::size_t>(n, 1));
}

template <class F>
double DfsphSolver::densityRatePass(const SolverContext& ctx, F&& stiffness) {
  const ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  const Vec3* x = p.x.data();
  const Vec3* v = p.v.data();
  const Vec3* xb = ctx.boundary.x.data();
  const std::uint32_t* fo = ctx.fluidNbrs.offsets.data();
  const std::uint32_t* bo = ctx.boundaryNbrs.offsets.data();
  const std::uint32_t* bi = ctx.boundaryNbrs.indices.data();
  const Real* gF = m_gradF.data();
  const Real* gB = m_gradB.data();
  return ctx.fluidNbrs.visit([&](auto fj) {
    return deterministicSum(n, 0.0, [&](std::size_t i) {
      const Vec3 xi = x[i];
      const Vec3 vi = v[i];
      Real rate = 0;
      // (the neighbours' arrays addressed from the row's base: (x + i)[d] for narrow lists)
      const Vec3* xr = x + fj.base(i);
      const Vec3* vr = v + fj.base(i);
      for (std::uint32_t k = fo[i]; k < fo[i + 1]; ++k) {
        const auto o = fj.offset(k);
        rate += gF[k] * (vi - vr[o]).dot(xi - xr[o]);
      }
      for (std::uint32_t k = bo[i]; k < bo[i + 1]; ++k) {
        const std::uint32_t b = bi[k];
        rate += gB[k] * (vi - ctx.boundary.velocity(b)).dot(xi - xb[b]);
      }
      m_rate[i] = rate;
      return double(stiffness(i, rate));
    });
  });
}

Vec3d DfsphSolver::applyStiffness(SolverContext& ctx, Real dt, std::vector<Real>& accumulated) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  const Vec3* x = p.x.data();
  Vec3* v = p.v.data();
  const Real* m = p.m.data();
  const Real* k = m_k.data();
  const Vec3* xb = ctx.boundary.x.data();
  const std::uint32_t* fo = ctx.fluidNbrs.offsets.data();
  const std::uint32_t* bo = ctx.boundaryNbrs.offsets.data();
  const std::uint32_t* bi = ctx.boundaryNbrs.indices.data();
  const Real* gF = m_gradF.data();
  const Real* gB = m_gradB.data();
  return ctx.fluidNbrs.visit([&](auto fj) {
    return deterministicSum(n, Vec3d(Vec3d::Zero()), [&](std::size_t i) -> Vec3d {
      const Vec3 xi = x[i];
      const Real ki = k[i];
      accumulated[i] += ki;
      Vec3 dv = Vec3::Zero();
      // every pair, also those with k_i + k_j = 0 (no branch: in the divergence solve most stiffnesses are
      // zero, and a test per pair mispredicted; a zero term leaves dv exactly as it was)
      // (the neighbours' arrays addressed from the row's base: (x + i)[d] for narrow lists)
      const Vec3* xr = x + fj.base(i);
      const Real* kr = k + fj.base(i);
      for (std::uint32_t q = fo[i]; q < fo[i + 1]; ++q) {
        const auto o = fj.offset(q);
        dv -= ((ki + kr[o]) * gF[q]) * (xi - xr[o]);
      }
      Vec3 dvb = Vec3::Zero();
      if (ki != Real(0)) {
        // Akinci 2012: the boundary mirrors the particle's own pressure
        for (std::uint32_t q = bo[i]; q < bo[i + 1]; ++q)
          dvb -= (ki * gB[q]) * (xi - xb[bi[q]]);
      }
      v[i] += dt * (dv + dvb);
      return double(m[i]) * double(dt) * dvb.cast<double>();
    });
  });
}

SolveResult DfsphSolver::divergenceSolve(SolverContext& ctx, Real dt) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  if (n == 0)
    return {};
  m_k.resize(n);
  const std::uint8_t* full = m_full.data();
  const Real* rho = p.rho.data();
  const Real* factor = m_factor.data();
  Real* kv = p.kappaV.data();
  // only expansion-free motion is enforced: compression (positive rate) is corrected, and only in full
  // neighbourhoods (by volume, see kMinDensityRatioForDivergence), as in Bender & Koschier's reference
  // implementation
  const Real minRho = kMinDensityRatioForDivergence * Real(ctx.params.restDensity);
  // (a caged particle's rate is not this solve's to correct: it has no stiffness to correct it with)
  const std::uint8_t* caged = m_caged.data();
  auto clampRate = [&](std::size_t i, Real rate) {
    return rho[i] < minRho || caged[i] ? Real(0) : std::max(rate, Real(0));
  };
  const double tolerance = ctx.params.divergenceTolerance * 0.01;
  const Real invDt = Real(1) / dt;
  // the density pass left the rate of the current velocities in m_rate; the warm start skips particles whose
  // neighbourhood is sparse by count (kMinNeighborsForWarmStart)
  if (ctx.params.warmStart) {
    parallelFor(Range(0, n, kGrain), [&](const Range& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        m_k[i] = full[i] && clampRate(i, m_rate[i]) > 0 ? Real(0.5) * kv[i] * invDt : Real(0);
        kv[i] = 0;
      }
    });
    m_boundaryImpulse += applyStiffness(ctx, dt, p.kappaV);
  } else {
    std::fill(p.kappaV.begin(), p.kappaV.end(), Real(0));
  }
  SolveResult result;
  auto stiffness = [&](std::size_t i, Real rate) {
    const Real clamped = clampRate(i, rate);
    m_k[i] = clamped * factor[i] * invDt;
    return clamped;
  };
  // without a warm start the rates are still those of the density pass
  bool fresh = !ctx.params.warmStart;
  for (;;) {
    double sum;
    if (fresh) {
      sum = deterministicSum(n, 0.0, [&](std::size_t i) { return double(stiffness(i, m_rate[i])); });
      fresh = false;
    } else {
      sum = densityRatePass(ctx, stiffness);
    }
    // (held particles add nothing: the mean is over the others, as the density solve's)
    result.error = sum / double(std::max<std::size_t>(1, n - std::min(n, ctx.heldCount))) * double(dt);
    // at least one iteration, as in the reference implementation (min_iterations applies to the density
    // solve)
    if ((result.iterations >= 1 && result.error <= tolerance) ||
        result.iterations >= ctx.params.maxIterations)
      break;
    m_boundaryImpulse += applyStiffness(ctx, dt, p.kappaV);
    ++result.iterations;
  }
  // stored per unit time step so that the warm start survives a change of dt
  parallelFor(Range(0, n, kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      kv[i] *= dt;
  });
  return result;
}

SolveResult DfsphSolver::densitySolve(SolverContext& ctx, Real dt) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  if (n == 0)
    return {};
  m_k.resize(n);
  const Real invRho0 = Real(1) / Real(ctx.params.restDensity);
  const Real invDt2 = Real(1) / (dt * dt);
  const Real* rho = p.rho.data();
  const Real* factor = m_factor.data();
  Real* kappa = p.kappa.data();
  auto predicted = [&](std::size_t i, Real rate) { return std::max(rho[i] * invRho0 + dt * rate, Real(1)); };
  const double tolerance = ctx.params.densityTolerance * 0.01;
  if (ctx.params.warmStart) {
    densityRatePass(ctx, [&](std::size_t i, Real rate) {
      m_k[i] = predicted(i, rate) > Real(1) ? Real(0.5) * kappa[i] : Real(0);
      kappa[i] = 0;
      return Real(0);
    });
    m_boundaryImpulse += applyStiffness(ctx, dt, p.kappa);
  } else {
    std::fill(p.kappa.begin(), p.kappa.end(), Real(0));
  }
  SolveResult result;
  for (;;) {
    const std::uint8_t* held = ctx.held;
    const std::uint8_t* caged = m_caged.data();
    const double sum = densityRatePass(ctx, [&](std::size_t i, Real rate) {
      // (a held particle's density is the one it was held with, a caged one's is beyond any stiffness of its
      // own: neither is this solve's to correct)
      const Real error = (held && held[i]) || caged[i] ? Real(0) : predicted(i, rate) - Real(1);
      m_k[i] = error * factor[i] * invDt2;
      return error;
    });
    result.error = sum / double(std::max<std::size_t>(1, n - std::min(n, ctx.heldCount)));
    if ((result.iterations >= ctx.params.minIterations && result.error <= tolerance) ||
        result.iterations >= ctx.params.maxIterations) {
      break;
    }
    m_boundaryImpulse += applyStiffness(ctx, dt, p.kappa);
    ++result.iterations;
  }
  return result;
}

void DfsphSolver::nonPressureForces(SolverContext& ctx, Real dtPrevious) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  const SimParams& prm = ctx.params;
  const Vec3 gravity(Real(prm.gravity[0]), Real(prm.gravity[1]), Real(prm.gravity[2]));
  const Real rho0 = Real(prm.restDensity);
  const Real Hb = ctx.boundary.support();
  // XSPH (Monaghan 1989, as in SPlisHSPlasH's Viscosity_XSPH): a velocity smoothing of strength c per step,
  // written as an acceleration c/dt. Unlike an explicit Laplacian it is stable for any step size (a Laplacian
  // with nu = 0.01 m^2/s needs dt < 1 ms at r = 5 mm and made corner particles jet in the tank at rest).
  const Real invDt = dtPrevious > 0 ? Real(1) / dtPrevious : Real(0);
  const Real cVisc = Real(prm.viscosity) * invDt;
  // The density pass of this step left XSPH's neighbour sum in fluid.a (unless it ran without XSPH, or a
  // caller did not run it); otherwise the pair loop below evaluates it, with the densities of now.
  const bool xsphGiven = cVisc > 0 && m_xsphSize == n;
  m_xsphSize = kNoXsph;
  const Real cBVisc = Real(prm.boundaryViscosity) * invDt;
  const Real gamma = Real(prm.surfaceTension);
  // Laminar viscosity (Monaghan 1992 / Morris 1997 as SPlisHSPlasH's Viscosity_Standard, which the reference
  // dam break runs with nu = 0.01 m^2/s): a_i += 2 (d + 2) nu sum_j m_j / rho_ij (v_ij . x_ij) /
  // (|x_ij|^2 + 0.01 H^2) grad W_ij, with d = 3.
  const Real nu10 = Real(10) * Real(prm.laminarViscosity);
  const Real* gF = m_gradF.data();
  const Vec3* x = p.x.data();
  const Vec3* v = p.v.data();
  const Real* m = p.m.data();
  const Real* H = p.H.data();
  const Real* rho = p.rho.data();
  const Vec3* xb = ctx.boundary.x.data();
  const Real* psi = ctx.boundary.psi.data();
  const std::uint32_t* fo = ctx.fluidNbrs.offsets.data();
  const std::uint32_t* bo = ctx.boundaryNbrs.offsets.data();
  const std::uint32_t* bi = ctx.boundaryNbrs.indices.data();

  // (fj(i, q): the neighbour of entry q of row i, for wide or narrow lists)
  ctx.fluidNbrs.visit([&](auto fj) {
    if (gamma > 0) {
      // Akinci 2013 normals n_i = H_i sum_j m_j / rho_j grad W_ij
      m_normal.resize(n);
      parallelFor(Range(0, n, kGrain), [&](const Range& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          Vec3 nrm = Vec3::Zero();
          for (std::uint32_t q = fo[i]; q < fo[i + 1]; ++q) {
            const auto j = fj(i, q);
            const Vec3 xij = x[i] - x[j];
            nrm += (m[j] / rho[j] * CubicSpline::gradFactor(xij.norm(), pairSupport(H[i], H[j]))) * xij;
          }
          m_normal[i] = H[i] * nrm;
        }
      });
    }

    // The explicit update is stable while dt times a particle's damping rate D_i = sum_j |c_ij| |x_ij|^2
    // stays below one (D_i is about 8.5 * 10 nu / H^2 in a full neighbourhood: 485 1/s at r = 10.5 mm, 2,100
    // 1/s at r = 5 mm). Each pair is scaled by min(1, 1 / (dt max(D_i, D_j))): symmetric, so momentum stays
    // exact, and inactive at the small steps of a fast flow. dt is the previous step, the one the CFL step
    // starts from. m_viscRate holds 1 / D_i, so the limit costs no division a pair, and both pair loops
    // divide once a pair: c_ij = 2 nu10 rho0 gF_ij / ((rho_i + rho_j) (|x_ij|^2 + 0.01 H^2)).
    const Real* invRate = m_viscRate.data();
    Real laminarLimit = 0;
    const Real laminarScale = Real(2) * nu10 * rho0;
    if (nu10 > 0) {
      m_viscRate.resize(n);
      laminarLimit = Real(1) / Real(dtPrevious > 0 ? dtPrevious : prm.dtMax);
      invRate = m_viscRate.data();
      parallelFor(Range(0, n, kGrain), [&](const Range& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          Real d = 0;
          const Vec3* xr = x + fj.base(i);
          const Real* Hr = H + fj.base(i);
          const Real* rhor = rho + fj.base(i);
          for (std::uint32_t q = fo[i]; q < fo[i + 1]; ++q) {
            const auto o = fj.offset(q);
            const Real r2 = (x[i] - xr[o]).squaredNorm();
            const Real h = pairSupport(H[i], Hr[o]);
            d -= gF[q] * r2 / ((rho[i] + rhor[o]) * (r2 + Real(0.01) * h * h));
          }
          m_viscRate[i] = Real(1) / std::max(laminarScale * d, kEps);
        }
      });
    }
    // (the pairs only for what the density pass did not give)
    const Real cPairVisc = xsphGiven ? Real(0) : cVisc;
    const bool pairTerms = cPairVisc > 0 || nu10 > 0 || gamma > 0;
    const bool pairDistance = cPairVisc > 0 || gamma > 0;  // (the laminar term needs only its square)
    m_boundaryForce = deterministicSum(n, Vec3d(Vec3d::Zero()), [&](std::size_t i) -> Vec3d {
      const Vec3 xi = x[i];
      const Vec3 vi = v[i];
      const Real Hi = H[i];
      Vec3 ai = gravity;
      if (xsphGiven)
        ai += cVisc * p.a[i];
      const std::ptrdiff_t base = fj.base(i);
      const Vec3* xr = x + base;
      const Vec3* vr = v + base;
      const Real* mr = m + base;
      const Real* Hr = H + base;
      const Real* rhor = rho + base;
      const Real* invRater = nu10 > 0 ? invRate + base : invRate;  // (no offset from a null pointer)
      for (std::uint32_t q = fo[i]; pairTerms && q < fo[i + 1]; ++q) {
        const auto j = fj.offset(q);
        const Vec3 xij = xi - xr[j];
        const Real h = pairSupport(Hi, Hr[j]);
        const Real r2 = xij.squaredNorm();
        const Real r = pairDistance ? std::sqrt(r2) : Real(0);
        // the pair density is the mean of both, so m_i a_i = -m_j a_j across resolutions
        const Real rhoij = Real(0.5) * (rho[i] + rhor[j]);
        if (cPairVisc > 0)
          ai += (cPairVisc * mr[j] / rhoij * CubicSpline::w(r, h)) * (vr[j] - vi);
        if (nu10 > 0) {
          // laminar viscosity, limited per pair where the step would make the explicit update overshoot
          const Real c = laminarScale * gF[q] / ((rho[i] + rhor[j]) * (r2 + Real(0.01) * h * h));
          const Real limit = std::min(Real(1), laminarLimit * std::min(invRate[i], invRater[j]));
          ai += (limit * c * (vi - vr[j]).dot(xij)) * xij;
        }
        if (gamma > 0) {
          const Real Kij = rho0 / rhoij;
          const Real mbar = Real(0.5) * (m[i] + mr[j]);
          Vec3 f = Vec3::Zero();
          if (r > Real(1e-6) * h)
            f += (mr[j] * cohesion(r, h) / r) * xij;
          f += (mbar / m[i]) * (m_normal[i] - m_normal[fj(i, q)]);
          ai -= gamma * Kij * f;
        }
      }
      Vec3 ab = Vec3::Zero();
      if (cBVisc > 0) {
        const Real hb = pairSupport(Hi, Hb);
        const Real sb = ctx.boundary.volumeScale(Hi);
        for (std::uint32_t q = bo[i]; q < bo[i + 1]; ++q) {
          const std::uint32_t b = bi[q];
          ab += (cBVisc * rho0 * sb * psi[b] / rho[i] * CubicSpline::w((xi - xb[b]).norm(), hb)) *
                (ctx.boundary.velocity(b) - vi);
        }
      }
      p.a[i] = ai + ab;
      return double(m[i]) * ab.cast<double>();
    });
  });
}

Real DfsphSolver::cflTimeStep(const SolverContext& ctx, Real dtPrevious) const {
  const ParticleSet& p = ctx.fluid;
  const std::size_t n = p.size();
  // min over particles of (2 r_i) / |v_i + a_i dt|, with 2 r_i = H_i / 2; min is exact in any order
  const Real limit = parallelReduce(
      Range(0, n, kGrain), std::numeric_limits<Real>::max(),
      [&](const Range& r, Real acc) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          const Real speed = (p.v[i] + dtPrevious * p.a[i]).norm();
          if (speed > Real(0))
            acc = std::min(acc, Real(0.5) * p.H[i] / speed);
        }
        return acc;
      },
      [](Real a, Real b) { return std::min(a, b); });
  // Moving colliders too (as the reference does for animated boundaries): a hand at 2.5 m/s crosses its
  // single layer of boundary particles in less than a 5 ms step, and the water leaks through it.
  const BoundarySet& b = ctx.boundary;
  const Real wallLimit = parallelReduce(
      Range(b.staticCount(), b.size(), kGrain), std::numeric_limits<Real>::max(),
      [&](const Range& r, Real acc) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
          const Real speed = b.velocity(k).norm();
          if (speed > Real(0))
            acc = std::min(acc, Real(0.5) * b.support() / speed);
        }
        return acc;
      },
      [](Real a, Real c) { return std::min(a, c); });
  const double dt = double(ctx.params.cflFactor) * double(std::min(limit, wallLimit));
  return Real(std::clamp(dt, ctx.params.dtMin, ctx.params.dtMax));
}

void DfsphSolver::integrateVelocities(SolverContext& ctx, Real dt) {
  ParticleSet& p = ctx.fluid;
  parallelFor(Range(0, p.size(), kGrain), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      p.v[i] += dt * p.a[i];
  });
}

void DfsphSolver::resizeCache(std::vector<Real>& cache, std::size_t n) {
  // a little room beyond the count, so that lists that grow by a few pairs do not reallocate every step
  if (cache.capacity() < n)
    cache.reserve(n + n / 16);
  cache.resize(n);
}

void DfsphSolver::shrinkToFit() {
  for (std::vector<Real>* v : {&m_factor, &m_rate, &m_k, &m_gradF, &m_gradB, &m_viscRate})
    v->shrink_to_fit();
  m_full.shrink_to_fit();
  m_caged.shrink_to_fit();
  m_cagedList.shrink_to_fit();
  m_normal.shrink_to_fit();
}

std::size_t DfsphSolver::carryCaged(SolverContext& ctx) {
  ParticleSet& p = ctx.fluid;
  const std::size_t n = std::min(p.size(), m_caged.size());
  // the particles caged now, and those caged in the last step
  parallelSelect(n, 4096, m_cagedList,
                 [&](std::size_t i) { return m_caged[i] != 0 || (p.flags[i] & kFlagCaged) != 0; });
  // the next density pass reads who the boundary alone cages now (a cluster shut in together,
  // kCagedClusterBoundaryDensity); a particle held in this step (time levels) was not evaluated and keeps its
  // bit
  std::size_t count = 0;
  for (const std::uint32_t i : m_cagedList) {
    count += m_caged[i] != 0;
    if (m_caged[i] == 1)
      p.flags[i] |= kFlagCaged;
    else if (!(ctx.held && ctx.held[i]))
      p.flags[i] &= ~std::uint32_t(kFlagCaged);
  }
  if (count == 0)
    return 0;
  const Real Hb = ctx.boundary.support();
  const Vec3* xb = ctx.boundary.x.data();
  const Real* psi = ctx.boundary.psi.data();
  const std::uint32_t* bo = ctx.boundaryNbrs.offsets.data();
  const std::uint32_t* bi = ctx.boundaryNbrs.indices.data();
  // the cage's velocity at the particle: its boundary neighbours' velocities weighted as in its density
  m_boundaryImpulse += deterministicSum(m_cagedList.size(), Vec3d(Vec3d::Zero()), [&](std::size_t k) {
    const std::uint32_t i = m_cagedList[k];
    if (!m_caged[i])
      return Vec3d(Vec3d::Zero());
    const Real hb = pairSupport(p.H[i], Hb);
    Vec3 weighted = Vec3::Zero();
    Real weight = 0;
    for (std::uint32_t e = bo[i]; e < bo[i + 1]; ++e) {
      const std::uint32_t b = bi[e];
      const Real w = psi[b] * CubicSpline::w((p.x[i] - xb[b]).norm(), hb);
      weighted += w * ctx.boundary.velocity(b);
      weight += w;
    }
    if (!(weight > Real(0)))
      return Vec3d(Vec3d::Zero());
    const Vec3 carried = weighted / weight;
    const Vec3d given = double(p.m[i]) * (carried.cast<double>() - p.v[i].cast<double>());
    p.v[i] = carried;
    return given;
  });
  return count;
}

std::size_t DfsphSolver::memoryBytes() const {
  return (m_factor.capacity() + m_rate.capacity() + m_k.capacity() + m_gradF.capacity() + m_gradB.capacity() +
          m_viscRate.capacity()) *
             sizeof(Real) +
         m_full.capacity() + m_caged.capacity() + m_cagedList.capacity() * sizeof(std::uint32_t) +
         m_normal.capacity() * sizeof(Vec3);
}

}  // namespace fp::sim
