#include "sim/adaptivity.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "sim/kernels.h"
#include "sim/levels.h"
#include "sim/parallel.h"
#include "sim/signed_distance.h"
#include "sim/split_templates.h"

namespace fp::sim {

namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

double uniform01(std::uint64_t& state) {
  state = splitmix(state);
  return double(state >> 11) * (1.0 / 9007199254740992.0);
}

// Orientation refinement (planSplit): the first try's angle [rad], the factor the angle is multiplied by
// after a try that does not improve, and where the tries' axes start in the candidates' hash stream. The hash
// keeps the low 8 bits of the index: candidates are 0..kMaxCandidates-1, tries
// kRefineStream..kRefineStream+kMaxTries-1, all below 256 and apart.
constexpr double kRefineAngle = 0.8;
constexpr double kRefineShrink = 0.7;
constexpr int kMaxCandidates = 64;  // the parameter table's limit of orientation_candidates
constexpr int kMaxTries = 64;       // and of orientation_refinement
constexpr int kRefineStream = kMaxCandidates;
constexpr int kMaxPositionSteps = 16;  // the parameter table's limit of split_position_steps
// the first move of the position refinement: the largest child moves this far, in child radii
constexpr double kPositionStep = 0.1;
// The position refinement keeps every two children at least this share of a child's diameter apart. With
// 0.6 the propeller's largest splash height grew with the steps (29 mm at 0 steps, 37 at 4, 46 at 6, three
// runs each): children pressed together under the parent's support are close under their own.
constexpr double kMinChildSpacing = 0.85;
static_assert(kRefineStream >= kMaxCandidates && kRefineStream + kMaxTries <= 256);

// The most of a receiver's mass one adaptation step moves into it when the adaptation period scales the
// transfer rate (transferMass; a transfer_rate above it is kept as set).
constexpr double kMaxTransferPerAdaptation = 0.1;

/// Candidate k of a split: the identity for k = 0 (the unrotated template), else a uniformly random rotation
/// (Shoemake 1992) drawn from the seed, the parent's id and the step, so runs are reproducible.
Quatd candidateRotation(std::uint64_t seed, std::uint32_t id, std::uint64_t step, int k) {
  if (k == 0)
    return Quatd::Identity();
  std::uint64_t state = splitmix(seed ^ splitmix(std::uint64_t(id) << 20 ^ step) ^ std::uint64_t(k) << 56);
  const double u1 = uniform01(state);
  const double u2 = 2.0 * kPi * uniform01(state);
  const double u3 = 2.0 * kPi * uniform01(state);
  const double a = std::sqrt(1.0 - u1);
  const double b = std::sqrt(u1);
  return Quatd(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)).normalized();
}

int childCount(Real q, const SimParams& params) {
  const int nMax = std::min(params.splitMaxChildren, SplitTemplates::kMaxChildren);
  // a tiny tolerance keeps q = 3 (to round-off) at three children
  const int n = int(std::ceil(double(q) - 1e-4));
  return std::clamp(n, SplitTemplates::kMinChildren, nMax);
}

}  // namespace

AdaptivityStats& AdaptivityStats::operator+=(const AdaptivityStats& o) {
  splits += o.splits;
  children += o.children;
  merges += o.merges;
  redistributions += o.redistributions;
  splitsBlocked += o.splitsBlocked;
  splitsCompared += o.splitsCompared;
  splitErrorChosen += o.splitErrorChosen;
  splitErrorRotated += o.splitErrorRotated;
  splitErrorUnrotated += o.splitErrorUnrotated;
  return *this;
}

std::vector<Vec3> Adaptivity::childPositions(const AdaptContext& ctx, std::size_t o, int n,
                                             const Quatd& rot) {
  const ParticleSet& p = ctx.fluid;
  const double radius = ctx.params.particleRadius * std::cbrt(double(p.m[o]) / double(ctx.mFine));
  const Vec3d centre = p.x[o].cast<double>();
  std::vector<Vec3> x;
  x.reserve(std::size_t(n));
  for (const Vec3d& offset : SplitTemplates::get().offsets(n))
    x.push_back((centre + radius * (rot * offset)).cast<Real>());
  return x;
}

namespace {

/// What splitError() evaluates of one parent, the same for every candidate orientation of its split: per
/// fluid neighbour its position, the kernel constants of its pair support with the parent (which is the
/// children's: they start with the parent's support), its volume and the parent's own term of its density
/// change; per boundary neighbour its position and pair-scaled volume. planSplit() gathers them once for its
/// up to orientation_candidates + orientation_refinement candidates. Every term is rounded as the direct sums
/// round it, so the errors are the same bit for bit.
class SplitErrorTerms {
 public:
  SplitErrorTerms(const AdaptContext& ctx, std::size_t o, std::size_t children) : m_children(children) {
    const ParticleSet& p = ctx.fluid;
    const Real rho0 = Real(ctx.params.restDensity);
    const Real Vo = p.m[o] / rho0;
    m_Vs = Vo / Real(children);
    const Real Ho = p.H[o];
    // The error of the state the solver then simulates: a split gives its children the parent's support,
    // which blends down to their own over the following steps (blendSupports).
    const Real Hs = Ho;
    m_invHs = Real(1) / Hs;
    m_kHs = CubicSpline::factor(m_invHs);
    const Real Hsb = pairSupport(Hs, ctx.boundary.support());
    m_invHsb = Real(1) / Hsb;
    m_kHsb = CubicSpline::factor(m_invHsb);
    const std::uint32_t f0 = ctx.fluidNbrs.offsets[o], f1 = ctx.fluidNbrs.offsets[o + 1];
    m_fluid.resize(f1 - f0);
    // the kernel terms as columns for error()'s kernel loop, padded with neighbours out of reach (W = 0)
    m_padded = (m_fluid.size() + kLanes - 1) / kLanes * kLanes;
    m_columns.assign(6 * m_padded, Real(0));
    std::fill_n(column(kReach2), m_padded, Real(-1));
    for (std::uint32_t k = f0; k < f1; ++k) {
      const std::uint32_t j = ctx.fluidNbrs.neighbor(o, k);
      const std::size_t c = k - f0;
      Fluid& f = m_fluid[c];
      f.x = p.x[j];
      const Real H = pairSupport(p.H[j], Ho);
      f.invH = Real(1) / H;
      f.volume = p.m[j] / rho0;
      f.tau0 = -double(Vo) * CubicSpline::w((p.x[j] - p.x[o]).norm(), H);
      column(kX)[c] = f.x.x();
      column(kY)[c] = f.x.y();
      column(kZ)[c] = f.x.z();
      column(kInvH)[c] = f.invH;
      column(kFactor)[c] = CubicSpline::factor(f.invH);
      // beyond (1 + 5e-5) H the kernel is zero for certain (q >= 1 however r and 1 / H round)
      column(kReach2)[c] = H * H * Real(1.0001);
    }
    const double sb = double(ctx.boundary.volumeScale(Hs));
    const std::uint32_t b0 = ctx.boundaryNbrs.offsets[o], b1 = ctx.boundaryNbrs.offsets[o + 1];
    m_walls.resize(b1 - b0);
    for (std::uint32_t k = b0; k < b1; ++k) {
      const std::uint32_t b = ctx.boundaryNbrs.indices[k];
      m_walls[k - b0] = Wall{ctx.boundary.x[b], sb * double(ctx.boundary.psi[b])};
    }
    m_keep = 1.0 - double(Adaptivity::splitBlendWeight(0, ctx.params.splitBlendSteps));
    m_target = double(p.rho[o]) / double(rho0);
  }

