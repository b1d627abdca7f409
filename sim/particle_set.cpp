#include "sim/particle_set.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>

#include "sim/parallel.h"

namespace fp::sim {

template <class F>
void ParticleSet::forEachAdaptivityField(F&& f) {
  f(splitTime);
  f(levelPhi);
  f(levelOmega);
  f(levelNu);
  f(mOpt);
  f(phi);
  f(omega);
  f(nu);
  f(heavySteps);
  f(parentId);
  f(splitAge);
}

template <class F>
void ParticleSet::forEachField(F&& f) {
  f(x);
  f(v);
  f(a);
  f(m);
  f(H);
  f(rho);
  f(kappa);
  f(kappaV);
  f(id);
  f(flags);
  if (m_adaptivityFields)
    forEachAdaptivityField(f);
}

std::size_t ParticleSet::add(const Vec3& position, const Vec3& velocity, Real mass, Real support,
                             Real restDensity) {
  // Grow by 1/16 (as the neighbour lists do), not by std::vector's doubling: a hand-tank run whose peak
  // count rose 4 % past the capacity held twice the arrays it needed (the soak's memory bound, issue #12's
  // bytes per particle). Every field is reserved at once, so they reallocate together.
  // The arguments may be this set's own elements (a split passes its parent's velocity): copied first, as
  // push_back would, since reserving moves them.
  const Vec3 position0 = position;
  const Vec3 velocity0 = velocity;
  if (x.size() == x.capacity())
    reserve(x.size() + std::max<std::size_t>(x.size() / 16, 256));
  x.push_back(position0);
  v.push_back(velocity0);
  a.push_back(Vec3::Zero());
  m.push_back(mass);
  H.push_back(support);
  rho.push_back(restDensity);
  kappa.push_back(0);
  kappaV.push_back(0);
  id.push_back(m_nextId++);
  flags.push_back(0);
  if (m_adaptivityFields) {
    splitTime.push_back(-1);
    levelPhi.push_back(1);
    levelOmega.push_back(1);
    levelNu.push_back(1);
    mOpt.push_back(mass);
    phi.push_back(std::numeric_limits<Real>::infinity());
    omega.push_back(0);
    nu.push_back(0);
    heavySteps.push_back(0);
    parentId.push_back(kNoParent);
    splitAge.push_back(0);
  }
  return x.size() - 1;
}

void ParticleSet::setAdaptivityFields(bool keep) {
  if (keep == m_adaptivityFields)
    return;
  m_adaptivityFields = keep;
  if (!keep) {
    forEachAdaptivityField([](auto& field) {
      field.clear();
      field.shrink_to_fit();
    });
    return;
  }
  const std::size_t n = size();
  splitTime.assign(n, Real(-1));
  levelPhi.assign(n, Real(1));
  levelOmega.assign(n, Real(1));
  levelNu.assign(n, Real(1));
  mOpt = m;
  phi.assign(n, std::numeric_limits<Real>::infinity());
  omega.assign(n, Real(0));
  nu.assign(n, Real(0));
  heavySteps.assign(n, 0u);
  parentId.assign(n, kNoParent);
  splitAge.assign(n, 0u);
}

void ParticleSet::clear() {
  forEachField([](auto& field) { field.clear(); });
  m_nextId = 0;
}

void ParticleSet::shrinkToFit() {
  forEachField([](auto& field) { field.shrink_to_fit(); });
  m_scratch.shrink_to_fit();
}

void ParticleSet::reserve(std::size_t n) {
  forEachField([n](auto& field) { field.reserve(n); });
}

void ParticleSet::permute(const std::vector<std::uint32_t>& order) {
  const std::size_t n = order.size();
  if (n < kColumnTasksBelow) {
    permuteByColumns(order);
    return;
  }
  // One buffer of one float a particle serves every field: a 4-byte field is gathered into it and copied
  // back, a vector field one coordinate at a time (the gathers of a coordinate read that coordinate only,
  // which the copies back of the others leave as it was). Copies go through memcpy: the ids and flags pass
  // through the float buffer as raw bytes.
  m_scratch.resize(n);
  Real* buffer = m_scratch.data();
  using Range = tbb::blocked_range<std::size_t>;
  auto copyBack = [&](auto* dst) {
    parallelFor(Range(0, n, 4096), [&](const Range& r) {
      std::memcpy(static_cast<void*>(dst + r.begin()), buffer + r.begin(),
                  (r.end() - r.begin()) * sizeof(Real));
    });
  };
  forEachField([&](auto& field) {
    using T = typename std::decay_t<decltype(field)>::value_type;
    if constexpr (std::is_same_v<T, Vec3>) {
      for (int c = 0; c < 3; ++c) {
        parallelFor(Range(0, n, 4096), [&](const Range& r) {
          for (std::size_t k = r.begin(); k < r.end(); ++k)
            buffer[k] = field[order[k]][c];
        });
        parallelFor(Range(0, n, 4096), [&](const Range& r) {
          for (std::size_t k = r.begin(); k < r.end(); ++k)
            field[k][c] = buffer[k];
        });
      }
    } else {
      static_assert(sizeof(T) == sizeof(Real) && std::is_trivially_copyable_v<T>);
      parallelFor(Range(0, n, 4096), [&](const Range& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k)
          std::memcpy(buffer + k, &field[order[k]], sizeof(Real));
      });
      copyBack(field.data());
    }
    field.resize(n);  // `order` may keep a subset (Adaptivity drops merged particles so)
  });
}

