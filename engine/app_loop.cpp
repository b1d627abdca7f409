#include "engine/app_loop.h"

namespace fp::engine {

int runAppLoop(AppSession& session, AppPlatform& platform, std::optional<int> frames) {
  int frame = 0;
  while ((!frames || frame < *frames) && platform.running()) {
    const FrameClock clock = platform.beginFrame();
    session.finishSteps();
    if (clock.restart) {
      platform.restart(session);
      continue;
    }
    platform.input(session, clock);
    session.applyRequests();
    if (clock.render)
      platform.capture(session, frame);
    if (clock.simulate)
      session.startSteps(clock.dt, platform.stepBudget());
    if (clock.render)
      platform.draw(session, frame);
    ++frame;
  }
  session.endRun();  // the last steps joined; --save-state written
  return frame;
}

}  // namespace fp::engine