  /// E of the children at `children` (as many as the constructor was given), stopping once the partial sum
  /// exceeds `bound` (see Adaptivity::splitError)
  double error(const std::vector<Vec3>& children, double bound) const {
    // (as many children as the terms were gathered for: their volume V_s is the parent's over that count)
    const std::size_t n = m_children;
    assert(children.size() == n);
    const std::size_t nf = m_fluid.size();
    const std::size_t padded = m_padded;
    // W between each child and each fluid neighbour, a row per child over the neighbours (kernelRow). The
    // neighbours' sums use them first, the children's sums then reuse them (|x_j - x_s| is |x_s - x_j|, the
    // pair support symmetric).
    thread_local std::vector<Real> wFluid;
    thread_local std::vector<Real> wChildren;
    wFluid.resize(n * padded);
    for (std::size_t s = 0; s < n; ++s)
      kernelRow(children[s], wFluid.data() + s * padded);
    double e = 0.0;
    // tau_j: the neighbours' density change
    for (std::size_t k = 0; k < nf; ++k) {
      double tau = m_fluid[k].tau0;
      for (std::size_t s = 0; s < n; ++s)
        tau += double(m_Vs) * wFluid[s * padded + k];
      e += tau * tau;
      if (e > bound)
        return e;
    }
    // tau_s: the children's density error against the parent's density; W between children is symmetric
    wChildren.resize(n * n);
    for (std::size_t s = 0; s < n; ++s) {
      // (as |x_s - x_s|, so that a child at a non-finite position gives what the direct sum gives)
      wChildren[s * n + s] = CubicSpline::wScaled((children[s] - children[s]).norm(), m_invHs, m_kHs);
      for (std::size_t t = s + 1; t < n; ++t) {
        const Real w = CubicSpline::wScaled((children[s] - children[t]).norm(), m_invHs, m_kHs);
        wChildren[s * n + t] = w;
        wChildren[t * n + s] = w;
      }
    }
    for (std::size_t s = 0; s < n; ++s) {
      const Vec3& xs = children[s];
      double rho = 0.0;
      for (std::size_t t = 0; t < n; ++t)
        rho += double(m_Vs) * wChildren[s * n + t];
      for (std::size_t k = 0; k < nf; ++k)
        rho += double(m_fluid[k].volume) * wFluid[s * padded + k];
      for (const Wall& b : m_walls)
        rho += b.volume * CubicSpline::wScaled((xs - b.x).norm(), m_invHsb, m_kHsb);
      // with temporal blending the solver sees the child's density moved (beta) towards the parent's, which
      // at the split is the target: its error enters at (1 - beta)
      const double tau = m_keep * (rho - m_target);
      e += tau * tau;
      if (e > bound)
        return e;
    }
    return e;
  }

  /// E of the children at `children` and its gradient with respect to each child's position, in `gradient`
  /// [1/m]. The kernels are evaluated in double precision here (the descent only needs the direction), so
  /// the value returned may differ from error()'s in the last digits.
  double errorAndGradient(const std::vector<Vec3d>& children, std::vector<Vec3d>& gradient) const {
    const std::size_t n = m_children;
    const std::size_t nf = m_fluid.size();
    thread_local std::vector<double> wf, gf, wc, gc, tauJ, tauS;
    wf.resize(nf * n);
    gf.resize(nf * n);
    wc.resize(n * n);
    gc.resize(n * n);
    tauJ.resize(nf);
    tauS.resize(n);
    const double Vs = m_Vs;
    double e = 0.0;
    for (std::size_t k = 0; k < nf; ++k) {
      const Fluid& f = m_fluid[k];
      const Vec3d xj = f.x.cast<double>();
      double tau = f.tau0;
      for (std::size_t s = 0; s < n; ++s) {
        kernelAndGradient((children[s] - xj).norm(), f.invH, wf[k * n + s], gf[k * n + s]);
        tau += Vs * wf[k * n + s];
      }
      tauJ[k] = tau;
      e += tau * tau;
    }
    for (std::size_t s = 0; s < n; ++s) {
      for (std::size_t t = s; t < n; ++t) {
        double w, g;
        kernelAndGradient((children[s] - children[t]).norm(), m_invHs, w, g);
        wc[s * n + t] = wc[t * n + s] = w;
        gc[s * n + t] = gc[t * n + s] = g;
      }
    }
    gradient.assign(n, Vec3d::Zero());
    for (std::size_t s = 0; s < n; ++s) {
      double rho = 0.0;
      for (std::size_t t = 0; t < n; ++t)
        rho += Vs * wc[s * n + t];
      Vec3d dRho = Vec3d::Zero();  // d rho_s / d x_s from the neighbours and walls
      for (std::size_t k = 0; k < nf; ++k) {
        const Fluid& f = m_fluid[k];
        const Vec3d d = children[s] - f.x.cast<double>();
        rho += double(f.volume) * wf[k * n + s];
        dRho += double(f.volume) * gf[k * n + s] * d;
        // tau_j's dependence on x_s
        gradient[s] += 2.0 * tauJ[k] * Vs * gf[k * n + s] * d;
      }
      for (const Wall& b : m_walls) {
        const Vec3d d = children[s] - b.x.cast<double>();
        double w, g;
        kernelAndGradient(d.norm(), m_invHsb, w, g);
        rho += b.volume * w;
        dRho += b.volume * g * d;
      }
      tauS[s] = m_keep * (rho - m_target);
      e += tauS[s] * tauS[s];
      gradient[s] += 2.0 * tauS[s] * m_keep * dRho;
    }
    // the children's mutual terms: W(x_s - x_t) enters rho_s and rho_t
    for (std::size_t s = 0; s < n; ++s) {
      for (std::size_t t = 0; t < n; ++t) {
        if (t == s)
          continue;
        const Vec3d d = children[s] - children[t];
        gradient[s] += 2.0 * m_keep * (tauS[s] + tauS[t]) * Vs * gc[s * n + t] * d;
      }
    }
    return e;
  }

