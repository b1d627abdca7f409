#include "engine/app_loop.h"

namespace fp::engine {

int runAppLoop(AppSession& session, AppPlatform& platform, std::optional<int> frames) {
  int frame = 0;
  double deferred = 0.0;  // time of the frames drawn while the steps ran [s], given to the next steps
  while ((!frames || frame < *frames) && platform.running()) {
    const FrameClock clock = platform.beginFrame();
    if (!clock.waitForSteps && !clock.restart && !session.fixedStep && session.stepsRunning()) {
      // the frame's deadline comes first: the last captured state again, the input queued for the next steps
      platform.inputWhileStepping(session, clock);
      if (clock.simulate)
        deferred += clock.dt;
      if (clock.render)
        platform.draw(session, frame);
      ++frame;
      continue;
    }
    session.finishSteps();
    if (clock.restart) {
      platform.restart(session);
      continue;
    }
    platform.input(session, clock);
    session.applyRequests();
    if (clock.render)
      platform.capture(session, frame);
    if (clock.simulate) {
      session.startSteps(clock.dt + deferred, platform.stepBudget());
      deferred = 0.0;
    }
    if (clock.render)
      platform.draw(session, frame);
    ++frame;
  }
  session.endRun();  // the last steps joined; --save-state written
  return frame;
}

}  // namespace fp::engine
