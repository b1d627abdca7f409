#include "sim/boundary_set.h"

#include <atomic>
#include <stdexcept>
#include <unordered_map>

#include "sim/boundary_sampling.h"
#include "sim/kernels.h"
#include "sim/parallel.h"

namespace fp::sim {

namespace {

/// the next BoundarySet::staticVersion() (0 is a default-constructed set's, which holds no particle)
std::uint64_t nextStaticVersion() {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

/// psi_b = 1 / sum_k W(x_b - x_k, H) over the same collider's particles, with a hashed grid of cell size H.
void computeVolumes(const std::vector<Vec3>& x, std::size_t begin, std::size_t end, Real H,
                    std::vector<Real>& psi) {
  auto key = [H](const Vec3& p) {
    const Eigen::Vector3i c = (p / H).array().floor().cast<int>();
    return (std::int64_t(c.x()) * 73856093) ^ (std::int64_t(c.y()) * 19349663) ^
           (std::int64_t(c.z()) * 83492791);
  };
  std::unordered_multimap<std::int64_t, std::uint32_t> cells;
  cells.reserve(end - begin);
  for (std::size_t i = begin; i < end; ++i)
    cells.emplace(key(x[i]), std::uint32_t(i));
  parallelFor(
      tbb::blocked_range<std::size_t>(begin, end, 256), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          Real sum = 0;
          const Eigen::Vector3i c = (x[i] / H).array().floor().cast<int>();
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const Vec3 q =
                    (c + Eigen::Vector3i(dx, dy, dz)).cast<Real>() * H + Vec3::Constant(Real(0.5) * H);
                auto range = cells.equal_range(key(q));
                for (auto it = range.first; it != range.second; ++it) {
                  const Vec3 d = x[i] - x[it->second];
                  // hash collisions may bring far cells: the kernel is zero there
                  sum += CubicSpline::w(d.norm(), H);
                }
              }
          psi[i] = sum > 0 ? Real(1) / sum : Real(0);
        }
      });
}

}  // namespace

void BoundarySet::build(const std::vector<ColliderState>& colliders, Real particleRadius) {
  x.clear();
  v.clear();
  psi.clear();
  local.clear();
  collider.clear();
  m_support = Real(4) * particleRadius;
  const double spacing = 2.0 * double(particleRadius);
  // static colliders first, then kinematic ones
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t c = 0; c < colliders.size(); ++c) {
      const ColliderState& cs = colliders[c];
      if (cs.desc.kinematic() != (pass == 1))
        continue;
      const std::size_t begin = x.size();
      const std::vector<Vec3d> points = sampleColliderLocal(cs.desc, spacing);
      for (const Vec3d& p : points) {
        x.push_back((cs.orientation * p + cs.position).cast<Real>());
        collider.push_back(std::uint16_t(c));
      }
      if (pass == 1) {
        local.insert(local.end(), points.begin(), points.end());
        v.resize(local.size(), Vec3::Zero());
      }
      psi.resize(x.size());
      computeVolumes(x, begin, x.size(), m_support, psi);
    }
    if (pass == 0)
      m_staticCount = x.size();
  }
  m_staticVersion = nextStaticVersion();
  // built once: no spare capacity from the growth of the vectors
  x.shrink_to_fit();
  v.shrink_to_fit();
  psi.shrink_to_fit();
  local.shrink_to_fit();
  collider.shrink_to_fit();
  updateKinematic(colliders);
}

void BoundarySet::updateKinematic(const std::vector<ColliderState>& colliders) {
  const std::size_t n = x.size();
  parallelFor(tbb::blocked_range<std::size_t>(m_staticCount, n, 1024),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t i = r.begin(); i < r.end(); ++i) {
                  const std::size_t k = i - m_staticCount;
                  const ColliderState& c = colliders[collider[i]];
                  const Vec3d arm = c.orientation * local[k];
                  x[i] = (arm + c.position).cast<Real>();
                  v[k] = (c.linearVelocity + c.angularVelocity.cross(arm)).cast<Real>();
                }
              });
}

void BoundarySet::permute(std::size_t begin, const std::vector<std::uint32_t>& order) {
  const std::size_t end = begin + order.size();
  if (!(end <= m_staticCount || begin >= m_staticCount) || end > x.size())
    throw std::logic_error("BoundarySet::permute: the range mixes static and kinematic particles");
  if (begin < m_staticCount && !order.empty())
    m_staticVersion = nextStaticVersion();
  auto apply = [&](auto& field, std::size_t s) {
    auto copy = std::vector<typename std::decay_t<decltype(field)>::value_type>(
        field.begin() + std::ptrdiff_t(s), field.begin() + std::ptrdiff_t(s + order.size()));
    for (std::size_t k = 0; k < order.size(); ++k)
      field[s + k] = copy[order[k]];
  };
  apply(x, begin);
  apply(psi, begin);
  apply(collider, begin);
  if (begin >= m_staticCount) {
    apply(v, begin - m_staticCount);
    apply(local, begin - m_staticCount);
  }
}

std::size_t BoundarySet::memoryBytes() const {
  return heldBytes(*this);
}

void BoundarySet::memoryBreakdown(std::vector<MemoryItem>& out) const {
  MemoryItem xPsi{"boundary: x psi collider", 0, 0};
  countVector(xPsi, x);
  countVector(xPsi, psi);
  countVector(xPsi, collider);
  MemoryItem vel{"boundary: v (kinematic only)", 0, 0};
  countVector(vel, v);
  MemoryItem loc{"boundary: local (double, kinematic only)", 0, 0};
  countVector(loc, local);
  out.push_back(xPsi);
  out.push_back(vel);
  out.push_back(loc);
}

}  // namespace fp::sim