 private:
  /// W(x_j - c, H_j) for every fluid neighbour j (and 0 for the padding), into row[0, m_padded): each value
  /// rounded as CubicSpline::wScaled(|x_j - c|) rounds it, with |.| as Eigen's norm() sums the squares, and 0
  /// beyond the reach. Four neighbours at a time with SSE2 (every x86-64), without branches.
  void kernelRow(const Vec3& c, Real* row) const {
    const Real* fx = column(kX);
    const Real* fy = column(kY);
    const Real* fz = column(kZ);
    const Real* fInvH = column(kInvH);
    const Real* fFactor = column(kFactor);
    const Real* fReach2 = column(kReach2);
#if defined(__SSE2__)
    const __m128 cx = _mm_set1_ps(c.x()), cy = _mm_set1_ps(c.y()), cz = _mm_set1_ps(c.z());
    const __m128 one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f), six = _mm_set1_ps(6.0f);
    const __m128 half = _mm_set1_ps(0.5f);
    for (std::size_t k = 0; k < m_padded; k += 4) {
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(fx + k), cx);
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(fy + k), cy);
      const __m128 dz = _mm_sub_ps(_mm_loadu_ps(fz + k), cz);
      const __m128 d2 = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_add_ps(_mm_mul_ps(dy, dy), _mm_mul_ps(dz, dz)));
      const __m128 q = _mm_mul_ps(_mm_sqrt_ps(d2), _mm_loadu_ps(fInvH + k));
      const __m128 t = _mm_sub_ps(one, q);
      const __m128 factor = _mm_loadu_ps(fFactor + k);
      // k (6 q q (q - 1) + 1) for q <= 1/2, k 2 t t t (t = 1 - q) for q < 1, else 0
      const __m128 inner = _mm_mul_ps(
          factor, _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_mul_ps(six, q), q), _mm_sub_ps(q, one)), one));
      const __m128 outer = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(_mm_mul_ps(factor, two), t), t), t);
      const __m128 isInner = _mm_cmple_ps(q, half);
      const __m128 isOuter = _mm_cmplt_ps(q, one);
      const __m128 w =
          _mm_or_ps(_mm_and_ps(isInner, inner), _mm_andnot_ps(isInner, _mm_and_ps(isOuter, outer)));
      _mm_storeu_ps(row + k, _mm_andnot_ps(_mm_cmpgt_ps(d2, _mm_loadu_ps(fReach2 + k)), w));
    }
#else
    for (std::size_t k = 0; k < m_padded; ++k) {
      const Real dx = fx[k] - c.x(), dy = fy[k] - c.y(), dz = fz[k] - c.z();
      const Real d2 = dx * dx + (dy * dy + dz * dz);
      row[k] = d2 > fReach2[k] ? Real(0) : CubicSpline::wScaled(std::sqrt(d2), fInvH[k], fFactor[k]);
    }
#endif
  }

  /// the cubic spline W(r) and (dW/dr) / r in double precision, from 1 / H
  static void kernelAndGradient(double r, double invH, double& w, double& g) {
    const double q = r * invH;
    const double k = 8.0 / kPi * invH * invH * invH;
    if (q >= 1.0) {
      w = g = 0.0;
      return;
    }
    const double invRH = r > 1e-12 ? invH / r : 0.0;
    if (q <= 0.5) {
      w = k * (6.0 * q * q * (q - 1.0) + 1.0);
      g = 6.0 * k * q * (3.0 * q - 2.0) * invRH;
    } else {
      const double t = 1.0 - q;
      w = 2.0 * k * t * t * t;
      g = -6.0 * k * t * t * invRH;
    }
  }

  struct Fluid {  // what the sums and the gradient read
    Vec3 x;
    Real invH, volume;
    double tau0;
  };
  // error()'s columns of the fluid terms, each m_padded long
  enum Column { kX, kY, kZ, kInvH, kFactor, kReach2 };
  static constexpr std::size_t kLanes = 8;
  Real* column(Column c) {
    return m_columns.data() + std::size_t(c) * m_padded;
  }
  const Real* column(Column c) const {
    return m_columns.data() + std::size_t(c) * m_padded;
  }
  std::vector<Real> m_columns;
  std::size_t m_padded = 0;
  struct Wall {
    Vec3 x;
    double volume;
  };
  std::vector<Fluid> m_fluid;
  std::vector<Wall> m_walls;
  Real m_Vs, m_invHs, m_kHs, m_invHsb, m_kHsb;
  std::size_t m_children;
  double m_keep, m_target;
};

}  // namespace

double Adaptivity::splitError(const AdaptContext& ctx, std::size_t o, const std::vector<Vec3>& children,
                              double bound) {
  return SplitErrorTerms(ctx, o, children.size()).error(children, bound);
}

double Adaptivity::splitErrorGradient(const AdaptContext& ctx, std::size_t o,
                                      const std::vector<Vec3d>& children, std::vector<Vec3d>& gradient) {
  return SplitErrorTerms(ctx, o, children.size()).errorAndGradient(children, gradient);
}

