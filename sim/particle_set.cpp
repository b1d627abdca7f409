#include "sim/particle_set.h"

#include <limits>

#include "sim/parallel.h"

namespace fp::sim {

template <class F>
void ParticleSet::forEachField(F&& f) {
  f(x, m_scratchVec);
  f(v, m_scratchVec);
  f(a, m_scratchVec);
  f(m, m_scratchReal);
  f(H, m_scratchReal);
  f(rho, m_scratchReal);
  f(kappa, m_scratchReal);
  f(kappaV, m_scratchReal);
  f(splitTime, m_scratchReal);
  f(id, m_scratchU32);
  f(flags, m_scratchU32);
  f(levelPhi, m_scratchReal);
  f(levelOmega, m_scratchReal);
  f(levelNu, m_scratchReal);
  f(mOpt, m_scratchReal);
  f(phi, m_scratchReal);
  f(omega, m_scratchReal);
  f(nu, m_scratchReal);
  f(heavySteps, m_scratchU32);
  f(parentId, m_scratchU32);
  f(splitAge, m_scratchU32);
}

std::size_t ParticleSet::add(const Vec3& position, const Vec3& velocity, Real mass, Real support,
                             Real restDensity) {
  x.push_back(position);
  v.push_back(velocity);
  a.push_back(Vec3::Zero());
  m.push_back(mass);
  H.push_back(support);
  rho.push_back(restDensity);
  kappa.push_back(0);
  kappaV.push_back(0);
  splitTime.push_back(-1);
  id.push_back(m_nextId++);
  flags.push_back(0);
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
  return x.size() - 1;
}

void ParticleSet::clear() {
  forEachField([](auto& field, auto&) { field.clear(); });
  m_nextId = 0;
}

void ParticleSet::shrinkToFit() {
  forEachField([](auto& field, auto& scratch) {
    field.shrink_to_fit();
    scratch.shrink_to_fit();
  });
}

void ParticleSet::reserve(std::size_t n) {
  forEachField([n](auto& field, auto&) { field.reserve(n); });
}

void ParticleSet::permute(const std::vector<std::uint32_t>& order) {
  const std::size_t n = order.size();
  forEachField([&](auto& field, auto& scratch) {
    scratch.resize(n);
    parallelFor(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k < r.end(); ++k)
        scratch[k] = field[order[k]];
    });
    field.swap(scratch);
  });
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
  std::size_t bytes = 0;
  auto count = [&bytes](const auto& field) { bytes += field.capacity() * sizeof(field[0]); };
  count(x);
  count(v);
  count(a);
  count(m);
  count(H);
  count(rho);
  count(kappa);
  count(kappaV);
  count(splitTime);
  count(id);
  count(flags);
  count(levelPhi);
  count(levelOmega);
  count(levelNu);
  count(mOpt);
  count(phi);
  count(omega);
  count(nu);
  count(heavySteps);
  count(parentId);
  count(splitAge);
  bytes += m_scratchVec.capacity() * sizeof(Vec3) + m_scratchReal.capacity() * sizeof(Real) +
           m_scratchU32.capacity() * sizeof(std::uint32_t);
  return bytes;
}

}  // namespace fp::sim