void ParticleSet::permuteByColumns(const std::vector<std::uint32_t>& order) {
  // A column is a 4-byte field or one coordinate of a vector field; each is gathered into a buffer and copied
  // back on its own, so the columns are the tasks (one parallel call; split by particles, a few thousand
  // particles made some 60 calls of a few microseconds, each mostly the threads' hand-over).
  struct Column {
    std::byte* base;
    std::size_t stride;
  };
  std::vector<Column> columns;
  columns.reserve(32);
  forEachField([&](auto& field) {
    using T = typename std::decay_t<decltype(field)>::value_type;
    static_assert((std::is_same_v<T, Vec3> || std::is_trivially_copyable_v<T>)&&sizeof(T) % sizeof(Real) ==
                  0);
    for (std::size_t c = 0; c < sizeof(T) / sizeof(Real); ++c)
      columns.push_back({reinterpret_cast<std::byte*>(field.data()) + c * sizeof(Real), sizeof(T)});
  });
  const std::size_t n = order.size();
  using Range = tbb::blocked_range<std::size_t>;
  parallelFor(Range(0, columns.size(), 1), [&](const Range& r) {
    const std::unique_ptr<Real[]> buffer(new Real[n]);  // every entry written before it is read
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      const Column col = columns[c];
      for (std::size_t k = 0; k < n; ++k)
        std::memcpy(&buffer[k], col.base + order[k] * col.stride, sizeof(Real));
      for (std::size_t k = 0; k < n; ++k)
        std::memcpy(col.base + k * col.stride, &buffer[k], sizeof(Real));
    }
  });
  forEachField(
      [&](auto& field) { field.resize(n); });  // `order` may keep a subset (merged particles dropped)
}

void ParticleSet::retain(const std::vector<std::uint32_t>& keep) {
  const std::size_t n = keep.size();
  std::size_t first = 0;  // the particles before the first dropped one stay where they are
  while (first < n && keep[first] == first)
    ++first;
  auto move = [&keep, first, n](auto& field) {
    // keep[k] >= k: each particle moves down over one already moved or dropped
    for (std::size_t k = first; k < n; ++k)
      field[k] = field[keep[k]];
    field.resize(n);
  };
  if (n - first < kRetainTasksFrom) {
    // a few thousand moves a field: on one thread, which is faster at two threads than 21 tasks reading what
    // the other core wrote (the propeller: 9 ms a run on one thread, 18 ms as tasks on two)
    forEachField(move);
    return;
  }
  TaskGroup tasks;
  forEachField([&](auto& field) { tasks.run([&field, &move] { move(field); }); });
  tasks.wait();
}

double ParticleSet::totalMass() const {
  double sum = 0.0;
  for (Real mi : m)
    sum += mi;
  return sum;
}

Vec3d ParticleSet::totalMomentum() const {
  Vec3d p = Vec3d::Zero();
  for (std::size_t i = 0; i < size(); ++i)
    p += double(m[i]) * v[i].cast<double>();
  return p;
}

std::size_t ParticleSet::memoryBytes() const {
  return heldBytes(*this);
}

void ParticleSet::memoryBreakdown(std::vector<MemoryItem>& out) const {
  MemoryItem solver{"fluid: x v a m H rho kappa kappaV id flags", 0, 0};
  for (const auto* f : {&x, &v, &a})
    countVector(solver, *f);
  for (const auto* f : {&m, &H, &rho, &kappa, &kappaV})
    countVector(solver, *f);
  for (const auto* f : {&id, &flags})
    countVector(solver, *f);
  MemoryItem adaptive{"fluid: adaptivity fields (levels mOpt phi omega nu split* heavySteps)", 0, 0};
  for (const auto* f : {&splitTime, &levelPhi, &levelOmega, &levelNu, &mOpt, &phi, &omega, &nu})
    countVector(adaptive, *f);
  for (const auto* f : {&heavySteps, &parentId, &splitAge})
    countVector(adaptive, *f);
  MemoryItem scratch{"fluid: sort scratch", 0, 0};
  countVector(scratch, m_scratch);
  out.push_back(solver);
  out.push_back(adaptive);
  out.push_back(scratch);
}

}  // namespace fp::sim