void Adaptivity::planSplit(const AdaptContext& ctx, SplitPlan& plan) const {
  const ParticleSet& p = ctx.fluid;
  const std::size_t o = plan.parent;
  // colliders near the parent: only they can hold a child
  std::vector<std::uint16_t> near;
  for (std::uint32_t k = ctx.boundaryNbrs.offsets[o]; k < ctx.boundaryNbrs.offsets[o + 1]; ++k) {
    const std::uint16_t c = ctx.boundary.collider[ctx.boundaryNbrs.indices[k]];
    if (std::find(near.begin(), near.end(), c) == near.end())
      near.push_back(c);
  }
  const double childRadius =
      ctx.params.particleRadius * std::cbrt(double(p.m[o]) / double(plan.n) / double(ctx.mFine));
  // A signed distance is 1-Lipschitz outside the solid (where it is exact): a collider whose distance from
  // the parent exceeds the farthest child offset by the clearance cannot hold a child of any orientation.
  // One query per collider drops those; the others answer the K x n child queries (a mesh through its
  // bounding-box tree, mostly without a distance: BallSdf::atLeast).
  double reach = 0.0;
  for (const Vec3d& offset : SplitTemplates::get().offsets(plan.n))
    reach = std::max(reach, offset.norm());
  reach *= ctx.params.particleRadius * std::cbrt(double(p.m[o]) / double(ctx.mFine));
  const Vec3d xo = p.x[o].cast<double>();
  struct NearCollider {
    const ColliderState* state;
    Vec3d centre;  // the parent, in the collider's frame
    BallSdf sdf;
  };
  std::vector<NearCollider> walls;
  for (std::uint16_t c : near) {
    const ColliderState& col = ctx.colliders[c];
    const Vec3d local = col.orientation.conjugate() * (xo - col.position);
    BallSdf sdf(col.desc, local);
    if (sdf.atCentre() - reach < 2.002 * childRadius)
      walls.push_back({&col, local, std::move(sdf)});
  }
  // A child must keep one of its own spacings from the wall surface. Two bounds decide most children without
  // a query, each exactly as the query would: the signed distance is at most the distance to a surface point
  // (a child that near the surface point closest to the parent is too near), and at least the parent's less
  // the child's offset (1-Lipschitz: a child that near the parent keeps the clearance). Margins leave the
  // cases within round-off of a bound to the query. All children are first checked against the bounds, so a
  // candidate with a child in the wall is mostly rejected before any query (a blocked split is planned again
  // kBlockedSplitRetry steps later).
  const double clearance = 2.0 * childRadius;
  thread_local std::vector<Vec3d> undecided;
  auto valid = [&](const std::vector<Vec3>& children) {
    for (const NearCollider& wall : walls) {
      const Quatd toLocal = wall.state->orientation.conjugate();
      Vec3d surface;
      const bool hasSurface = wall.sdf.surfacePoint(surface);
      undecided.clear();
      for (const Vec3& xs : children) {
        const Vec3d q = toLocal * (xs.cast<double>() - wall.state->position);
        if (hasSurface && (q - surface).norm() < clearance - 1e-9)
          return false;
        if (wall.sdf.atCentre() - (q - wall.centre).norm() < clearance + 1e-9)
          undecided.push_back(q);
      }
      for (const Vec3d& q : undecided) {
        if (!wall.sdf.atLeast(q, clearance))
          return false;
      }
    }
    return true;
  };
  // A candidate whose error exceeds the best so far is rejected whatever the rest of its sum (splitError's
  // bound): the same choice, bit for bit, at less cost.
  constexpr double kNoBound = std::numeric_limits<double>::infinity();
  const int candidates = std::clamp(ctx.params.orientationCandidates, 1, kMaxCandidates);
  const SplitErrorTerms terms(ctx, o, std::size_t(plan.n));
  plan.chosen = -1;
  plan.errorUnrotated = -1.0;
  for (int k = 0; k < candidates; ++k) {
    const Quatd rot = candidateRotation(ctx.params.seed, p.id[o], ctx.step, k);
    const std::vector<Vec3> children = childPositions(ctx, o, plan.n, rot);
    if (!valid(children))
      continue;
    // (the first candidate evaluated is evaluated whole: k = 0's error is the unrotated one reported)
    const double e = terms.error(children, plan.chosen < 0 ? kNoBound : plan.errorChosen);
    if (k == 0)
      plan.errorUnrotated = e;
    if (plan.chosen < 0 || e < plan.errorChosen) {
      plan.chosen = k;
      plan.errorChosen = e;
      plan.rotation = rot;
    }
  }
  // Refinement around the best candidate: each try turns the chosen rotation by `angle` about a random axis
  // (drawn from the same hash as the candidates, so runs repeat) and is kept when it lowers the error; a try
  // that does not shrinks the angle. With 8 candidates, 8 tries raise the propeller's orientation gain from
  // 12.0 % to 17.6 % (docs/method.md); more random candidates alone gave 14.5 % at 16 and 16.7 % at 32.
  if (plan.chosen < 0)
    return;
  double angle = kRefineAngle;
  for (int r = 0; r < std::min(ctx.params.orientationRefinement, kMaxTries); ++r) {
    const Vec3d axis =
        candidateRotation(ctx.params.seed, p.id[o], ctx.step, kRefineStream + r) * Vec3d::UnitZ();
    const Quatd rot = (plan.rotation * Quatd(Eigen::AngleAxisd(angle, axis))).normalized();
    const std::vector<Vec3> children = childPositions(ctx, o, plan.n, rot);
    bool better = false;
    if (valid(children)) {
      const double e = terms.error(children, plan.errorChosen);
      if (e < plan.errorChosen) {
        plan.errorChosen = e;
        plan.rotation = rot;
        better = true;
      }
    }
    if (!better)
      angle *= kRefineShrink;
  }
  plan.errorRotated = plan.errorChosen;
  const int moves = std::min(ctx.params.splitPositionSteps, kMaxPositionSteps);
  if (moves <= 0)
    return;
  // Position refinement (after Winchenbach & Kolb 2021, who optimise the children's positions): the children
  // of the chosen orientation move down the gradient of E, the mean of the gradient removed so that their
  // centre of mass stays the parent's. A move is kept when E falls, every child stays within the template's
  // reach of the parent, no two children come closer than kMinChildSpacing of a child's diameter (or the
  // template's closest pair, if closer), and no child comes into a wall; otherwise the step is halved (up to
  // four times).
  const std::vector<Vec3> rotated = childPositions(ctx, o, plan.n, plan.rotation);
  std::vector<Vec3d> x(rotated.size());
  for (std::size_t s = 0; s < x.size(); ++s)
    x[s] = rotated[s].cast<double>();
  std::vector<Vec3d> gradient, trial(x.size());
  std::vector<Vec3> trialReal(x.size());
  // (the templates of 18-26 children are packed closer than that: their own spacing is kept)
  double minSpacing2 = std::pow(kMinChildSpacing * 2.0 * childRadius, 2);
  for (std::size_t a = 0; a < x.size(); ++a)
    for (std::size_t b = a + 1; b < x.size(); ++b)
      minSpacing2 = std::min(minSpacing2, (x[a] - x[b]).squaredNorm());
  double step = kPositionStep * childRadius;
  bool moved = false;
  for (int it = 0; it < moves; ++it) {
    terms.errorAndGradient(x, gradient);
    Vec3d mean = Vec3d::Zero();
    for (const Vec3d& g : gradient)
      mean += g;
    mean /= double(gradient.size());
    double largest = 0.0;
    for (Vec3d& g : gradient) {
      g -= mean;
      largest = std::max(largest, g.norm());
    }
    if (!(largest > 0.0) || !std::isfinite(largest))
      break;
    bool accepted = false;
    for (int halving = 0; halving < 4 && !accepted; ++halving, step *= 0.5) {
      for (std::size_t s = 0; s < x.size(); ++s) {
        trial[s] = x[s] - (step / largest) * gradient[s];
        trialReal[s] = trial[s].cast<Real>();
      }
      // (within the template's reach of the parent: the walls near enough to matter, and their BallSdf, were
      // chosen for that ball)
      bool apart = true;
      for (std::size_t a = 0; a < trial.size() && apart; ++a)
        apart = (trial[a] - xo).squaredNorm() <= reach * reach;
      for (std::size_t a = 0; a < trial.size() && apart; ++a) {
        for (std::size_t b = a + 1; b < trial.size(); ++b) {
          if ((trial[a] - trial[b]).squaredNorm() < minSpacing2) {
            apart = false;
            break;
          }
        }
      }
      if (!apart || !valid(trialReal))
        continue;
      const double e = terms.error(trialReal, plan.errorChosen);
      if (e < plan.errorChosen) {
        plan.errorChosen = e;
        x = trial;
        accepted = true;
        moved = true;
      }
    }
    if (!accepted)
      break;
    step *= 3.0;  // (halved once on leaving the loop above: 1.5 times the accepted step)
  }
  if (moved) {
    plan.children.resize(x.size());
    for (std::size_t s = 0; s < x.size(); ++s)
      plan.children[s] = x[s].cast<Real>();
  }
}

