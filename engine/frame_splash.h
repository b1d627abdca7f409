#pragma once
/// The splash a window draws: generated once for each state of the simulation (its address, step count and
/// time), so a paused simulation keeps the splash it has instead of generating it again every frame (issue
/// 14). The headless run shares one computation a frame between its statistics and the renderer another way:
/// the frame callback hands the renderer the splash the statistics generated (engine/headless_app.cpp).

#include <cstdint>

#include "sim/simulation.h"
#include "sim/splash.h"

namespace fp::engine {

class FrameSplash {
 public:
  /// the splash of `simulation`'s current state, generated (with `frame`'s random numbers) only when the
  /// state differs from the one of the last call
  const sim::SplashParticles& of(const sim::Simulation& simulation, std::uint64_t frame) {
    if (m_of != &simulation || m_step != simulation.stepCount() || m_time != simulation.time()) {
      m_generator.generate(simulation, frame);
      m_of = &simulation;
      m_step = simulation.stepCount();
      m_time = simulation.time();
      ++m_generations;
    }
    return m_generator.splash();
  }
  /// how many times the splash was generated
  std::uint64_t generations() const { return m_generations; }

 private:
  sim::SplashGenerator m_generator;
  const sim::Simulation* m_of = nullptr;
  std::uint64_t m_step = ~0ull;
  double m_time = -1.0;
  std::uint64_t m_generations = 0;
};

}  // namespace fp::engine
