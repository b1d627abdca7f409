#include "engine/app_loop.h"

#include <chrono>

namespace fp::engine {

int runAppLoop(AppSession& session, AppPlatform& platform, std::optional<int> frames) {
  using Clock = std::chrono::steady_clock;
  auto last = Clock::now();
  int frame = 0;
  for (; (!frames || frame < *frames) && platform.running(); ++frame) {
    const auto now = Clock::now();
    const double wallDt = std::chrono::duration<double>(now - last).count();
    last = now;
    session.finishSteps();
    platform.input(session, wallDt);
    session.applyRequests();
    platform.capture(session, frame);
    session.startSteps(wallDt, platform.stepBudget());
    platform.draw(session, frame);
  }
  session.finishSteps();
  return frame;
}

}  // namespace fp::engine
