#include "sim/metrics.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace fp::sim {

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
  std::sort(yw.begin(), yw.end());
  double total = 0.0;
  for (const auto& [y, w] : yw)
    total += w;
  double below = 0.0;
  for (const auto& [y, w] : yw) {
    below += w;
    if (below >= fraction * total)
      return y;
  }
  return yw.back().first;
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

}  // namespace fp::sim
