#include "sim/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace fp::sim {

namespace {

/// In ascending order of value, the first (value, weight) of `vw` at which the weight so far reaches `target`
/// (exceeds it, when `strictly`), by weighted selection instead of a full sort (the headless run measures
/// heights twice a frame); the largest value when round-off keeps the sum short of it. Reorders `vw`, which
/// must not be empty. Values that tie are one value, whatever their order.
double weightedQuantile(std::vector<std::pair<double, double>>& vw, double target, bool strictly) {
  auto reaches = [&](double weight) { return strictly ? weight > target : weight >= target; };
  // `below` is the weight of everything before [lo, hi) and does not reach the target
  auto lo = vw.begin();
  auto hi = vw.end();
  double below = 0.0;
  while (hi - lo > 32) {
    const auto mid = lo + (hi - lo) / 2;
    std::nth_element(lo, mid, hi);
    double left = 0.0;
    for (auto it = lo; it != mid; ++it)
      left += it->second;
    if (reaches(below + left)) {
      hi = mid;
      continue;
    }
    below += left;
    if (reaches(below + mid->second))
      return mid->first;
    below += mid->second;
    lo = mid + 1;
  }
  std::sort(lo, hi);
  for (auto it = lo; it != hi; ++it) {
    below += it->second;
    if (reaches(below))
      return it->first;
  }
  return std::max_element(vw.begin(), vw.end())->first;
}

}  // namespace

double heightPercentile(const ParticleSet& p, double fraction, const SplashParticles* splash, int perSource) {
  std::vector<std::pair<double, double>> yw;
  yw.reserve(p.size() + (splash ? splash->size() : 0));
  for (std::size_t i = 0; i < p.size(); ++i)
    yw.emplace_back(double(p.x[i].y()), double(p.m[i]));
  if (splash) {
    for (std::size_t k = 0; k < splash->size(); ++k)
      yw.emplace_back(double(splash->x[k].y()),
                      double(p.m[splash->source[k]]) / double(std::max(1, perSource)));
  }
  if (yw.empty())
    return 0.0;
  double total = 0.0;
  for (const auto& [y, w] : yw)
    total += w;
  return weightedQuantile(yw, fraction * total, false);
}

DensityErrorMeans densityErrorMeans(const ParticleSet& p, double restDensity) {
  DensityErrorMeans out;
  double sum = 0.0, weighted = 0.0, volume = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double e = std::max(0.0, double(p.rho[i]) / restDensity - 1.0);
    sum += e;
    weighted += double(p.m[i]) * e;
    volume += double(p.m[i]);
  }
  if (p.size() > 0)
    out.perParticle = sum / double(p.size());
  if (volume > 0.0)
    out.volumeWeighted = weighted / volume;
  return out;
}

double surgeFront(const ParticleSet& p, double massBeyond) {
  if (p.size() == 0)
    return 0.0;
  // the reaches negated, so that ascending is farthest first
  std::vector<std::pair<double, double>> reach(p.size());
  double total = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    reach[i] = {-(double(p.x[i].x()) + 0.25 * double(p.H[i])), double(p.m[i])};
    total += double(p.m[i]);
  }
  return -weightedQuantile(reach, massBeyond * total, true);
}

TimeStepHeadroom timeStepHeadroom(const ParticleSet& p, double dt, double cflFactor, double dtMax) {
  TimeStepHeadroom out;
  if (p.size() == 0 || !(dt > 0.0))
    return out;
  // the level whose step 2^L dt is the longest within `limit`
  auto work = [&](double limit) {
    int level = 0;
    while (level < kMaxTimeLevel && std::ldexp(dt, level + 1) <= limit)
      ++level;
    return std::ldexp(1.0, -level);
  };
  double capped = 0.0, uncapped = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double speed = double((p.v[i] + Real(dt) * p.a[i]).norm());
    const double own =
        speed > 0.0 ? cflFactor * 0.5 * double(p.H[i]) / speed : std::numeric_limits<double>::infinity();
    capped += work(std::min(own, dtMax));
    uncapped += work(own);
  }
  out.capped = capped / double(p.size());
  out.uncapped = uncapped / double(p.size());
  return out;
}

}  // namespace fp::sim
