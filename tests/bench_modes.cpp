/// fp_bench_modes: the paper's experiment. Runs one scene (default: the propeller) for the same simulated
/// time in each resolution mode, one after the other in this process, and prints one table row per mode plus
/// the same figures as CSV: wall time of the simulation steps and speed-up against uniform-high, mean and max
/// particle count as a share of uniform-high, the splash height (the mass-weighted 99.9th-percentile fluid
/// height above the mode's resting level: its mean over the frames and its maximum, without and with the
/// splash particles), splash particles per frame, the mean density error, the density error decrease from
/// choosing split orientations, and the share of step time spent on levels and adaptation. With --out it also
/// writes the CSV, the per-frame series, SVG plots of the particle count and the splash height over time, and
/// (with
/// --images) one rendered image per mode at the same instant, side by side like the paper's figure 3.
///
///   fp_bench_modes [--scene FILE] [--sim-time S] [--modes a,b,..] [--threads T] [--runs N]
///                  [--set KEY=VALUE]... [--csv FILE] [--out DIR [--images] [--image-time S]] [--quick]
///                  [--help]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "engine/cli.h"
#include "engine/cli_app.h"
#include "engine/headless_render.h"
#include "engine/scene_loader.h"
#include "render/image.h"
#include "sim/metrics.h"
#include "sim/simulation.h"
#include "sim/splash.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace fp;

const char* const kDefaultScene = FP_SOURCE_DIR "/assets/scenes/propeller.json";
constexpr double kDefaultSimTime = 2.0;
constexpr double kQuickSimTime = 0.3;
/// the splash height is the height below which this share of the water's mass lies
constexpr double kHeightFraction = 0.999;
/// starting phase between the perturbed runs of a mode: a fraction of a blade's turn [rad]
constexpr double kPhaseStep = 0.4;

/// One frame of a run.
struct Sample {
  double t = 0;               // simulated time [s]
  std::size_t particles = 0;  // fluid particles
  double height = 0;          // 99.9th-percentile fluid height above the resting level [m]
  double heightSplash = 0;    // the same with the splash particles [m]
  std::size_t splash = 0;     // splash particles
  // what the particles are refined for (adaptive modes, from the last levels): fully fine at the surface
  // (R_phi = 0), in the graded band below it, refined by vorticity or velocity difference, at the base mass;
  // and how many are too light, waiting to merge
  std::size_t surfaceFine = 0, band = 0, dynamic = 0, base = 0, tooLight = 0;
  sim::DensityErrorMeans densityError;  // of the last step's densities
};

struct Row {
  std::string mode;
  std::vector<Sample> series;
  double heightMean = 0, heightMax = 0, heightSplashMean = 0, heightSplashMax = 0, splashMean = 0;
  double restLevel = 0;  // 99.9 % mass height of this mode at rest [m]
  std::string status = "ok";
  double wall = 0;
  std::uint64_t steps = 0;
  double particlesMean = 0;
  std::size_t particlesMax = 0;
  double densityError = 0;
  sim::AdaptivityStats adaptivity;
  double adaptivityShare = 0;
  double levelsShare = 0;  // levels alone, share of step time
  double level1Share = 0;  // time_levels = 2: particle-steps on time level 1, share of all particle-steps
  double heldShare = 0;    // particle-steps that held their acceleration (skipped the solves), share
  // what time steps per particle could save at most (sim::timeStepHeadroom), particle-weighted over the steps
  // of the first run: the particle-steps an ideal power-of-two scheme takes, within dt_max and without it
  double headroomCapped = 1, headroomUncapped = 1;
  sim::PhaseTimes times;  // wall time by phase, summed over the steps (of the first run)
  double surfaceFine = 0, band = 0, dynamic = 0, base = 0, tooLight = 0;  // mean particles per frame
  double densityErrorParticles = 0, densityErrorVolume = 0;  // frame means, per particle and volume-weighted
  std::vector<double> runHeightMean, runHeightMax;           // heightMean and heightMax of every run [m]
  std::vector<double> runOrientationGain;                    // split error reduction of every run
  double pooledErrorChosen = 0, pooledErrorUnrotated = 0;    // the split errors summed over the runs
  double pooledErrorRotated = 0;  // E of the chosen rotations before the children moved, summed over the runs
  // the split children's density in the first density pass after their split against their parent's
  // (|rho_s - rho_o| / rho0, summed over the children) and the children counted, summed over the runs
  double splitJumpSum = 0;
  std::uint64_t splitJumpChildren = 0;
  std::vector<double> runSplitJump;     // the mean jump of every run
  std::vector<double> runDensityError;  // densityError of every run
};