namespace {

/// The most of its mass a receiver takes in one adaptation step. The transfer rate is per solver step: an
/// adaptation every k steps may move k times as much, but never more than kMaxTransferPerAdaptation of a
/// receiver's mass at once (a receiver that jumps carries the density error of its jump into the next
/// pressure solve: at adaptation_period = 100 the first adaptation moved up to 5 times a receiver's mass and
/// the propeller blew up three steps later).
double receiverRate(const SimParams& params) {
  return std::min(params.transferRate * double(std::max(1, params.adaptationPeriod)),
                  std::max(params.transferRate, kMaxTransferPerAdaptation));
}

/// Every change of a particle's mass goes through here: its support is no longer its mass's own
/// (kFlagSupportSettled, Adaptivity::blendSupports).
inline void setMass(ParticleSet& p, std::size_t i, Real m) {
  p.m[i] = m;
  p.flags[i] &= ~std::uint32_t(kFlagSupportSettled);
}

/// Solver steps before a split that every orientation blocked is planned again. On the propeller at
/// r = 0.0088 m a blocked split was planned in every step: 964 of 1,816 plans in 2 s, a third of the plans'
/// time, for parents the blades pass within a few steps anyway.
constexpr std::uint32_t kBlockedSplitRetry = 4;

/// A share goes to light neighbours (q < light_below). A merge may also fill neighbours that are nearly right
/// (q < merge_receivers_below, 1 by default) up to their optimal mass: with light ones only, a too-light
/// particle among right ones found no room, stayed, and was tried again every step (the hand tank at
/// r = 5 mm: about 560 failed merges a step, 19 % of its particles staying too light).
Real receiverBelow(const SimParams& params, bool all) {
  return Real(all ? params.mergeReceiversBelow : params.lightBelow);
}

/// Whether fluid particle j may receive from `donor` (locks aside): light enough, and within their pair
/// support; then `distance` and `room`, j's term of the donor's capacity.
inline bool receiverRoom(const ParticleSet& p, std::size_t donor, std::uint32_t j, Real below, double rate,
                         Real& distance, double& room, Real reach = Real(1)) {
  if (p.m[j] >= below * p.mOpt[j])
    return false;
  distance = (p.x[j] - p.x[donor]).norm();
  if (distance >= reach * pairSupport(p.H[j], p.H[donor]))
    return false;
  room = std::min(double(p.mOpt[j]) - double(p.m[j]), rate * double(p.m[j]));
  return true;
}

}  // namespace

namespace {
std::atomic<bool>& prefilterSetting() {
  static std::atomic<bool> on(true);
  return on;
}
}  // namespace

bool setAdaptivityPrefilter(bool on) {
  return prefilterSetting().exchange(on);
}

double Adaptivity::capacityBound(const AdaptContext& ctx, std::size_t donor, bool all) {
  const ParticleSet& p = ctx.fluid;
  const double rate = receiverRate(ctx.params);
  const Real below = receiverBelow(ctx.params, all);
  // (receivers up to a hair beyond the pair support count too: a build that fuses the distance's
  // multiply-adds differently here than in transferMass() must not leave out a receiver that one counts)
  constexpr Real kReach = Real(1) + Real(1e-5);
  double bound = 0.0;
  for (std::uint32_t k = ctx.fluidNbrs.offsets[donor]; k < ctx.fluidNbrs.offsets[donor + 1]; ++k) {
    Real distance;
    double room;
    if (receiverRoom(p, donor, ctx.fluidNbrs.neighbor(donor, k), below, rate, distance, room, kReach))
      bound += std::max(0.0, room);
  }
  return bound;
}

