#include "engine/app_session.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "engine/cli.h"
#include "engine/scene_loader.h"
#include "sim/param_table.h"
#include "sim/state_io.h"

namespace fp::engine {

namespace {
using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

// exponential smoothing of the plotted rates, so one frame's burst reads as a bump, not a spike
float smooth(const Series& s, double value, double alpha) {
  return s.values().empty() ? float(value) : float((1.0 - alpha) * s.last() + alpha * value);
}
}  // namespace

void Series::push(float v) {
  if (m_values.size() >= m_capacity)
    m_values.erase(m_values.begin());
  m_values.push_back(v);
}

input::HandPose restingHandPose(const sim::SceneDesc& scene, const input::HandModel& model) {
  sim::Aabb water;
  for (const sim::FluidBlock& b : scene.fluid)
    water.extend(b.box);
  if (water.isEmpty())
    water = scene.domain;
  input::HandPose pose;
  const sim::Vec3d c = water.center();
  // fingertips 3 cm above the water, so building the fluid lattice leaves no hole around the hand
  pose.position = sim::Vec3d(c.x(), water.max().y() + model.reachBelowPalm() + 0.03, c.z());
  pose.position.y() = std::min(pose.position.y(), scene.domain.max().y() - 0.06 * model.scale());
  return pose;
}

std::vector<std::string> availableScenes() {
  namespace fs = std::filesystem;
  fs::path dir = "assets/scenes";
  if (!fs::is_directory(dir))
    dir = fs::path(FP_SOURCE_DIR) / "assets/scenes";
  std::vector<std::string> out;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".json")
      out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

AppSession::AppSession(const SessionConfig& config) : m_config(config) {
  fixedStep = config.fixedStep;
  timeScale = std::clamp(config.timeScale, 0.01, 4.0);
  m_scene = loadScene(config.scenePath);
  overrideScene(m_scene, {config.mode, config.seed, config.sets});
  m_params = m_scene.params;
  m_mode = m_scene.mode;
  if (!config.handScript.empty())
    m_replay = input::PoseTrack::load(config.handScript);
  build();
  if (!config.loadState.empty())
    loadStateFile(config.loadState);
}

AppSession::~AppSession() {
  m_task.wait();
  if (m_thread.joinable())
    m_thread.join();
}

void AppSession::build() {
  sim::SceneDesc scene = m_scene;
  scene.params = m_params;
  scene.mode = m_mode;
  const input::HandModel model(m_config.handScale);
  const input::HandPose rest = restingHandPose(m_scene, model);
  const input::HandDriver hand =
      m_config.hand ? input::HandDriver::attach(scene, model, rest) : input::HandDriver(model, 0);
  // tracked hands: parked above the water, 18 cm apart, until their first tracked frame
  sim::Aabb water;
  for (const sim::FluidBlock& b : m_scene.fluid)
    water.extend(b.box);
  const double park = (water.isEmpty() ? m_scene.domain.max().y() : water.max().y()) + 0.03;
  for (std::size_t k = 0; k < m_tracked.size(); ++k) {
    TrackedHand& t = m_tracked[k];
    input::HandPose pose = rest;
    pose.position.z() += (t.side == input::HandSide::Left ? 0.09 : -0.09);
    const input::HandJoints parked = input::jointsOfHandPose(input::HandModel(), pose, t.side);
    // the tracked hand's own sizes, at the parked hand's pose
    input::HandJoints placed = t.reference;
    const sim::Quatd turn = parked.joint[0].orientation * t.reference.joint[0].orientation.conjugate();
    for (input::JointPose& j : placed.joint) {
      j.position = parked.joint[0].position + turn * (j.position - t.reference.joint[0].position);
      j.orientation = (turn * j.orientation).normalized();
    }
    t.first = scene.colliders.size();
    for (sim::ColliderDesc& c : input::jointHandColliders(placed, t.side))
      scene.colliders.push_back(std::move(c));
    t.parts = input::partPosesFromJoints(placed);
    t.target = t.parts;
    t.through.clear();
    t.motion.set(t.parts, t.parts, 0.0, 1.0);
    // a lost hand rises until its lowest part is 3 cm above the water, at 1 m/s
    t.presence = input::HandPresence(park, 1.0);
  }
  // built aside first: a scene that fails to build leaves the running simulation as it was
  auto simulation = std::make_unique<sim::Simulation>(scene);
  m_restPose = rest;
  m_hand = hand;
  m_sim = std::move(simulation);
  m_handPose = m_restPose;
  m_handTarget = m_restPose;
  m_segment = input::PoseTrack();
  m_mouseHand.place(m_restPose);
  // the palm stays where the fingers remain inside the domain
  const sim::Vec3d margin(0.05, 0.3 * model.reachBelowPalm(), 0.05);
  m_mouseHand.lo = scene.domain.min() + margin;
  m_mouseHand.hi = scene.domain.max() - sim::Vec3d(margin.x(), 0.04, margin.z());
  if (m_replay)
    m_replayStart = 0.0;
  m_stats.uniformHighCount = double(m_sim->totalMass() / m_sim->latticeMass());
  m_targetTime = 0.0;
  m_stepsBefore = 0;
  m_splitsBefore = 0;
  m_mergesBefore = 0;
  m_wallTotal = 0.0;
  m_simTotal = 0.0;
  m_restartPending = false;
  m_handScalePending = false;
  m_error.clear();
  m_snapshots.clear();
  m_snapshotEdits.clear();
  m_recovery = RecoveryReport{};
  m_lastFinish = Clock::now();
}

namespace {
// the owner's numbers of a saved state: a tag, the hand pose (position, orientation, gestures), the replay's
// start and the fixed-step frame target
constexpr double kAppStateTag = 1501.0;
constexpr std::size_t kAppStateSize = 12;
}  // namespace

std::vector<double> AppSession::appState() const {
  const input::HandPose& h = m_handPose;
  return {kAppStateTag,      h.position.x(),    h.position.y(),    h.position.z(), h.orientation.w(),
          h.orientation.x(), h.orientation.y(), h.orientation.z(), h.grip,         h.point,
          m_replayStart,     m_targetTime};
}

void AppSession::restoreAppState(const std::vector<double>& e) {
  input::HandPose& h = m_handPose;
  h.position = sim::Vec3d(e[1], e[2], e[3]);
  h.orientation = sim::Quatd(e[4], e[5], e[6], e[7]);
  h.grip = e[8];
  h.point = e[9];
  m_replayStart = e[10];
  m_targetTime = e[11];
  m_handTarget = m_handPose;
  m_segment = input::PoseTrack();
  m_mouseHand.place(m_handPose);
}

void AppSession::saveStateNow(const std::string& path) {
  const std::string file = !path.empty()                 ? path
                           : !m_config.saveState.empty() ? m_config.saveState
                                                         : "fluidplaying_state.bin";
  sim::saveState(file, *m_sim, appState());
  m_savedStatePath = file;
}

void AppSession::loadStateFile(const std::string& path) {
  // the state now, put back when the app's numbers of the file are bad (the simulation's own are checked by
  // loadState, which leaves it unchanged when it refuses the file)
  const std::string before = sim::encodeState(*m_sim, appState());
  const std::vector<double> extra = sim::loadState(path, *m_sim);
  std::string bad;
  if (extra.size() != kAppStateSize || extra[0] != kAppStateTag) {
    bad = "not saved by the app (" + std::to_string(extra.size()) + " app numbers)";
  } else if (!std::all_of(extra.begin(), extra.end(), [](double v) { return std::isfinite(v); })) {
    bad = "a non-finite hand pose or time";
  } else if (std::abs(sim::Quatd(extra[4], extra[5], extra[6], extra[7]).norm() - 1.0) > 1e-6) {
    bad = "the hand's orientation is not a unit quaternion";
  }
  if (!bad.empty()) {
    sim::decodeState(before, *m_sim);
    throw sim::StateError(path + ": corrupt: " + bad);
  }
  restoreAppState(extra);
  m_params = m_sim->params();
  m_restartPending = false;
  m_error.clear();
  paused = false;
  m_snapshots.clear();
  m_snapshotEdits.clear();
  m_savedStatePath = path;
}

void AppSession::endRun() {
  finishSteps();
  if (!m_config.saveState.empty() && m_error.empty())
    saveStateNow();
}

void AppSession::takeSnapshot() {
  const double t = m_sim->time();
  if (!m_snapshots.empty() && t - m_snapshots.back().first < kSnapshotSpacing)
    return;
  m_snapshots.emplace_back(t, sim::encodeState(*m_sim, appState()));
  m_snapshotEdits.push_back(m_params);
  while (m_snapshots.size() > kSnapshots) {
    m_snapshots.pop_front();
    m_snapshotEdits.pop_front();
  }
}

bool AppSession::keepNonLive(sim::SimParams& next) const {
  bool pending = false;
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    if (info.live)
      continue;
    if (!sim::ParamTable::equal(info, next, m_sim->params())) {
      pending = true;
      sim::ParamTable::copy(info, m_sim->params(), next);
    }
  }
  return pending;
}