/// Follows the children of each split into the solver's next density pass: their density there against the
/// parent's density they were created with, |rho_s - rho_o| / rho0. This is the density error of a split as
/// the solver simulates it (the split error E predicts it at the instant of the split).
class SplitJumpTracker {
 public:
  /// call after every step
  void afterStep(const sim::Simulation& simulation) {
    const sim::ParticleSet& p = simulation.particles();
    const double rho0 = simulation.params().restDensity;
    if (!m_parentRho.empty()) {
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (!(p.flags[i] & sim::kFlagSplit))
          continue;
        const auto it = m_parentRho.find(p.id[i]);
        if (it == m_parentRho.end())
          continue;
        sum += std::abs(double(p.rho[i]) - it->second) / rho0;
        ++children;
      }
    }
    // this step's children hold their parent's density (Adaptivity::adapt) until the next density pass
    m_parentRho.clear();
    const sim::Real now = sim::Real(simulation.time());
    for (std::size_t i = 0; i < p.size(); ++i) {
      if ((p.flags[i] & sim::kFlagSplit) && p.splitTime[i] == now)
        m_parentRho.emplace(p.id[i], double(p.rho[i]));
    }
  }
  double sum = 0.0;
  std::uint64_t children = 0;

 private:
  std::unordered_map<std::uint32_t, double> m_parentRho;
};