bool Adaptivity::transferMass(const AdaptContext& ctx, std::size_t donor, double amount, bool all) {
  ParticleSet& p = ctx.fluid;
  m_candidates.clear();
  double capacity = 0.0;
  const double rate = receiverRate(ctx.params);
  const Real below = receiverBelow(ctx.params, all);
  for (std::uint32_t k = ctx.fluidNbrs.offsets[donor]; k < ctx.fluidNbrs.offsets[donor + 1]; ++k) {
    const std::uint32_t j = ctx.fluidNbrs.neighbor(donor, k);
    if (m_locked[j] || m_removed[j])
      continue;
    Real distance;
    double room;
    if (!receiverRoom(p, donor, j, below, rate, distance, room))
      continue;
    m_candidates.emplace_back(distance, j);
    capacity += room;
  }
  // (a merge whose receivers have room for all but round-off of the donor goes ahead: see below)
  if (m_candidates.empty() || capacity <= 0.0 || (all && capacity < amount * (1.0 - 1e-9)))
    return false;
  // nearest receivers first, each filled up to its optimal mass
  std::sort(m_candidates.begin(), m_candidates.end());
  double left = amount;
  const double mDonor = p.m[donor];
  const Vec3d xDonor = p.x[donor].cast<double>();
  const Vec3d vDonor = p.v[donor].cast<double>();
  constexpr std::uint32_t kNoReceiver = ~std::uint32_t(0);
  std::uint32_t last = kNoReceiver;
  for (const auto& [distance, j] : m_candidates) {
    if (left <= 0.0)
      break;
    // Each receiver grows by at most `transfer_rate` of its mass per step: a particle whose mass jumps (say
    // doubles) carries a density error of the same order that the pressure solve must undo in one step. A
    // merge thus spreads its donor over several receivers, or waits for a step where they have room. (Letting
    // donors shrink over several steps instead leaves tiny particles with lagging supports that get shot
    // out.)
    const double room = std::min(double(p.mOpt[j]) - double(p.m[j]), rate * double(p.m[j]));
    // a merge hands its last receiver the exact remainder, so no sliver of mass is left behind by round-off
    const double give = all && room >= left * (1.0 - 1e-9) ? left : std::min(room, left);
    if (give <= 0.0)
      continue;
    left -= give;
    last = j;
    const double mj = p.m[j];
    const double total = mj + give;
    // The received mass brings its momentum. A merge also brings its position (the donor vanishes, its centre
    // of mass stays); a share leaves the receiver in place, or a heavy donor would pull its receivers onto
    // itself.
    if (all)
      p.x[j] = ((mj * p.x[j].cast<double>() + give * xDonor) / total).cast<Real>();
    p.v[j] = ((mj * p.v[j].cast<double>() + give * vDonor) / total).cast<Real>();
    setMass(p, j, Real(total));
    m_locked[j] = 1;
    note(j, kOpReceived);
  }
  // Summing the rooms can fall short of the donor's mass by round-off although the capacity covered it: the
  // last receiver then takes that remainder too, so no donor of ~1e-16 of its mass survives a merge.
  if (all && left > 0.0 && left <= 1e-9 * amount && last != kNoReceiver) {
    const double mj = p.m[last];
    const double total = mj + left;
    p.x[last] = ((mj * p.x[last].cast<double>() + left * xDonor) / total).cast<Real>();
    p.v[last] = ((mj * p.v[last].cast<double>() + left * vDonor) / total).cast<Real>();
    setMass(p, last, Real(total));
    left = 0.0;
  }
  const double given = amount - std::max(0.0, left);
  m_locked[donor] = 1;
  if (all && left <= 0.0) {
    m_removed[donor] = 1;
    note(donor, kOpMerged);
    return true;
  }
  if (given > 0.0)
    note(donor, kOpShared);
  setMass(p, donor, Real(mDonor - given));
  return !all && given > 0.0;
}

AdaptivityStats Adaptivity::adapt(const AdaptContext& ctx, bool ignoreDelay, bool compact) {
  ParticleSet& p = ctx.fluid;
  const SimParams& params = ctx.params;
  const std::size_t n = p.size();
  AdaptivityStats stats;
  m_keep.clear();
  m_locked.resize(n);
  m_removed.resize(n);
  m_ops.resize(n);
  m_kind.resize(n);

  auto ratio = [&](std::size_t i) { return p.m[i] / p.mOpt[i]; };
  // share: a heavy particle gives half its excess to light neighbours, once its mass leaves the band of the
  // targets' hysteresis (kTargetBand in sim/levels.cpp, 0.3): within it the particle is as close to its
  // target as the target is to the levels, and sharing would only churn water at rest
  constexpr double kTargetBand = 0.3;
  const Real shareAbove = Real(std::max(params.shareAbove, 1.0 + kTargetBand));
  // the split delay counts solver steps, whatever the adaptation period
  const std::uint32_t period = std::uint32_t(std::max(1, params.adaptationPeriod));
  // One parallel pass finds the particles each operation below may take. The merges and shares then run in
  // order, each changing only particles it locks, so a particle that is not locked keeps its mass, place and
  // support, and a donor's capacity only loses terms as they proceed. A donor whose capacity at the start
  // (its non-negative terms; floating-point sums of non-negative terms only grow with more terms) is already
  // too small would fail without changing anything, so leaving it out gives the same result; the serial
  // passes visit only the others. (The hand tank at r = 5 mm: the serial merges cost more at two threads
  // than at one, as they read what the other core wrote.)
  const bool prefilter = prefilterSetting().load();
  std::atomic<std::size_t> leftOut{0};
  parallelFor(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    std::size_t dropped = 0;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      m_locked[i] = 0;
      m_removed[i] = 0;
      m_ops[i] = ParticleOps{p.id[i], 0, 0};
      const Real q = ratio(i);
      p.heavySteps[i] = q >= Real(params.splitAbove) ? p.heavySteps[i] + period : 0;
      std::uint8_t kind = 0;
      if (q < Real(params.mergeBelow)) {
        if (!prefilter || capacityBound(ctx, i, true) >= double(p.m[i]) * (1.0 - 1e-9))
          kind |= kMayMerge;
        else
          ++dropped;
      }
      if (q >= Real(params.splitAbove) &&
          (ignoreDelay || p.heavySteps[i] >= std::uint32_t(params.splitDelay)))
        kind |= kMaySplit;
      if (q >= shareAbove) {
        if (!prefilter || capacityBound(ctx, i, false) > 0.0)
          kind |= kMayShare;
        else
          ++dropped;
      }
      m_kind[i] = kind;
    }
    leftOut += dropped;
  });
  m_leftOut = leftOut.load();
  auto select = [&](std::uint8_t kind) {
    parallelSelect(n, 4096, m_selected, [&](std::size_t i) { return (m_kind[i] & kind) != 0; });
  };

  // merge n:(n-1): a too-light particle goes into its nearest light neighbours
  select(kMayMerge);
  for (const std::uint32_t i : m_selected) {
    if (!m_locked[i] && ratio(i) < Real(params.mergeBelow) && transferMass(ctx, i, p.m[i], true))
      ++stats.merges;
  }

  // split 1:n, orientations chosen in parallel on the state before any split of this step (one plan a task: a
  // step has a few plans of tens of microseconds each)
  m_plans.clear();
  select(kMaySplit);
  for (const std::uint32_t i : m_selected) {
    if (m_locked[i])
      continue;
    SplitPlan plan;
    plan.parent = i;
    plan.n = childCount(ratio(i), params);
    m_plans.push_back(plan);
  }
  parallelFor(tbb::blocked_range<std::size_t>(0, m_plans.size(), 1),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k)
                  planSplit(ctx, m_plans[k]);
              });
  for (const SplitPlan& plan : m_plans) {
    if (plan.chosen < 0) {
      // every orientation put a child in a wall: planned again kBlockedSplitRetry solver steps later (or
      // after the split delay, when that is shorter), not in every step while the wall is still there. (The
      // delay counts in steps of the adaptation period: with a period above 1 the retry is rounded up to a
      // whole number of adaptations.)
      ++stats.splitsBlocked;
      const std::uint32_t delay = std::uint32_t(std::max(0, params.splitDelay));
      p.heavySteps[plan.parent] = delay > kBlockedSplitRetry ? delay - kBlockedSplitRetry : 0u;
      continue;
    }
    const std::size_t o = plan.parent;
    const std::vector<Vec3> children =
        plan.children.empty() ? childPositions(ctx, o, plan.n, plan.rotation) : plan.children;
    const double mParent = p.m[o];
    const Real mChild = Real(mParent / plan.n);
    for (int s = 0; s < plan.n; ++s) {
      // the last child takes the remainder, so the children's masses sum to the parent's to round-off
      const Real m = s + 1 < plan.n ? mChild : Real(mParent - double(mChild) * (plan.n - 1));
      // children start with the parent's support and blend to their own (Adaptivity::blendSupports)
      const std::size_t c = p.add(children[std::size_t(s)], p.v[o], m, p.H[o], p.rho[o]);
      p.a[c] = p.a[o];
      p.kappa[c] = p.kappa[o];
      p.kappaV[c] = p.kappaV[o];
      p.splitTime[c] = Real(ctx.time);
      // (a parent caged by the boundary alone leaves its children counted as cage until the next density
      // pass finds out for itself)
      p.flags[c] = kFlagSplit | (p.flags[o] & (kFlagSurface | kFlagCaged));
      p.levelPhi[c] = p.levelPhi[o];
      p.levelOmega[c] = p.levelOmega[o];
      p.levelNu[c] = p.levelNu[o];
      p.mOpt[c] = p.mOpt[o];
      p.phi[c] = p.phi[o];
      p.omega[c] = p.omega[o];
      p.nu[c] = p.nu[o];
      // temporal blending from the parent (blendSplitVelocities, blendSplitDensities)
      p.parentId[c] = params.splitBlendSteps > 0 ? p.id[o] : kNoParent;
      p.splitAge[c] = 0;
    }
    m_removed[o] = 1;
    m_locked[o] = 1;
    note(o, kOpSplit);
    ++stats.splits;
    stats.children += std::uint64_t(plan.n);
    if (plan.errorUnrotated >= 0.0) {
      ++stats.splitsCompared;
      stats.splitErrorChosen += plan.errorChosen;
      stats.splitErrorRotated += plan.errorRotated;
      stats.splitErrorUnrotated += plan.errorUnrotated;
    }
  }

  // share (see above)
  select(kMayShare);
  for (const std::uint32_t i : m_selected) {
    if (m_locked[i] || ratio(i) < shareAbove)
      continue;
    if (transferMass(ctx, i, 0.5 * (double(p.m[i]) - double(p.mOpt[i])), false))
      ++stats.redistributions;
  }

  if (stats.merges + stats.splits > 0) {
    parallelSelect(p.size(), 4096, m_keep, [&](std::size_t i) { return i >= n || !m_removed[i]; });
    if (compact)
      p.retain(m_keep);
  }
  return stats;
}