void AppSession::rollBack(const std::string& why) {
  RecoveryReport& r = m_recovery;
  const double failedAt = m_sim->time();
  const bool again = r.dtCap > 0.0;  // still in the last recovery: halve the cap further
  std::ostringstream s;
  s << "unstable at t = " << std::fixed << std::setprecision(2) << failedAt << " s (" << why << "): ";
  if (m_snapshots.empty()) {
    // nothing good kept (an instability within the first frames): the scene again, as loaded
    m_params = m_scene.params;
    const int rollbacks = r.rollbacks;
    build();
    m_recovery.rollbacks = rollbacks + 1;
    m_recovery.failedAt = failedAt;
    s << "no snapshot left, the scene was reset";
    m_recovery.message = s.str();
    return;
  }
  // the newest snapshot, dropped from the ring: a second failure goes further back
  const auto [time, bytes] = std::move(m_snapshots.back());
  const sim::SimParams edit = m_snapshotEdits.back();
  m_snapshots.pop_back();
  m_snapshotEdits.pop_back();
  restoreAppState(sim::decodeState(bytes, *m_sim));
  m_params = edit;  // an edit made since (an absurd value) is undone with the state
  const double base = again ? r.dtCap : m_params.dtMax;
  r.dtCap = std::max(0.5 * base, m_params.dtMin);
  r.capUntil = time + 1.0;
  ++r.rollbacks;
  r.failedAt = failedAt;
  r.restoredTo = time;
  // the snapshot's edits: the live ones now, the others (a particle radius changed in the panel before the
  // snapshot) still wait for a reset, as they did (they were applied here until session 20)
  sim::SimParams next = m_params;
  m_restartPending = keepNonLive(next);
  m_sim->params() = next;
  m_sim->params().dtMax = r.dtCap;
  s << "rolled back to t = " << time << " s, time step cap " << std::setprecision(3) << 1e3 * r.dtCap
    << " ms for 1 s (rollback " << r.rollbacks << ")";
  r.message = s.str();
}

