// Soak of the hand tank in fluidplaying mode under the aggressive recorded hand (assets/hands/aggressive.csv,
// repeated): at every frame end no NaN, no particle out of the tank, the total mass to 1e-6, the particle
// count between the uniform-low and uniform-high counts (the README's share floor, two fine surface layers,
// reported as a figure), no fluid particle inside a hand collider, the density error bounded; memory flat
// after the start. Both are label soak; Soak.ThirtySeconds runs by default (about 180 s on the r = 5 mm
// tank), Soak.TenMinutes only when asked: ctest --test-dir build -C soak -L soak (docs/robustness.md,
// "Soak"). Soak.RecordedHandsStayFarBelowTheHandTanksLid (label physics) checks the cause of the blow-up the
// soak found. Soak.LiveParameterSweep (label physics) drags every live parameter of the panel from its
// minimum to its maximum and back while the hand plays.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <malloc.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "engine/app_session.h"
#include "engine/cli.h"
#include "engine/scene_loader.h"
#include "input/hand_model.h"
#include "sim/signed_distance.h"

namespace {

using namespace fp;

/// resident set size of the process [bytes]
/// The process's resident set [bytes], after the allocator handed back the free pages it holds. Without the
/// trim the figure depends on which thread freed what: glibc keeps a free list per thread arena, and the same
/// deterministic run ended at 17.3 MB in one process and 19.7 MB in another (the r = 5 mm tank; its arrays
/// are larger than the coarse tank's, so that slack is too). The trim frees nothing live: a leak still shows.
double residentBytes() {
  malloc_trim(0);
  std::ifstream statm("/proc/self/statm");
  double pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * double(sysconf(_SC_PAGESIZE));
}

/// frames before the share floor holds: the hand tank starts coarse below the surface layer
constexpr int kSettleFrames = 60;

struct SoakFigures {
  int frames = 0;
  double simTime = 0;
  double wallSeconds = 0;
  std::size_t countMin = SIZE_MAX, countMax = 0;
  double floorCount = 0, uniformHighCount = 0, twoLayers = 0;
  double massErrorMax = 0;       // relative
  double densityErrorMax = 0;    // mean compression of a step, max over frames
  double densityErrorSum = 0;    // for the mean over frames
  double penetrationMax = 0;     // deepest fluid particle inside a hand collider [m]
  double particleRadius = 0;     // the scene's (finest) particle radius [m]
  std::size_t insideFrames = 0;  // frames ending with a fluid particle inside a hand collider
  int belowTwoLayers = 0;        // frames (after the first second) with fewer than two fine surface layers
  double speedMax = 0;           // fastest fluid particle at a frame end [m/s]
  double rssAfterStart = 0, rssEnd = 0, simBytesAfterStart = 0, simBytesEnd = 0;
  std::size_t countMaxAtStart = 0;  // the most particles up to the memory sample after the start
  std::uint64_t splits = 0, merges = 0, steps = 0;
  std::string failure;  // the first broken invariant, empty when all held
};

std::ostream& operator<<(std::ostream& o, const SoakFigures& f) {
  o << "frames " << f.frames << ", simulated " << f.simTime << " s in " << f.wallSeconds << " s wall, "
    << f.steps << " steps\n"
    << "particles in [" << f.countMin << ", " << f.countMax << "], bounds [" << f.floorCount << ", "
    << f.uniformHighCount << "] (two fine layers: " << f.twoLayers << ", fewer in " << f.belowTwoLayers
    << " frames); splits " << f.splits << ", merges " << f.merges << "\n"
    << "mass error max " << f.massErrorMax << " (relative); density error max " << 100 * f.densityErrorMax
    << " %, mean " << 100 * f.densityErrorSum / std::max(1, f.frames) << " %; fastest particle " << f.speedMax
    << " m/s\n"
    << "deepest fluid particle inside a hand collider " << 1e3 * f.penetrationMax << " mm (" << f.insideFrames
    << " frames)\n"
    << "memory after the start: rss " << f.rssAfterStart / 1e6 << " MB, simulation "
    << f.simBytesAfterStart / 1e6 << " MB; at the end: rss " << f.rssEnd / 1e6 << " MB, simulation "
    << f.simBytesEnd / 1e6 << " MB; most particles " << f.countMaxAtStart << " by then, " << f.countMax
    << " by the end\n";
  return o;
}

/// Runs the hand tank in fluidplaying mode for `seconds` of simulated time with the aggressive hand
/// repeated. Memory is sampled at `settle` seconds and at the end.
SoakFigures soak(double seconds, double settle) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  engine::SessionConfig config;
  config.scenePath = engine::assetPath("assets/scenes/hand_tank.json");
  config.mode = "fluidplaying";
  config.fixedStep = true;
  engine::AppSession session(config);
  const input::PoseTrack track = input::PoseTrack::load(engine::assetPath("assets/hands/aggressive.csv"));
  session.startReplay(track);
  double cycleStart = 0.0;