void Adaptivity::blendSupports(ParticleSet& p, const SimParams& params, Real mFine) {
  const Real r = Real(params.particleRadius);
  const Real keep = params.supportBlendSteps > 0 ? Real(std::exp(-3.0 / params.supportBlendSteps)) : Real(0);
  // (a cube root a particle: worth two threads from about 1,000 particles; the grain does not change results)
  // A particle whose support was its mass's own at the last call and whose mass has not changed since
  // (kFlagSupportSettled, cleared by setMass) would get the same support again, so its cube root is skipped
  // (seven in ten particles a step on the propeller at r = 0.0088 m and in the hand tank).
  parallelFor(tbb::blocked_range<std::size_t>(0, p.size(), 512),
              [&](const tbb::blocked_range<std::size_t>& rg) {
                for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
                  if (p.flags[i] & kFlagSupportSettled)
                    continue;
                  const Real target = supportForMass(p.m[i], mFine, r);
                  Real h = target + (p.H[i] - target) * keep;
                  if (std::abs(h - target) < Real(1e-3) * target)
                    h = target;
                  p.H[i] = h;
                  if (h == target)
                    p.flags[i] |= kFlagSupportSettled;
                }
              });
}

namespace {

/// The split children that still blend, grouped by parent: `index` holds their particle indices sorted by
/// (parent id, index), `start` the first entry of each group and the end.
struct BlendGroups {
  std::vector<std::uint32_t> index;
  std::vector<std::uint32_t> start;
};

BlendGroups blendGroups(const ParticleSet& p, int steps) {
  BlendGroups g;
  // (ascending, in parallel above 4,096 particles: the same list whatever the thread count)
  const std::uint32_t age = std::uint32_t(std::max(steps, 0));
  parallelSelect(p.size(), 4096, g.index,
                 [&](std::size_t i) { return p.parentId[i] != kNoParent && p.splitAge[i] < age; });
  std::sort(g.index.begin(), g.index.end(), [&](std::uint32_t a, std::uint32_t b) {
    return p.parentId[a] != p.parentId[b] ? p.parentId[a] < p.parentId[b] : a < b;
  });
  for (std::size_t k = 0; k < g.index.size(); ++k) {
    if (k == 0 || p.parentId[g.index[k]] != p.parentId[g.index[k - 1]])
      g.start.push_back(std::uint32_t(k));
  }
  g.start.push_back(std::uint32_t(g.index.size()));
  return g;
}

}  // namespace

Real Adaptivity::splitBlendWeight(std::uint32_t age, int steps) {
  if (steps <= 0 || age >= std::uint32_t(steps))
    return 0;
  return Real(0.5) * (Real(1) - Real(age) / Real(steps));
}