void AppSession::setTrackedHands(
    const std::vector<std::pair<input::HandSide, input::HandJoints>>& references) {
  m_tracked.clear();
  for (const auto& [side, joints] : references) {
    TrackedHand t;
    t.side = side;
    t.reference = joints;
    m_tracked.push_back(t);
  }
}

void AppSession::setTrackedHandTarget(
    std::size_t k, const std::optional<std::array<input::PartPose, input::HandModel::kParts>>& parts,
    double frameDt) {
  TrackedHand& t = m_tracked.at(k);
  if (!t.presence.placed() && !parts)
    return;  // parked until first seen
  if (!t.presence.placed())
    t.presence.park(t.parts);  // the first sight: eased to from the parked pose, never jumped to
  t.target = t.presence.update(parts, frameDt);
  t.through.push_back(t.target);
}

void AppSession::setHandScale(double scale) {
  scale = std::clamp(scale, 0.5, 3.0);
  if (scale != m_config.handScale) {
    m_config.handScale = scale;
    m_handScalePending = true;
  }
}

void AppSession::startReplay(const input::PoseTrack& track) {
  m_replay = track;
  m_replayStart = m_sim->time();
}

void AppSession::stopReplay() {
  m_replay.reset();
  m_mouseHand.place(m_handPose);
}

