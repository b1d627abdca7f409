#include "engine/app_session.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "engine/cli.h"
#include "engine/scene_loader.h"

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
}

AppSession::~AppSession() {
  m_task.wait();
}

void AppSession::build() {
  sim::SceneDesc scene = m_scene;
  scene.params = m_params;
  scene.mode = m_mode;
  const input::HandModel model(m_config.handScale);
  const input::HandPose rest = restingHandPose(m_scene, model);
  const input::HandDriver hand =
      m_config.hand ? input::HandDriver::attach(scene, model, rest) : input::HandDriver(model, 0);
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
  m_lastFinish = Clock::now();
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

double AppSession::meanRealTimeFactor() const {
  return m_wallTotal > 0.0 ? m_simTotal / m_wallTotal : 0.0;
}

void AppSession::finishSteps() {
  const auto waitStart = Clock::now();
  m_task.wait();
  const auto now = Clock::now();
  const bool ran = m_running;
  m_running = false;
  m_stats.waitMs = 1e3 * seconds(now - waitStart);
  const double frameWall = seconds(now - m_lastFinish);
  m_lastFinish = now;
  if (!m_taskError.empty()) {
    m_error = m_taskError;
    m_taskError.clear();
    paused = true;
  }
  // where the hand is now: the motion's pose at the simulated time reached
  const double t = m_sim->time();
  if (m_replay)
    m_handPose = input::handPoseOf(m_replay->sample(t - m_replayStart));
  else if (!m_segment.keys().empty())
    m_handPose = input::handPoseOf(m_segment.sample(t));
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
  bool pending = false;
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    if (info.live)
      continue;
    if (!sim::ParamTable::equal(info, next, m_sim->params())) {
      pending = true;
      sim::ParamTable::copy(info, m_sim->params(), next);
    }
  }
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
  m_running = true;
  const double stepBudget = oneStep || fixedStep ? std::numeric_limits<double>::infinity() : budget;
  m_task.run([this, target, stepBudget, oneStep] { runSteps(target, stepBudget, oneStep); });
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
      simulation.step();
      ++m_taskSteps;
      if (oneStep || seconds(Clock::now() - start) > budget)
        break;
    }
  } catch (const sim::InstabilityError& e) {
    m_taskError = e.what();
  }
  m_stepWallSeconds = seconds(Clock::now() - start);
}

}  // namespace fp::engine