void Adaptivity::blendSplitVelocities(ParticleSet& p, const SimParams& params) {
  const BlendGroups g = blendGroups(p, params.splitBlendSteps);
  for (std::size_t k = 0; k + 1 < g.start.size(); ++k) {
    double mass = 0.0;
    Vec3d momentum = Vec3d::Zero();
    for (std::uint32_t e = g.start[k]; e < g.start[k + 1]; ++e) {
      const std::uint32_t s = g.index[e];
      mass += double(p.m[s]);
      momentum += double(p.m[s]) * p.v[s].cast<double>();
    }
    const Vec3d vParent = momentum / mass;
    for (std::uint32_t e = g.start[k]; e < g.start[k + 1]; ++e) {
      const std::uint32_t s = g.index[e];
      const double beta = double(splitBlendWeight(p.splitAge[s], params.splitBlendSteps));
      p.v[s] = (p.v[s].cast<double>() + beta * (vParent - p.v[s].cast<double>())).cast<Real>();
    }
  }
}

namespace {

/// f(k) for every sorted point k of `cells` in the grid cells that a ball of radius `reach` about `x` touches
template <class F>
void forPointsNear(const UniformGrid& grid, const std::vector<std::uint32_t>& cells, const Vec3& x,
                   Real reach, const F& f) {
  if (CellRanges(cells).count() == 0)
    return;
  const Eigen::Vector3i lo = grid.cellCoord(x - Vec3::Constant(reach));
  const Eigen::Vector3i hi = grid.cellCoord(x + Vec3::Constant(reach));
  for (int cz = lo.z(); cz <= hi.z(); ++cz) {
    for (int cy = lo.y(); cy <= hi.y(); ++cy) {
      // (a row's cells are consecutive in the sorted order: one range from its first cell to its last)
      const std::uint32_t first = grid.cellRange(cells, lo.x(), cy, cz).first;
      const std::uint32_t last = grid.cellRange(cells, hi.x(), cy, cz).second;
      for (std::uint32_t k = first; k < last; ++k)
        f(k);
    }
  }
}

}  // namespace

void Adaptivity::blendSplitDensities(ParticleSet& p, const SortedParticles& sorted,
                                     const BoundarySet& boundary, const SimParams& params, Real mFine) {
  const BlendGroups g = blendGroups(p, params.splitBlendSteps);
  // (the cell ranges' header holds the count of points sorted: ranges of another set of particles are not
  // these particles')
  if (g.index.empty() || CellRanges(sorted.fluidCells).count() != p.size())
    return;
  const double rho0 = params.restDensity;
  const Real r = Real(params.particleRadius);
  const Real Hb = boundary.support();
  const std::size_t nStatic = boundary.staticCount();
  const std::size_t groups = g.start.size() - 1;
  // The parent's density sums over every particle within its pair support of the siblings' centre, found
  // through the search's grid. (The union of the siblings' own lists, used before, misses the outer shell of
  // the parent's support as the children's supports shrink to their own: on the two-hand replay with a lost
  // hand the parent read 10-25 % under its children, the blend let them compress, and at its end the density
  // came back as a push that threw water at 4.9 m/s where the run without blending peaked at 2.0 m/s.)
  parallelFor(tbb::blocked_range<std::size_t>(0, groups, 8), [&](const tbb::blocked_range<std::size_t>& rg) {
    std::vector<std::uint32_t> members;
    for (std::size_t k = rg.begin(); k < rg.end(); ++k) {
      members.assign(g.index.begin() + g.start[k], g.index.begin() + g.start[k + 1]);
      std::sort(members.begin(), members.end());
      double mass = 0.0;
      Vec3d centre = Vec3d::Zero();
      for (std::uint32_t s : members) {
        mass += double(p.m[s]);
        centre += double(p.m[s]) * p.x[s].cast<double>();
      }
      centre /= mass;
      // the parent: its mass and the support of that mass, at the siblings' centre of mass
      const Real Ho = supportForMass(Real(mass), mFine, r);
      const Vec3 xo = centre.cast<Real>();
      double density = mass / rho0 * double(CubicSpline::w0(Ho));
      forPointsNear(sorted.grid, sorted.fluidCells, xo, pairSupport(Ho, sorted.maxSupport),
                    [&](std::uint32_t j) {
                      if (std::binary_search(members.begin(), members.end(), j))
                        return;
                      const Real h = pairSupport(Ho, p.H[j]);
                      const Real d2 = (xo - p.x[j]).squaredNorm();
                      if (d2 < h * h)
                        density += double(p.m[j]) / rho0 * double(CubicSpline::w(std::sqrt(d2), h));
                    });
      const Real Hob = pairSupport(Ho, Hb);
      const double sb = double(boundary.volumeScale(Ho));
      auto wall = [&](std::size_t b) {
        const Real d2 = (xo - boundary.x[b]).squaredNorm();
        if (d2 < Hob * Hob)
          density += sb * double(boundary.psi[b]) * double(CubicSpline::w(std::sqrt(d2), Hob));
      };
      forPointsNear(sorted.grid, sorted.staticCells, xo, Hob, [&](std::uint32_t b) { wall(b); });
      forPointsNear(sorted.grid, sorted.kinematicCells, xo, Hob, [&](std::uint32_t b) { wall(nStatic + b); });
      const double rhoParent = density * rho0;
      for (std::uint32_t s : members) {
        const double beta = double(splitBlendWeight(p.splitAge[s], params.splitBlendSteps));
        p.rho[s] = Real(double(p.rho[s]) + beta * (rhoParent - double(p.rho[s])));
      }
    }
  });
}

void Adaptivity::ageSplitChildren(ParticleSet& p, const SimParams& params) {
  const std::uint32_t steps = std::uint32_t(std::max(0, params.splitBlendSteps));
  parallelFor(tbb::blocked_range<std::size_t>(0, p.size(), 4096),
              [&](const tbb::blocked_range<std::size_t>& rg) {
                for (std::size_t i = rg.begin(); i < rg.end(); ++i) {
                  if (p.parentId[i] == kNoParent)
                    continue;
                  if (++p.splitAge[i] >= steps)
                    p.parentId[i] = kNoParent;
                }
              });
}

std::size_t Adaptivity::memoryBytes() const {
  return m_locked.capacity() + m_removed.capacity() + m_ops.capacity() * sizeof(ParticleOps) +
         m_plans.capacity() * sizeof(SplitPlan) + m_keep.capacity() * sizeof(std::uint32_t) +
         m_candidates.capacity() * sizeof(m_candidates[0]) + m_kind.capacity() +
         m_selected.capacity() * sizeof(std::uint32_t);
}

}  // namespace fp::sim