  const sim::Simulation& sim0 = session.simulation();
  const double mass0 = sim0.totalMass();
  const double r = sim0.params().particleRadius;
  SoakFigures f;
  f.particleRadius = r;
  f.uniformHighCount = session.stats().uniformHighCount;
  // The share floor of the README (two fine lattice layers of spacing 2r over the tank's water surface) is a
  // figure here, not a check: with cfl_limited_refinement (on since issue 13) the water the hand sweeps stays
  // coarse, and the count falls to about 0.6 of it. The check is the hard floor: never fewer particles than
  // all of the water at the coarsest mass (the uniform-low count).
  const sim::ColliderDesc& tank = session.scene().colliders.front();
  f.twoLayers = 2.0 * 4.0 * tank.halfExtents.x() * tank.halfExtents.z() / (4.0 * r * r);
  f.floorCount = std::floor(f.uniformHighCount / sim0.params().massRatio);
  // the tank's inner walls: a particle beyond them (by more than a radius) escaped
  const sim::Vec3d lo = tank.position - tank.halfExtents - sim::Vec3d::Constant(r);
  const sim::Vec3d hi = tank.position + tank.halfExtents + sim::Vec3d::Constant(r);
  const std::size_t firstHand = session.hand().firstCollider();
  const double frameRate = session.scene().frameRate;
  const int frames = int(std::lround(seconds * frameRate));
  const auto start = std::chrono::steady_clock::now();
  // the run's totals so far (the trace and the end)
  const auto recordTotals = [&](const sim::Simulation& sim) {
    f.simTime = sim.time();
    f.steps = sim.runStats().steps;
    f.splits = sim.runStats().adaptivity.splits;
    f.merges = sim.runStats().adaptivity.merges;
    f.rssEnd = residentBytes();
    f.simBytesEnd = double(sim.memoryBytes());
    f.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto fail = [&f](const std::string& what) {
    if (f.failure.empty())
      f.failure = what;
  };
  for (int frame = 0; frame < frames && f.failure.empty(); ++frame) {
    session.finishSteps();
    const sim::Simulation& sim = session.simulation();
    if (!session.error().empty()) {
      fail("frame " + std::to_string(frame) + ": " + session.error());
      break;
    }
    const sim::ParticleSet& p = sim.particles();
    const std::size_t n = p.size();
    f.countMin = std::min(f.countMin, n);
    f.countMax = std::max(f.countMax, n);
    if (std::getenv("FP_SOAK_TRACE") && frame % 10 == 0)
      std::cout << "frame " << frame << " t " << sim.time() << " n " << n << " vmax " << f.speedMax << "\n";
    if (frame >= kSettleFrames && double(n) < f.twoLayers)
      ++f.belowTwoLayers;
    if (double(n) < f.floorCount || double(n) > f.uniformHighCount + 0.5)
      fail("frame " + std::to_string(frame) + ": " + std::to_string(n) + " particles");
    const double massError = std::abs(sim.totalMass() - mass0) / mass0;
    f.massErrorMax = std::max(f.massErrorMax, massError);
    if (massError > 1e-6)
      fail("frame " + std::to_string(frame) + ": mass error " + std::to_string(massError));
    const double densityError = sim.lastStep().densityError;
    f.densityErrorMax = std::max(f.densityErrorMax, densityError);
    f.densityErrorSum += densityError;
    bool inside = false;
    for (std::size_t i = 0; i < n; ++i) {
      const sim::Vec3d x = p.x[i].cast<double>();
      if (!x.allFinite() || !p.v[i].allFinite()) {
        fail("frame " + std::to_string(frame) + ": a non-finite particle");
        break;
      }
      f.speedMax = std::max(f.speedMax, double(p.v[i].norm()));
      if ((x.array() < lo.array()).any() || x.x() > hi.x() || x.z() > hi.z())
        fail("frame " + std::to_string(frame) + ": particle " + std::to_string(p.id[i]) +
             " escaped the tank");
      for (std::size_t c = firstHand; c < firstHand + input::HandModel::kParts; ++c) {
        const sim::ColliderState& s = sim.colliders()[c];
        sim::ColliderDesc posed = s.desc;
        posed.position = s.position;
        posed.orientation = s.orientation;
        const double d = sim::signedDistance(posed, x);
        if (d < 0.0) {
          inside = true;
          f.penetrationMax = std::max(f.penetrationMax, -d);
        }
      }
    }
    f.insideFrames += inside ? 1 : 0;
    const double t = sim.time();
    if (frame == int(settle * frameRate)) {
      f.rssAfterStart = residentBytes();
      f.simBytesAfterStart = double(sim.memoryBytes());
      f.countMaxAtStart = f.countMax;
    }
    // the recording again from the start once it has ended (the hand is back at its first pose then)
    if (t - cycleStart > track.duration()) {
      session.startReplay(track);
      cycleStart = t;
    }
    // a long soak may not end within a session: with FP_SOAK_TRACE the figures so far every 10 simulated s
    if (std::getenv("FP_SOAK_TRACE") && (frame + 1) % 600 == 0) {
      f.frames = frame + 1;
      recordTotals(sim);
      std::cout << "--- so far: " << f << std::flush;
    }
    session.setHandTarget(session.handPose());
    session.applyRequests();
    session.startSteps(1.0 / frameRate, std::numeric_limits<double>::infinity());
    f.frames = frame + 1;
  }
  session.finishSteps();
  const sim::Simulation& sim = session.simulation();
  recordTotals(sim);
  return f;
}

void expectSound(const SoakFigures& f) {
  std::cout << f;
  EXPECT_EQ(f.failure, "");
  // A particle may end a frame a little inside a finger that moved into it during the frame's last step: the
  // boundary particles push it out over the next steps. Deeper than a particle radius would be a hole.
  EXPECT_GT(f.particleRadius, 0.0);
  EXPECT_LT(f.penetrationMax, f.particleRadius);
  EXPECT_LT(f.densityErrorMax, 0.05);
  // flat: memory grows with the most particles held at once (the arrays keep their capacity for the next
  // surge), never with the time run. The simulation's arrays at the end hold no more than after the start,
  // scaled by how much the peak count grew since (+10 %); the process no more than 10 % over its size after
  // the start plus that growth of the arrays. (The 10-minute soak's peak grew 1.41x, from 2,961 to 4,172
  // particles, after the first minute, and its arrays 1.16x: a bound without the peak failed there; a leak of
  // 100 bytes a frame would fail the second bound there.) Outside the simulation's arrays the splash and the
  // app's buffers grow with the peak count too, about as much: CI's run of 89762cc, its machine shared with a
  // build, ended at 14.00 MB where the arrays' growth alone allowed 13.86 (peak 9,367 -> 11,902 in the last
  // seconds, arrays 4.00 -> 5.15 MB); the bound counts that growth 1.5 times (14.43 MB there; a leak of
  // 1 KB a frame over its 1,200 frames would still fail it).
  ASSERT_GT(f.countMaxAtStart, 0u);
  const double peakGrowth = double(f.countMax) / double(f.countMaxAtStart);
  EXPECT_LT(f.simBytesEnd, 1.1 * peakGrowth * f.simBytesAfterStart);
  EXPECT_LT(f.rssEnd, 1.1 * f.rssAfterStart + 1.5 * (peakGrowth - 1.0) * f.simBytesAfterStart);
}

TEST(Soak, ThirtySeconds) {
  // about 27,000 steps at r = 5 mm; memory sampled after 10 s
  const SoakFigures f = soak(30.0, 10.0);
  EXPECT_EQ(f.frames, 1800);
  expectSound(f);
}

TEST(Soak, TenMinutes) {
  const SoakFigures f = soak(600.0, 60.0);
  EXPECT_EQ(f.frames, 36000);
  expectSound(f);
}

/// Every recorded hand's highest point stays below `highest` [m] (the tank `file`'s lid less a margin).
void expectHandsBelow(double highest, const char* file) {
  const input::HandModel model;
  for (const char* name : {"aggressive", "point_stir", "push", "push_x", "scoop", "splash"}) {
    const input::PoseTrack track =
        input::PoseTrack::load(engine::assetPath(std::string("assets/hands/") + name + ".csv"));
    double top = -1e9, topTime = 0;
    for (double t = 0; t <= track.duration(); t += 1.0 / 240.0) {
      const input::PoseSample s = track.sample(t);
      input::HandPose pose;
      pose.position = s.position;
      pose.orientation = s.orientation;
      pose.grip = s.grip;
      pose.point = s.point;
      for (const sim::ColliderDesc& c : model.colliders(pose)) {
        double high = -1e9;
        if (c.shape == sim::ShapeType::Box) {
          for (int k = 0; k < 8; ++k) {
            const sim::Vec3d h = c.halfExtents;
            const sim::Vec3d corner(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z());
            high = std::max(high, (c.position + c.orientation * corner).y());
          }
        } else {
          const double axis = std::abs((c.orientation * sim::Vec3d(0.0, c.halfLength, 0.0)).y());
          high = c.position.y() + axis + c.radius;
        }
        if (high > top) {
          top = high;
          topTime = t;
        }
      }
    }
    std::cout << file << ", " << name << ": highest point of the hand " << top << " m at t = " << topTime
              << " s, bound " << highest << " m\n";
    EXPECT_LT(top, highest) << file << ", " << name;
  }
}

TEST(Soak, RecordedHandsStayFarBelowTheHandTanksLid) {
  // The cause of the soak's blow-up at t = 4.04 s (docs/robustness.md, "Soak"): the tank's lid was its rim,
  // in the hand's path, and a fist rising out of the water pressed the water on it against the lid. The lid
  // is now raised (headroom): no recorded hand comes within two support radii of it, so no particle carried
  // on a hand is pinched against it. Both tanks: the default (r = 5 mm, a margin of 4 cm) and the coarse one
  // (7.9 mm, 6.3 cm).
  for (const char* file : {"hand_tank.json", "hand_tank_coarse.json"}) {
    const sim::SceneDesc scene = engine::loadScene(engine::assetPath(std::string("assets/scenes/") + file));
    const sim::ColliderDesc& tank = scene.colliders.front();
    ASSERT_TRUE(tank.container) << file;
    const double lid = tank.position.y() + tank.halfExtents.y() + tank.headroom;
    const double margin = 2.0 * 4.0 * scene.params.particleRadius;
    expectHandsBelow(lid - margin, file);
  }
}

TEST(Soak, LiveParameterSweep) {
  // Every live parameter of the panel from its minimum to its maximum and back over 12 frames while the hand
  // sweeps; the others at their scene values. Frames are paced like the window's (a wall-time budget per
  // frame), so extreme step sizes slow the simulated time instead of the test. An absurd value may make the
  // run unstable: that must be reported (never a NaN in a state shown as good) and a reset must recover.
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  engine::SessionConfig config;
  config.scenePath = engine::assetPath("assets/scenes/hand_tank.json");
  config.mode = "fluidplaying";
  engine::AppSession session(config);
  session.startReplay(input::PoseTrack::load(engine::assetPath("assets/hands/aggressive.csv")));
  const sim::SimParams base = session.simulation().params();
  int swept = 0, instabilities = 0, relationHeld = 0;
  constexpr int kFrames = 12;
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries()) {
    if (!info.live)
      continue;
    ++swept;
    for (int k = 0; k <= kFrames; ++k) {
      session.finishSteps();
      const sim::Simulation& sim = session.simulation();
      if (!session.error().empty()) {
        ++instabilities;
        session.editParams() = base;
        session.requests().reset = true;
      } else {
        for (std::size_t i = 0; i < sim.particles().size(); ++i) {
          ASSERT_TRUE(sim.particles().x[i].allFinite() && sim.particles().v[i].allFinite())
              << info.key << " frame " << k << ": a NaN in a state shown as good";
        }
        const double s = 1.0 - std::abs(2.0 * k / kFrames - 1.0);  // 0 -> 1 -> 0
        const double value = info.min + s * (info.max - info.min);
        sim::SimParams& edit = session.editParams();
        if (info.kind == sim::ParamKind::Vector3)
          sim::ParamTable::setVec3(edit, info, {value, value, value});
        else
          sim::ParamTable::setScalar(edit, info,
                                     info.kind == sim::ParamKind::Number ? value : std::round(value));
      }
      session.setHandTarget(session.handPose());
      session.applyRequests();
      // the running parameters keep every relation, whatever the edit
      ASSERT_EQ(sim::ParamTable::validate(session.simulation().params()), "") << info.key << " frame " << k;
      ++relationHeld;
      session.startSteps(1.0 / 60.0, 0.02);
    }
    session.finishSteps();
    session.editParams() = base;
    if (!session.error().empty()) {
      ++instabilities;
      session.requests().reset = true;
    }
    session.applyRequests();
  }
  std::cout << swept << " live parameters swept, " << relationHeld << " frames with the relations held, "
            << instabilities << " instabilities reported and reset\n";
  EXPECT_GT(swept, 20);
}

}  // namespace