void AppSession::startRecording() {
  m_recording = input::PoseTrack();
  m_recordStart = m_sim->time();
  m_recording->add(input::poseSampleOf(0.0, m_handPose));
}

input::PoseTrack AppSession::stopRecording() {
  input::PoseTrack out = m_recording ? std::move(*m_recording) : input::PoseTrack();
  m_recording.reset();
  return out;
}

std::string AppSession::toggleRecording(const std::string& path) {
  if (!recording()) {
    startRecording();
    return "recording the hand (F5 stops)";
  }
  try {
    stopRecording().save(path);
    return "hand motion saved to " + path;
  } catch (const sim::InputError& e) {
    return e.what();
  }
}

std::string AppSession::toggleReplay(const std::string& path) {
  if (replaying()) {
    stopReplay();
    return "";
  }
  try {
    startReplay(input::PoseTrack::load(path));
  } catch (const sim::InputError& e) {
    return e.what();
  }
  return "";
}

double AppSession::meanRealTimeFactor() const {
  return m_wallTotal > 0.0 ? m_simTotal / m_wallTotal : 0.0;
}

void AppSession::finishSteps() {
  const auto waitStart = Clock::now();
  m_task.wait();
  if (m_thread.joinable())
    m_thread.join();
  const auto now = Clock::now();
  const bool ran = m_running;
  const bool stepped = ran && m_taskSteps > 0;
  m_running = false;
  m_stats.waitMs = 1e3 * seconds(now - waitStart);
  const double frameWall = seconds(now - m_lastFinish);
  m_lastFinish = now;
  if (m_config.recover && m_taskError.empty() && stepped &&
      m_sim->lastStep().densityError > kDensityErrorLimit) {
    std::ostringstream s;
    s << "mean density error " << 100.0 * m_sim->lastStep().densityError << " % past "
      << 100.0 * kDensityErrorLimit << " %";
    m_taskError = s.str();
  }
  if (!m_taskError.empty()) {
    const std::string why = std::move(m_taskError);
    m_taskError.clear();
    if (m_config.recover) {
      rollBack(why);
    } else {
      m_error = why;
      paused = true;
    }
  } else if (stepped) {
    ++m_framesDone;
    if (m_config.recover)
      takeSnapshot();
    if (!m_config.saveState.empty() && m_config.saveStateEvery > 0 &&
        m_framesDone % m_config.saveStateEvery == 0)
      saveStateNow();
  }
  // where the hand is now: the motion's pose at the simulated time reached
  const double t = m_sim->time();
  if (m_replay)
    m_handPose = input::handPoseOf(m_replay->sample(t - m_replayStart));
  else if (!m_segment.keys().empty())
    m_handPose = input::handPoseOf(m_segment.sample(t));
  for (TrackedHand& h : m_tracked)
    h.parts = h.motion.sample(t);
  if (m_recording && t - m_recordStart > m_recording->duration())
    m_recording->add(input::poseSampleOf(t - m_recordStart, m_handPose));
  if (!ran || frameWall <= 0.0)
    return;

  const double simAdvance = t - m_frameStartSim;
  const sim::RunStats& run = m_sim->runStats();
  m_stats.steps = m_taskSteps;
  m_stats.simMs = 1e3 * m_stepWallSeconds;
  m_stats.frameMs = 1e3 * frameWall;
  m_stats.fps.push(float(1.0 / frameWall));
  m_stats.msPerStep.push(m_taskSteps > 0 ? float(1e3 * m_stepWallSeconds / m_taskSteps)
                                         : m_stats.msPerStep.last());
  m_stats.particles.push(float(m_sim->particles().size()));
  m_stats.highShare.push(
      float(100.0 * double(m_sim->particles().size()) / std::max(1.0, m_stats.uniformHighCount)));
  const double splits = double(run.adaptivity.splits - m_splitsBefore);
  const double merges = double(run.adaptivity.merges - m_mergesBefore);
  m_splitsBefore = run.adaptivity.splits;
  m_mergesBefore = run.adaptivity.merges;
  m_stepsBefore = run.steps;
  m_stats.splitsPerSecond.push(
      smooth(m_stats.splitsPerSecond, simAdvance > 0 ? splits / simAdvance : 0.0, 0.2));
  m_stats.mergesPerSecond.push(
      smooth(m_stats.mergesPerSecond, simAdvance > 0 ? merges / simAdvance : 0.0, 0.2));
  m_stats.densityError.push(float(100.0 * m_sim->lastStep().densityError));
  m_stats.realTimeFactor.push(smooth(m_stats.realTimeFactor, simAdvance / frameWall, 0.1));
  m_wallTotal += frameWall;
  m_simTotal += simAdvance;
}