std::string machineDescription() {
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  std::string model = "unknown CPU";
  while (std::getline(cpu, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

/// An SVG line plot of one series per mode over time.
void writePlot(const std::string& path, const std::string& title, const std::string& unit,
               const std::vector<Row>& rows, double (*value)(const Sample&)) {
  const double w = 720, h = 400, left = 70, right = 150, top = 40, bottom = 50;
  double tMax = 0, vMin = 0, vMax = 0;
  for (const Row& r : rows)
    for (const Sample& s : r.series) {
      tMax = std::max(tMax, s.t);
      vMax = std::max(vMax, value(s));
      vMin = std::min(vMin, value(s));
    }
  if (tMax <= 0)
    tMax = 1;
  if (vMax <= vMin)
    vMax = vMin + 1;
  auto px = [&](double t) { return left + (w - left - right) * t / tMax; };
  auto py = [&](double v) { return h - bottom - (h - top - bottom) * (v - vMin) / (vMax - vMin); };
  const char* colours[] = {"#888888", "#1f77b4", "#ff7f0e", "#d62728", "#2ca02c", "#9467bd"};
  std::ofstream f(path);
  f << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w << "\" height=\"" << h
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
       "fill=\"white\"/>\n";
  f << "<text x=\"" << left << "\" y=\"22\" font-size=\"15\">" << title << "</text>\n";
  f << "<line x1=\"" << left << "\" y1=\"" << h - bottom << "\" x2=\"" << w - right << "\" y2=\""
    << h - bottom << "\" stroke=\"black\"/>\n<line x1=\"" << left << "\" y1=\"" << top << "\" x2=\"" << left
    << "\" y2=\"" << h - bottom << "\" stroke=\"black\"/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double t = tMax * k / 4.0;
    const double v = vMin + (vMax - vMin) * k / 4.0;
    char label[64];
    std::snprintf(label, sizeof(label), "%.2f", t);
    f << "<text x=\"" << px(t) << "\" y=\"" << h - bottom + 18 << "\" text-anchor=\"middle\">" << label
      << "</text>\n";
    std::snprintf(label, sizeof(label), "%.4g", v);
    f << "<text x=\"" << left - 6 << "\" y=\"" << py(v) + 4 << "\" text-anchor=\"end\">" << label
      << "</text>\n";
    f << "<line x1=\"" << left << "\" y1=\"" << py(v) << "\" x2=\"" << w - right << "\" y2=\"" << py(v)
      << "\" stroke=\"#e0e0e0\"/>\n";
  }
  f << "<text x=\"" << (left + w - right) / 2 << "\" y=\"" << h - 10
    << "\" text-anchor=\"middle\">simulated time [s]</text>\n";
  f << "<text x=\"16\" y=\"" << (top + h - bottom) / 2 << "\" transform=\"rotate(-90 16 "
    << (top + h - bottom) / 2 << ")\" text-anchor=\"middle\">" << unit << "</text>\n";
  for (std::size_t m = 0; m < rows.size(); ++m) {
    const char* c = colours[m % 6];
    f << "<polyline fill=\"none\" stroke=\"" << c << "\" stroke-width=\"1.5\" points=\"";
    for (const Sample& s : rows[m].series)
      f << px(s.t) << "," << py(value(s)) << " ";
    f << "\"/>\n<text x=\"" << w - right + 10 << "\" y=\"" << top + 16 * (m + 1) << "\" fill=\"" << c << "\">"
      << rows[m].mode << "</text>\n";
  }
  f << "</svg>\n";
}

/// A mode's water at rest, frame by frame: the same scene with every collider held still, sampled at the
/// run's frame times. Each mode has its own: coarse particles keep a larger distance from the floor (the
/// wall holds them at about 2.2 of their own radii), which lifts the whole water surface by a few fine
/// radii, and that must not count as splash. And the settled start is not quite at rest: at r = 0.00538 m
/// uniform-high's still water rose 14 mm over its first 0.5 s and sank back by 1.5 s, so a single resting
/// level taken early read the propeller's splash as -10 mm. A run's height at a frame is taken above the
/// still run's at the same frame, which cancels what the start does in both.
struct StillRun {
  std::vector<double> frames;  // 99.9 % mass height per frame, a moving median over 5 frames [m]
  double level = 0;            // the median over the still run's second half [m]
  /// the still height at `frame`; past the still run's end its resting level
  double at(std::size_t frame) const { return frame < frames.size() ? frames[frame] : level; }
};

StillRun stillRun(sim::SceneDesc scene, double restTime) {
  for (sim::ColliderDesc& c : scene.colliders) {
    c.linearVelocity.setZero();
    c.angularVelocity.setZero();
    c.driven = false;
  }
  sim::Simulation simulation(scene);
  const double frameDt = 1.0 / scene.frameRate;
  std::vector<double> raw{sim::heightPercentile(simulation.particles(), kHeightFraction)};
  std::vector<double> late;
  while (simulation.time() < restTime - 1e-12) {
    simulation.step();
    const double h = sim::heightPercentile(simulation.particles(), kHeightFraction);
    // sampled as runMode samples: the first step at or past each frame's time
    if (simulation.time() >= double(raw.size()) * frameDt - 1e-12)
      raw.push_back(h);
    if (simulation.time() > 0.5 * restTime)
      late.push_back(h);
  }
  StillRun still;
  if (late.empty())
    late.push_back(raw.back());
  std::nth_element(late.begin(), late.begin() + std::ptrdiff_t(late.size() / 2), late.end());
  still.level = late[late.size() / 2];
  // (a median of 5 frames: one frame's percentile jumps by a particle's height as particles cross it)
  for (std::size_t k = 0; k < raw.size(); ++k) {
    std::vector<double> window;
    for (std::size_t q = k > 2 ? k - 2 : 0; q <= std::min(raw.size() - 1, k + 2); ++q)
      window.push_back(raw[q]);
    std::nth_element(window.begin(), window.begin() + std::ptrdiff_t(window.size() / 2), window.end());
    still.frames.push_back(window[window.size() / 2]);
  }
  return still;
}

/// The scene with every spinning collider started `angle` further along its spin [rad]: a perturbed start of
/// the same experiment.
sim::SceneDesc withStartingPhase(sim::SceneDesc scene, double angle) {
  for (sim::ColliderDesc& c : scene.colliders) {
    if (c.driven || c.angularVelocity.norm() <= 0.0)
      continue;
    c.orientation =
        (sim::Quatd(Eigen::AngleAxisd(angle, c.angularVelocity.normalized())) * c.orientation).normalized();
  }
  return scene;
}

/// One run of one mode, its heights measured above the still water's at the same frame (`still`). The wall
/// time counts the simulation only: frame sampling, splash and rendering are timed out.
Row runMode(sim::SceneDesc scene, sim::AdaptivityMode mode, double simTime, const StillRun& still,
            double imageTime, engine::HeadlessRender* render, sim::SplashParticles* imageSplash) {
  scene.mode = mode;
  Row row;
  row.mode = sim::modeName(mode);
  row.restLevel = still.level;
  sim::Simulation simulation(scene);
  sim::SplashGenerator splash;
  int frame = 0;
  bool imageDone = false;
  auto sample = [&]() {
    const sim::SplashParticles& sp = splash.generate(simulation, std::uint64_t(frame));
    Sample s;
    s.t = simulation.time();
    s.particles = simulation.particles().size();
    s.splash = sp.size();
    s.height = sim::heightPercentile(simulation.particles(), kHeightFraction);
    s.heightSplash =
        sim::heightPercentile(simulation.particles(), kHeightFraction, &sp, scene.params.splashCount);
    s.height -= still.at(std::size_t(frame));
    s.heightSplash -= still.at(std::size_t(frame));
    s.densityError = sim::densityErrorMeans(simulation.particles(), scene.params.restDensity);
    if (simulation.adaptive()) {
      const sim::ParticleSet& p = simulation.particles();
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (p.levelOmega[i] * p.levelNu[i] > sim::Real(1.01))
          ++s.dynamic;
        else if (p.levelPhi[i] <= sim::Real(0))
          ++s.surfaceFine;
        else if (p.levelPhi[i] < sim::Real(1))
          ++s.band;
        else
          ++s.base;
        if (p.m[i] < sim::Real(scene.params.mergeBelow) * p.mOpt[i])
          ++s.tooLight;
      }
    }
    row.series.push_back(s);
    if (render && !imageDone && simulation.time() >= imageTime - 1e-9) {
      render->renderFrame(0, simulation, &sp);
      if (imageSplash)
        *imageSplash = sp;
      imageDone = true;
    }
    ++frame;
  };
  const double frameDt = 1.0 / scene.frameRate;
  double wall = 0.0;
  SplitJumpTracker jumps;
  double headroomCapped = 0.0, headroomUncapped = 0.0, headroomParticles = 0.0;
  sample();
  try {
    while (simulation.time() < simTime - 1e-12) {
      const auto start = Clock::now();
      simulation.step();
      wall += std::chrono::duration<double>(Clock::now() - start).count();
      if (simulation.adaptive())
        jumps.afterStep(simulation);
      const sim::TimeStepHeadroom h =
          sim::timeStepHeadroom(simulation.particles(), simulation.lastStep().dt,
                                simulation.params().cflFactor, simulation.params().dtMax);
      const double count = double(simulation.particles().size());
      headroomCapped += count * h.capped;
      headroomUncapped += count * h.uncapped;
      headroomParticles += count;
      if (simulation.time() >= frame * frameDt - 1e-12)
        sample();
    }
  } catch (const sim::InstabilityError& e) {
    row.status = e.what();
  }
  if (render && !imageDone)
    render->renderFrame(0, simulation);
  row.wall = wall;
  if (headroomParticles > 0) {
    row.headroomCapped = headroomCapped / headroomParticles;
    row.headroomUncapped = headroomUncapped / headroomParticles;
  }
  for (const Sample& s : row.series) {
    row.heightMean += s.height / double(row.series.size());
    row.heightSplashMean += s.heightSplash / double(row.series.size());
    row.splashMean += double(s.splash) / double(row.series.size());
    row.heightMax = std::max(row.heightMax, s.height);
    row.heightSplashMax = std::max(row.heightSplashMax, s.heightSplash);
    const double f = 1.0 / double(row.series.size());
    row.surfaceFine += f * double(s.surfaceFine);
    row.band += f * double(s.band);
    row.dynamic += f * double(s.dynamic);
    row.base += f * double(s.base);
    row.tooLight += f * double(s.tooLight);
    if (s.t > 0) {
      row.densityErrorParticles += s.densityError.perParticle / double(row.series.size() - 1);
      row.densityErrorVolume += s.densityError.volumeWeighted / double(row.series.size() - 1);
    }
  }
  const sim::RunStats& run = simulation.runStats();
  row.steps = run.steps;
  row.particlesMean = run.steps ? double(run.particleSteps) / double(run.steps) : 0.0;
  row.particlesMax = run.particlesMax;
  row.densityError = run.steps ? run.densityErrorSum / double(run.steps) : 0.0;
  row.adaptivity = run.adaptivity;
  const double total = run.times.total();
  row.adaptivityShare = total > 0 ? (run.times.levels + run.times.adaptation) / total : 0.0;
  row.levelsShare = total > 0 ? run.times.levels / total : 0.0;
  row.times = run.times;
  if (run.particleSteps > 0) {
    row.level1Share = double(run.level1ParticleSteps) / double(run.particleSteps);
    row.heldShare = double(run.heldParticleSteps) / double(run.particleSteps);
  }
  row.runHeightMean.push_back(row.heightMean);
  row.runHeightMax.push_back(row.heightMax);
  row.runOrientationGain.push_back(row.adaptivity.splitErrorReduction());
  row.pooledErrorChosen = row.adaptivity.splitErrorChosen;
  row.pooledErrorUnrotated = row.adaptivity.splitErrorUnrotated;
  row.pooledErrorRotated = row.adaptivity.splitErrorRotated;
  row.splitJumpSum = jumps.sum;
  row.splitJumpChildren = jumps.children;
  row.runSplitJump.push_back(jumps.children ? jumps.sum / double(jumps.children) : 0.0);
  row.runDensityError.push_back(row.densityError);
  return row;
}

/// Mean and sample standard deviation.
std::pair<double, double> meanAndSpread(const std::vector<double>& v) {
  if (v.empty())
    return {0.0, 0.0};
  double mean = 0.0;
  for (double x : v)
    mean += x / double(v.size());
  double var = 0.0;
  for (double x : v)
    var += (x - mean) * (x - mean);
  return {mean, v.size() > 1 ? std::sqrt(var / double(v.size() - 1)) : 0.0};
}

/// `runs` runs of one mode, the k-th with the spinning colliders' starting phase advanced by k kPhaseStep
/// (one still run for all): the figures of the first run, and the splash heights of every run.
Row runModeRepeated(const sim::SceneDesc& scene, sim::AdaptivityMode mode, double simTime, double restTime,
                    double imageTime, engine::HeadlessRender* render, int runs) {
  sim::SceneDesc still = scene;
  still.mode = mode;
  StillRun rest;
  try {
    rest = stillRun(still, restTime > 0.0 ? restTime : simTime);
  } catch (const sim::InstabilityError& e) {
    // the mode's still run went unstable: a row that says so (exit code 4), not an abort
    Row row;
    row.mode = sim::modeName(mode);
    row.status = std::string("still run: ") + e.what();
    return row;
  }
  Row row = runMode(scene, mode, simTime, rest, imageTime, render, nullptr);
  for (int k = 1; k < runs && row.status == "ok"; ++k) {
    std::fprintf(stderr, "    run %d of %d ...\n", k + 1, runs);
    const Row more =
        runMode(withStartingPhase(scene, k * kPhaseStep), mode, simTime, rest, imageTime, nullptr, nullptr);
    if (more.status != "ok")
      row.status = more.status;
    row.runHeightMean.push_back(more.heightMean);
    row.runHeightMax.push_back(more.heightMax);
    row.runOrientationGain.push_back(more.adaptivity.splitErrorReduction());
    row.pooledErrorChosen += more.adaptivity.splitErrorChosen;
    row.pooledErrorUnrotated += more.adaptivity.splitErrorUnrotated;
    row.pooledErrorRotated += more.adaptivity.splitErrorRotated;
    row.splitJumpSum += more.splitJumpSum;
    row.splitJumpChildren += more.splitJumpChildren;
    row.runSplitJump.push_back(more.runSplitJump.front());
    row.runDensityError.push_back(more.densityError);
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath = kDefaultScene;
  double simTime = kDefaultSimTime;
  std::string csvPath;
  std::string outDir;
  bool images = false;
  double imageTime = -1.0;
  double restTime = 0.0;  // the still run's length; 0: the run's
  int threads = 0;
  int runs = 1;  // runs per mode with perturbed starts
  std::vector<sim::AdaptivityMode> modes = {sim::AdaptivityMode::UniformLow, sim::AdaptivityMode::UniformHigh,
                                            sim::AdaptivityMode::Surface, sim::AdaptivityMode::FluidPlaying};
  std::vector<std::string> sets;
  engine::CommandLine line(
      "fp_bench_modes",
      "fp_bench_modes: the paper's comparison: one scene in the resolution modes, with wall time, particle "
      "counts, splash heights and (--out) per-frame series, SVG plots and images.");
  {
    CLI::App& app = line.app();
    app.add_option("--scene", scenePath, "scene JSON (default assets/scenes/propeller.json)")
        ->type_name("FILE");
    // --quick first: its callback runs before --sim-time's, which wins
    app.add_flag_callback(
        "--quick", [&] { simTime = kQuickSimTime; }, "a short run: 0.3 s per mode");
    line.addPositive(
        "--sim-time", [&](double v) { simTime = v; }, "simulated seconds per mode (default 2; --quick: 0.3)");
    app.add_option_function<std::string>(
           "--modes",
           [&](const std::string& list) {
             modes.clear();
             std::stringstream in(list);
             for (std::string name; std::getline(in, name, ',');)
               modes.push_back(*sim::parseMode(name));
           },
           "comma-separated modes (default uniform-low,uniform-high,surface,fluidplaying)")
        ->check(CLI::Validator(
            [](std::string& list) -> std::string {
              std::stringstream in(list);
              for (std::string name; std::getline(in, name, ',');) {
                if (!sim::parseMode(name))
                  return "unknown mode '" + name + "' (expected " + sim::modeNames() + ")";
              }
              return "";
            },
            ""))
        ->type_name("LIST");
    line.addInteger(
        "--threads", [&](long long n) { threads = int(n); }, 1, 1024, "worker threads (default: all cores)");
    line.addInteger(
        "--runs", [&](long long n) { runs = int(n); }, 1, 100,
        "runs per mode, the spinning colliders' starting phase 0.4 rad apart: splash height mean and spread "
        "(default 1)");
    line.addSet(sets);
    app.add_option("--csv", csvPath, "also write the table as CSV")->type_name("FILE");
    app.add_option("--out", outDir,
                   "write DIR/modes_<scene>.csv, the per-frame series, SVG plots and (--images) images")
        ->type_name("DIR");
    app.add_flag("--images", images,
                 "render one image per mode at --image-time (default: the end), side by side");
    line.addPositive(
        "--image-time", [&](double v) { imageTime = v; }, "simulated time of the images");
    line.addPositive(
        "--rest-time", [&](double v) { restTime = v; },
        "simulated seconds of the still run whose heights, frame by frame, are each mode's rest (default: "
        "--sim-time; past its end the median of its second half)");
    app.footer("Exit codes: 0 ok, 2 bad command line, 3 bad scene or output, 4 a mode went unstable.");
  }
  if (const std::optional<int> exit = line.parse(argc, argv))
    return *exit;

  sim::SceneDesc scene;
  try {
    scene = engine::loadScene(scenePath);
    engine::applySettings(scene.params, sets);
  } catch (const std::invalid_argument& e) {  // a --set that breaks a relation with the scene's values
    std::cerr << engine::usageErrorLine("fp_bench_modes", e.what()) << "\n";
    return engine::kExitUsage;
  } catch (const sim::InputError& e) {
    std::cerr << "fp_bench_modes: " << e.what() << "\n";
    return engine::kExitInput;
  }
  const engine::ThreadLimit limit(threads);
  threads = limit.count();

  if (images && outDir.empty()) {
    std::cerr << engine::usageErrorLine("fp_bench_modes", "--images needs --out DIR") << "\n";
    return engine::kExitUsage;
  }
  if (imageTime < 0 || imageTime > simTime)
    imageTime = simTime;
  std::string stem = std::filesystem::path(scenePath).stem().string();
  for (const std::string& kv : sets) {
    const std::size_t eq = kv.find('=');
    stem += "_" + kv.substr(0, eq) + kv.substr(eq + 1);
  }
  if (!outDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(outDir, ec);
    if (ec) {
      std::cerr << "fp_bench_modes: " << outDir << ": cannot create (" << ec.message() << ")\n";
      return engine::kExitInput;
    }
  }
  const std::string machine = machineDescription();
  std::printf(
      "fp_bench_modes: %s, r = %g m, mass ratio %g, %g s simulated per mode, %d threads\nmachine: %s\n",
      scene.name.c_str(), scene.params.particleRadius, scene.params.massRatio, simTime, threads,
      machine.c_str());
  std::vector<Row> rows;
  std::vector<std::string> imagePaths;
  for (sim::AdaptivityMode m : modes) {
    std::fprintf(stderr, "  running %s ...\n", sim::modeName(m));
    std::unique_ptr<engine::HeadlessRender> render;
    if (images) {
      engine::CliOptions options;
      options.render = true;
      options.width = 640;
      options.height = 360;
      options.outDir = (std::filesystem::path(outDir) / (stem + "_" + sim::modeName(m))).string();
      try {
        render = std::make_unique<engine::HeadlessRender>(options);
      } catch (const std::exception& e) {
        std::cerr << "fp_bench_modes: no images: " << e.what() << "\n";
        return engine::kExitInput;
      }
      imagePaths.push_back((std::filesystem::path(options.outDir) / "frame_00000.png").string());
    }
    rows.push_back(runModeRepeated(scene, m, simTime, restTime, imageTime, render.get(), runs));
  }
  const Row* high = nullptr;
  for (const Row& r : rows)
    if (r.mode == "uniform-high")
      high = &r;
  // Without a uniform-high run the shares still have their reference: its particle count never changes, so
  // building it is enough (speed-ups stay unknown).
  Row highCount;
  if (!high) {
    sim::SceneDesc fine = scene;
    fine.mode = sim::AdaptivityMode::UniformHigh;
    fine.params.initialRelaxation = 0;  // the count is the lattice's: no settling at full resolution
    const sim::Simulation reference(fine);
    highCount.mode = "uniform-high (not run)";
    highCount.particlesMean = double(reference.particles().size());
    highCount.particlesMax = reference.particles().size();
    high = &highCount;
  }

  std::printf("\n%-13s %9s %7s %8s %10s %7s %9s %7s %9s %9s %9s %9s %8s %9s %9s %8s\n", "mode", "wall [s]",
              "speedup", "steps", "particles", "share", "max", "share", "h99.9 mm", "max mm", "+spl. mm",
              "max mm", "splash", "dens.err%", "orient.-%", "adapt.%");
  std::ostringstream csv;
  csv << "mode,status,wall_s,speedup_vs_uniform_high,steps,particles_mean,particles_mean_share,particles_max,"
         "particles_max_share,splash_height_mean_m,splash_height_max_m,splash_height_with_splash_mean_m,"
         "splash_height_with_splash_max_m,resting_level_m,splash_particles_mean,density_error_mean,split_"
         "error_reduction,"
         "adaptivity_share,splits,merges,redistributions,sim_time_s,particle_radius_m,threads,machine,levels_"
         "share,"
         "density_error_frames_per_particle,density_error_frames_volume_weighted,runs,splash_height_mean_"
         "runs_m,"
         "splash_height_mean_spread_m,splash_height_max_runs_m,splash_height_max_spread_m,"
         "time_step_headroom_capped,time_step_headroom_uncapped\n";
  bool allOk = true;
  for (const Row& r : rows) {
    const double speedup = high && high->wall > 0 && r.wall > 0 ? high->wall / r.wall : 0.0;
    const double meanShare = high && high->particlesMean > 0 ? r.particlesMean / high->particlesMean : 0.0;
    const double maxShare =
        high && high->particlesMax > 0 ? double(r.particlesMax) / double(high->particlesMax) : 0.0;
    std::printf(
        "%-13s %9.2f %7.2f %8llu %10.0f %6.1f%% %9zu %6.1f%% %9.1f %9.1f %9.1f %9.1f %8.0f %9.3f %9.1f "
        "%8.1f\n",
        r.mode.c_str(), r.wall, speedup, (unsigned long long)r.steps, r.particlesMean, 100 * meanShare,
        r.particlesMax, 100 * maxShare, 1000 * r.heightMean, 1000 * r.heightMax, 1000 * r.heightSplashMean,
        1000 * r.heightSplashMax, r.splashMean, 100 * r.densityError,
        100 * r.adaptivity.splitErrorReduction(), 100 * r.adaptivityShare);
    if (r.status != "ok") {
      std::printf("  %s: %s\n", r.mode.c_str(), r.status.c_str());
      allOk = false;
    }
    csv << r.mode << "," << (r.status == "ok" ? "ok" : "unstable") << "," << r.wall << "," << speedup << ","
        << r.steps << "," << r.particlesMean << "," << meanShare << "," << r.particlesMax << "," << maxShare
        << "," << r.heightMean << "," << r.heightMax << "," << r.heightSplashMean << "," << r.heightSplashMax
        << "," << r.restLevel << "," << r.splashMean << "," << r.densityError << ","
        << r.adaptivity.splitErrorReduction() << "," << r.adaptivityShare << "," << r.adaptivity.splits << ","
        << r.adaptivity.merges << "," << r.adaptivity.redistributions << "," << simTime << ","
        << scene.params.particleRadius << "," << threads << ",\"" << machine << "\"," << r.levelsShare << ","
        << r.densityErrorParticles << "," << r.densityErrorVolume << "," << r.runHeightMean.size() << ","
        << meanAndSpread(r.runHeightMean).first << "," << meanAndSpread(r.runHeightMean).second << ","
        << meanAndSpread(r.runHeightMax).first << "," << meanAndSpread(r.runHeightMax).second << ","
        << r.headroomCapped << "," << r.headroomUncapped << "\n";
  }
  std::printf(
      "\nparticles by what they are refined for, mean per frame as a share of uniform-high's count:\n");
  std::printf("%-13s %9s %9s %9s %9s %9s %8s %10s %10s %7s %7s %7s %7s\n", "mode", "surface", "band",
              "dynamic", "base", "too light", "levels%", "err% part", "err% vol", "lvl1%", "held%", "ideal%",
              "nocap%");
  for (const Row& r : rows) {
    const double u = high && high->particlesMean > 0 ? 100.0 / high->particlesMean : 0.0;
    std::printf("%-13s %8.2f%% %8.2f%% %8.2f%% %8.2f%% %8.2f%% %8.1f %10.3f %10.3f %7.1f %7.1f %7.1f %7.1f\n",
                r.mode.c_str(), u * r.surfaceFine, u * r.band, u * r.dynamic, u * r.base, u * r.tooLight,
                100 * r.levelsShare, 100 * r.densityErrorParticles, 100 * r.densityErrorVolume,
                100 * r.level1Share, 100 * r.heldShare, 100 * r.headroomCapped, 100 * r.headroomUncapped);
  }
  std::printf("\nwall time by phase, ms per step (first run of each mode):\n");
  std::printf("%-13s %9s %9s %9s %9s %9s %9s %9s %9s %9s %9s\n", "mode", "neighb.", "density", "diverg.",
              "viscos.", "pressure", "bound.", "integr.", "levels", "adapt.", "total");
  for (const Row& r : rows) {
    const double k = r.steps > 0 ? 1000.0 / double(r.steps) : 0.0;
    const sim::PhaseTimes& t = r.times;
    std::printf("%-13s %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f\n", r.mode.c_str(),
                k * t.neighbors, k * t.density, k * t.divergence, k * t.viscosity, k * t.pressure,
                k * t.boundaries, k * t.integrate, k * t.levels, k * t.adaptation, k * t.total());
  }
  if (runs > 1) {
    // an order between two modes is claimed only where the means differ by more than the spreads
    std::printf(
        "\nsplash height over %d runs (starting phases %g rad apart): mean +- standard deviation [mm]\n",
        runs, kPhaseStep);
    std::printf("%-13s %17s %17s\n", "mode", "h99.9 mean", "h99.9 max");
    for (const Row& r : rows) {
      const auto [mean, spread] = meanAndSpread(r.runHeightMean);
      const auto [max, maxSpread] = meanAndSpread(r.runHeightMax);
      std::printf("%-13s %8.1f +- %5.1f %8.1f +- %5.1f\n", r.mode.c_str(), 1000 * mean, 1000 * spread,
                  1000 * max, 1000 * maxSpread);
    }
    for (const Row& a : rows) {
      for (const Row& b : rows) {
        if (&a == &b || a.mode != "fluidplaying")
          continue;
        const auto [ma, sa] = meanAndSpread(a.runHeightMean);
        const auto [mb, sb] = meanAndSpread(b.runHeightMean);
        const double d = ma - mb;
        const double noise = sa + sb;
        std::printf("%s - %s: %+.1f mm (spreads %.1f mm together): %s\n", a.mode.c_str(), b.mode.c_str(),
                    1000 * d, 1000 * noise,
                    std::abs(d) > noise ? (d > 0 ? "higher" : "lower") : "within the noise");
      }
    }
    // the orientation gain moves with which particles split: every run's, and pooled over the runs' splits
    std::printf(
        "\norientation gain over up to %d runs (split error of the chosen rotation against the unrotated "
        "template's, %%; a mode that went unstable stops its runs)\n",
        runs);
    std::printf("%-13s %8s %9s %17s  %s\n", "mode", "pooled", "rotation", "mean +- std", "runs");
    for (const Row& r : rows) {
      if (r.pooledErrorUnrotated <= 0)
        continue;
      const auto [mean, spread] = meanAndSpread(r.runOrientationGain);
      std::printf("%-13s %8.1f %9.1f %8.1f +- %5.1f ", r.mode.c_str(),
                  100 * (1 - r.pooledErrorChosen / r.pooledErrorUnrotated),
                  100 * (1 - r.pooledErrorRotated / r.pooledErrorUnrotated), 100 * mean, 100 * spread);
      for (double g : r.runOrientationGain)
        std::printf(" %.1f", 100 * g);
      std::printf("\n");
    }
    // what the solver then sees of the splits
    std::printf(
        "\nsplit children in the next density pass: |rho_child - rho_parent| / rho0, %% (mean over the "
        "children; pooled, and every run's)\n");
    std::printf("%-13s %9s %8s %17s  %s\n", "mode", "children", "pooled", "mean +- std", "runs");
    for (const Row& r : rows) {
      if (r.splitJumpChildren == 0)
        continue;
      const auto [mean, spread] = meanAndSpread(r.runSplitJump);
      std::printf("%-13s %9llu %8.3f %8.3f +- %5.3f ", r.mode.c_str(),
                  (unsigned long long)r.splitJumpChildren, 100 * r.splitJumpSum / double(r.splitJumpChildren),
                  100 * mean, 100 * spread);
      for (double g : r.runSplitJump)
        std::printf(" %.3f", 100 * g);
      std::printf("\n");
    }
    std::printf(
        "\nmean density error of the steps over the runs, %% (the table's dens.err%% is the first run's)\n");
    for (const Row& r : rows) {
      const auto [mean, spread] = meanAndSpread(r.runDensityError);
      std::printf("%-13s %8.4f +- %6.4f ", r.mode.c_str(), 100 * mean, 100 * spread);
      for (double g : r.runDensityError)
        std::printf(" %.4f", 100 * g);
      std::printf("\n");
    }
  }
  std::printf("\nCSV\n%s", csv.str().c_str());
  if (!outDir.empty()) {
    const std::filesystem::path dir(outDir);
    if (csvPath.empty())
      csvPath = (dir / ("modes_" + stem + ".csv")).string();
    std::ofstream series(dir / ("series_" + stem + ".csv"));
    series << "mode,t_s,particles,splash_height_m,splash_height_with_splash_m,splash_particles\n";
    for (const Row& r : rows)
      for (const Sample& x : r.series)
        series << r.mode << "," << x.t << "," << x.particles << "," << x.height << "," << x.heightSplash
               << "," << x.splash << "\n";
    writePlot((dir / ("particles_" + stem + ".svg")).string(),
              "Fluid particles over time (" + scene.name + ")", "particles", rows,
              [](const Sample& x) { return double(x.particles); });
    writePlot((dir / ("splash_height_" + stem + ".svg")).string(),
              "99.9th-percentile height above the resting level (" + scene.name + ")", "height [mm]", rows,
              [](const Sample& x) { return 1000.0 * x.height; });
    if (images) {
      // the modes' images side by side, in the order of the table
      render::Image strip;
      std::vector<render::Image> parts;
      // (a mode whose still run went unstable rendered nothing: its place is left out)
      for (const std::string& path : imagePaths)
        if (std::filesystem::exists(path))
          parts.push_back(render::readPng(path));
      strip.height = parts.empty() ? 0 : parts[0].height;
      for (const render::Image& im : parts)
        strip.width += im.width;
      strip.rgba.assign(std::size_t(strip.width) * std::size_t(strip.height) * 4, 0);
      int x0 = 0;
      for (const render::Image& im : parts) {
        for (int y = 0; y < std::min(im.height, strip.height); ++y)
          std::copy(im.rgba.begin() + std::ptrdiff_t(std::size_t(y) * std::size_t(im.width) * 4),
                    im.rgba.begin() + std::ptrdiff_t(std::size_t(y + 1) * std::size_t(im.width) * 4),
                    strip.rgba.begin() +
                        std::ptrdiff_t((std::size_t(y) * std::size_t(strip.width) + std::size_t(x0)) * 4));
        x0 += im.width;
      }
      const std::string stripPath = (dir / ("modes_" + stem + ".png")).string();
      render::writePng(stripPath, strip);
      std::printf("images: %s (left to right: the table's modes at t = %g s)\n", stripPath.c_str(),
                  imageTime);
    }
  }
  if (!csvPath.empty()) {
    std::ofstream file(csvPath);
    file << csv.str();
    if (!file) {
      std::cerr << "fp_bench_modes: cannot write " << csvPath << "\n";
      return engine::kExitInput;
    }
  }
  return allOk ? engine::kExitOk : engine::kExitUnstable;
}