void AppSession::applyRequests() {
  SessionRequests req = std::move(m_requests);
  m_requests = SessionRequests{};
  if (req.resetToSavedState && !m_savedStatePath.empty()) {
    try {
      loadStateFile(m_savedStatePath);
      return;
    } catch (const sim::InputError& e) {
      m_error = e.what();  // shown by the panel; the running simulation goes on
    }
  }
  bool rebuild = req.reset;
  const sim::SceneDesc previousScene = m_scene;
  const std::string previousPath = m_config.scenePath;
  if (req.scenePath) {
    try {
      sim::SceneDesc scene = loadScene(*req.scenePath);
      m_scene = std::move(scene);
      m_config.scenePath = *req.scenePath;
      m_params = m_scene.params;
      m_mode = m_scene.mode;
      rebuild = true;
    } catch (const sim::InputError& e) {
      m_error = e.what();  // shown by the panel; the running scene goes on
    }
  }
  if (req.mode && *req.mode != m_mode) {
    m_mode = *req.mode;
    rebuild = true;
  }
  if (!sim::ParamTable::validate(m_params).empty()) {
    // an edit in progress that breaks a relation (lo above hi): keep running with the last valid set
    m_params = m_sim->params();
  }
  if (rebuild) {
    const bool failed = !m_error.empty();
    try {
      build();
      if (failed)
        paused = false;  // the reset is the way out of an instability
    } catch (const sim::InputError& e) {
      m_scene = previousScene;
      m_config.scenePath = previousPath;
      m_params = m_sim->params();
      m_mode = m_sim->mode();
      m_error = std::string("cannot build the scene: ") + e.what();
    }
    return;
  }
  // live parameters now; the others wait for a reset
  sim::SimParams next = m_params;
  const bool pending = keepNonLive(next);
  // the recovery's time-step cap for its second, then the edited step again
  if (m_recovery.dtCap > 0.0 && m_sim->time() >= m_recovery.capUntil)
    m_recovery.dtCap = 0.0;
  if (m_recovery.dtCap > 0.0)
    next.dtMax = std::max(next.dtMin, std::min(next.dtMax, m_recovery.dtCap));
  m_sim->params() = next;
  m_restartPending = pending;
  if (req.singleStep && paused)
    m_singleStep = true;
}

void AppSession::startSteps(double wallDt, double budget) {
  sim::Simulation& simulation = *m_sim;
  m_frameStartSim = simulation.time();
  m_taskSteps = 0;
  m_stepWallSeconds = 0.0;
  const bool oneStep = m_singleStep;
  m_singleStep = false;
  const double t0 = simulation.time();
  if (paused && !oneStep) {
    // a paused hand stays put: moving it with no steps would teleport it into the water on resume
    m_mouseHand.place(m_handPose);
    m_segment = input::PoseTrack();
    m_segment.add(input::poseSampleOf(t0, m_handPose));
    m_targetTime = t0;
    for (TrackedHand& h : m_tracked) {
      h.motion.set(h.parts, h.parts, t0, t0 + 1.0);
      h.through.clear();
    }
    m_stepsDone.store(true, std::memory_order_release);
    m_running = true;
    return;
  }
  wallDt = std::clamp(wallDt, 0.0, 0.1);  // a stall (window drag, rebuild) is not simulated after the fact
  double target;
  if (oneStep) {
    target = std::numeric_limits<double>::infinity();
  } else if (fixedStep) {
    // the target advances by exactly one frame, so a step's overshoot is paid back in the next frame
    m_targetTime = std::max(m_targetTime, t0 - 0.5 / m_scene.frameRate) + 1.0 / m_scene.frameRate;
    target = m_targetTime;
  } else {
    // behind the wall clock by more than a step: drop the deficit, so time slows instead of racing to catch
    // up
    if (m_targetTime - t0 > simulation.params().dtMax || m_targetTime < t0)
      m_targetTime = t0;
    m_targetTime += wallDt * timeScale;
    target = m_targetTime;
  }
  target = std::min(target, m_endTime);
  // the frame's hand motion: from where the hand is to the new target at the frame's end
  if (!m_replay) {
    m_segment = input::PoseTrack();
    m_segment.add(input::poseSampleOf(t0, m_handPose));
    const double tEnd = std::isfinite(target) ? target : t0 + simulation.params().dtMax;
    if (tEnd > t0)
      m_segment.add(input::poseSampleOf(tEnd, m_handTarget));
  }
  for (TrackedHand& h : m_tracked) {
    const double tEnd = std::isfinite(target) ? target : t0 + simulation.params().dtMax;
    // through every frame's target since the last steps (one: the frame's own, two keys as always)
    if (h.through.size() > 1)
      h.motion.set(h.parts, h.through, t0, tEnd);
    else
      h.motion.set(h.parts, h.target, t0, tEnd);
    h.through.clear();
  }
  m_running = true;
  m_stepsDone.store(false, std::memory_order_relaxed);
  const double stepBudget = oneStep || fixedStep ? std::numeric_limits<double>::infinity() : budget;
  auto steps = [this, target, stepBudget, oneStep] {
    runSteps(target, stepBudget, oneStep);
    m_stepsDone.store(true, std::memory_order_release);
  };
  if (m_config.stepThread)
    m_thread = std::thread(steps);
  else
    m_task.run(steps);
}

void AppSession::runSteps(double target, double budget, bool oneStep) {
  sim::Simulation& simulation = *m_sim;
  const auto start = Clock::now();
  const input::PoseTrack& motion = m_replay ? *m_replay : m_segment;
  const double trackStart = m_replay ? m_replayStart : 0.0;
  try {
    while (simulation.time() < target - 1e-12) {
      const double last = simulation.lastStep().dt;
      const double estimate = last > 0.0 ? last : simulation.params().dtMax;
      // never ahead of the wall clock: stop when the next step would pass the target (fixed steps finish it)
      if (!fixedStep && !oneStep && simulation.time() + estimate > target + 1e-12)
        break;
      if (m_config.hand)
        m_hand.apply(simulation, motion, trackStart, estimate);
      for (const TrackedHand& h : m_tracked)
        h.motion.apply(simulation, h.first, estimate);
      simulation.step();
      ++m_taskSteps;
      if (m_slowStepsDone < m_config.slowSteps) {
        ++m_slowStepsDone;
        std::this_thread::sleep_for(std::chrono::duration<double>(m_config.slowStepSeconds));
      }
      if (oneStep || seconds(Clock::now() - start) > budget)
        break;
    }
    // the lists of the state the frame shows: the splash reads them, and the next step starts from them
    simulation.prepareNeighbors();
  } catch (const sim::InstabilityError& e) {
    m_taskError = e.what();
  }
  m_stepWallSeconds = seconds(Clock::now() - start);
}

}  // namespace fp::engine
