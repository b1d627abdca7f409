// Image tests of how the water looks (issue 14, label gl), measured from the renderer's own buffers at
// 640x360 through OSMesa: the resting hand tank at uniform-high and fluidplaying (states exported by the
// simulation at frame 90, tests/gl/data) and a moving propeller frame of mixed resolution. The figures at
// 1280x720 and their history are in docs/rendering.md (fp_water_look prints them).
#include <gtest/gtest.h>

#include <memory>

#include "render/offscreen_context.h"
#include "render/shader_program.h"
#include "water_look_scenes.h"

using namespace fp;

namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 360;

// Tolerances. A resting surface: rms normal angle from the vertical at most 3 degrees (before this issue's
// filter: 8.2 uniform-high, 22.9 fluidplaying; session 7, on today's fluidplaying state, 4.27 before the
// pinholes were filled and the filter widened to 5 fine radii, 2.23 after), the rendered height within half a
// fine radius of the simulated one, the surface drawn wherever it should be.
constexpr double kMaxRestingNormalRms = 3.0;  // [deg]
constexpr double kMaxHeightError = 0.5;       // [fine radii]
constexpr double kMinRestingCoverage = 0.98;
// Adaptive against uniform at rest: the mean channel difference over the water's pixels (the 2
// levels; session 7: 2.93 before, 1.76 after; 2.12 with the filter of 4 fine radii) and over the whole image,
// and the share of the water's pixels differing by more than 24 levels (0.22 % before, 0.26 % after).
constexpr double kMaxWaterMeanDifference = 2.0;  // [levels]
constexpr double kMaxImageMeanDifference = 2.0;  // [levels]
constexpr double kMaxWaterFractionOver = 0.01;
// The renderer's part of it: the same uniform-high water drawn from particles at fluidplaying's resolutions
// (coarsenedRestingTank) against the uniform-high particles, mean over the water's pixels (without the
// thickness smoothing: 2.00 levels; with it 0.98; the refraction sized by each pixel's particle: 1.07; by the
// fine radius: 0.78).
constexpr double kMaxSameWaterMeanDifference = 1.0;  // [levels]
// Creases (seams, rings, blobs): the share of interior water pixels whose normal turns by more than 20
// degrees over 2 pixels, in a moving frame of fine and coarse particles (propeller: 0.17 before the pair
// filter, 0.0032 now; the hand tank pushed by the recorded hand: 0.0125, 0.37 unfiltered).
constexpr double kMaxMovingCreases = 0.03;
// Speckles: single water pixels brighter or darker than their four agreeing neighbours by more than 6 levels.
// The near glass tied in depth with the water on it (the wetted glass) and its tint flickered pixel by pixel:
// propeller 105 px of 38,308 (0.27 %), hand tank 24 of 35,124 (0.07 %); with the glass drawn in front
// (polygon offset) 4 and 9.
constexpr double kMaxMovingSpeckles = 0.0005;

class WaterLookTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_context = std::make_unique<render::OffscreenContext>(kWidth, kHeight);
    s_renderer = std::make_unique<render::FluidRenderer>(render::defaultShaderDir());
  }
  static void TearDownTestSuite() {
    s_renderer.reset();
    s_context.reset();
  }
  void SetUp() override { s_renderer->settings() = render::RenderSettings(); }
  static test::LookShot shoot(const test::LookScene& scene) {
    return test::shoot(*s_renderer, scene, kWidth, kHeight);
  }

  static std::unique_ptr<render::OffscreenContext> s_context;
  static std::unique_ptr<render::FluidRenderer> s_renderer;
};

std::unique_ptr<render::OffscreenContext> WaterLookTest::s_context;
std::unique_ptr<render::FluidRenderer> WaterLookTest::s_renderer;

}  // namespace

TEST_F(WaterLookTest, ARestingTankIsFlatAtTheSimulatedHeightInEveryMode) {
  for (bool adaptive : {false, true}) {
    const test::LookScene scene = test::restingHandTank(adaptive);
    const test::LookShot shot = shoot(scene);
    const test::RestingSurface r = test::measureRestingSurface(shot.surface, scene.surfaceY, scene.inner);
    SCOPED_TRACE(adaptive ? "fluidplaying" : "uniform-high");
    ASSERT_GT(r.pixels, 5000u);
    EXPECT_GE(r.coverage, kMinRestingCoverage);
    EXPECT_LE(r.rmsNormalDegrees, kMaxRestingNormalRms);
    EXPECT_LE(std::abs(r.meanHeightError) / scene.fineRadius, kMaxHeightError) << r.meanHeightError << " m";
  }
}

TEST_F(WaterLookTest, AdaptiveWaterAtRestLooksLikeUniformWater) {
  const test::LookShot uniform = shoot(test::restingHandTank(false));
  const test::LookShot adaptive = shoot(test::restingHandTank(true));
  const test::WaterDifference d =
      test::compareWater(uniform.image, adaptive.image, uniform.depth, adaptive.depth, 24);
  EXPECT_GT(d.waterPixels, 20000u);
  EXPECT_LE(d.meanLevels, kMaxWaterMeanDifference);
  EXPECT_LE(d.imageMeanLevels, kMaxImageMeanDifference);
  EXPECT_LE(d.fractionOver, kMaxWaterFractionOver);
}

TEST_F(WaterLookTest, TheAdaptiveToleranceFailsTheNarrowerFilter) {
  // the filter of 4 fine radii (sessions 3-6) leaves the adaptive surface's bumps in the refraction
  s_renderer->settings().filterRadius = 4.0f;
  const test::LookShot uniform = shoot(test::restingHandTank(false));
  const test::LookShot adaptive = shoot(test::restingHandTank(true));
  EXPECT_GT(test::compareWater(uniform.image, adaptive.image, uniform.depth, adaptive.depth, 24).meanLevels,
            kMaxWaterMeanDifference);
}

TEST_F(WaterLookTest, TheRestingToleranceFailsTheSurfaceWithItsPinholes) {
  // gaps between the spheres of the adaptive surface, left as drawn, turn the normals around them
  s_renderer->settings().fillHoles = false;
  const test::LookScene scene = test::restingHandTank(true);
  EXPECT_GT(test::measureRestingSurface(shoot(scene).surface, scene.surfaceY, scene.inner).rmsNormalDegrees,
            kMaxRestingNormalRms);
}

TEST_F(WaterLookTest, TheSameWaterFromCoarseParticlesLooksLikeItFromFineOnes) {
  const test::LookShot uniform = shoot(test::restingHandTank(false));
  const test::LookShot coarse = shoot(test::coarsenedRestingTank());
  const test::WaterDifference d =
      test::compareWater(uniform.image, coarse.image, uniform.depth, coarse.depth, 24);
  EXPECT_GT(d.waterPixels, 20000u);
  EXPECT_LE(d.meanLevels, kMaxSameWaterMeanDifference);
  EXPECT_LE(d.fractionOver, kMaxWaterFractionOver);
}

TEST_F(WaterLookTest, TheSameWaterToleranceFailsTheUnblurredThickness) {
  // the thickness summed from the spheres as drawn: the coarse particles' spacing shows as blotches
  s_renderer->settings().thicknessBlur = 0.0f;
  const test::LookShot uniform = shoot(test::restingHandTank(false));
  const test::LookShot coarse = shoot(test::coarsenedRestingTank());
  EXPECT_GT(test::compareWater(uniform.image, coarse.image, uniform.depth, coarse.depth, 24).meanLevels,
            kMaxSameWaterMeanDifference);
}

TEST_F(WaterLookTest, AMovingFrameOfMixedResolutionHasNoCreases) {
  // the propeller (0.0032) and the hand tank with the recorded hand pushing (0.0125)
  for (bool hand : {false, true}) {
    const test::LookScene scene = hand ? test::movingHandTank() : test::movingPropeller();
    const test::LookShot shot = shoot(scene);
    const test::Creases c = test::measureCreases(shot.surface, 2, 20.0f, scene.fineRadius);
    SCOPED_TRACE(hand ? "hand tank" : "propeller");
    EXPECT_GT(c.interior, 20000u);
    EXPECT_LE(c.fraction, kMaxMovingCreases);
    const test::ImageSpeckles k = test::measureImageSpeckles(shot.image, shot.depth, 6);
    EXPECT_LE(double(k.speckled), kMaxMovingSpeckles * double(k.water));
  }
}

TEST_F(WaterLookTest, TheMetricsFailTheUnfilteredSurface) {
  // the raw sphere impostors: the lattice and the coarse spheres show, and the metrics say so
  s_renderer->settings().filterIterations = 0;
  const test::LookScene rest = test::restingHandTank(false);
  const test::LookShot shot = shoot(rest);
  EXPECT_GT(test::measureRestingSurface(shot.surface, rest.surfaceY, rest.inner).rmsNormalDegrees,
            3.0 * kMaxRestingNormalRms);
  const test::LookScene moving = test::movingPropeller();
  EXPECT_GT(test::measureCreases(shoot(moving).surface, 2, 20.0f, moving.fineRadius).fraction,
            3.0 * kMaxMovingCreases);  // 0.13
  const test::LookScene pushed = test::movingHandTank();
  EXPECT_GT(test::measureCreases(shoot(pushed).surface, 2, 20.0f, pushed.fineRadius).fraction,
            3.0 * kMaxMovingCreases);  // 0.37
}

namespace {

// The resting surface at 1280x720, where the normals see more of what the filter leaves (before the filter at
// half resolution: 3.22 deg fluidplaying, 0.81 uniform-high).
class WaterLookHighResolutionTest : public ::testing::Test {
 protected:
  static constexpr int kW = 1280;
  static constexpr int kH = 720;
  static void SetUpTestSuite() {
    s_context = std::make_unique<render::OffscreenContext>(kW, kH);
    s_renderer = std::make_unique<render::FluidRenderer>(render::defaultShaderDir());
  }
  static void TearDownTestSuite() {
    s_renderer.reset();
    s_context.reset();
  }
  void SetUp() override { s_renderer->settings() = render::RenderSettings(); }
  static std::unique_ptr<render::OffscreenContext> s_context;
  static std::unique_ptr<render::FluidRenderer> s_renderer;
};

std::unique_ptr<render::OffscreenContext> WaterLookHighResolutionTest::s_context;
std::unique_ptr<render::FluidRenderer> WaterLookHighResolutionTest::s_renderer;

}  // namespace

TEST_F(WaterLookHighResolutionTest, ARestingTankIsFlatInEveryMode) {
  for (bool adaptive : {false, true}) {
    const test::LookScene scene = test::restingHandTank(adaptive);
    const test::LookShot shot = test::shoot(*s_renderer, scene, kW, kH);
    const test::RestingSurface r = test::measureRestingSurface(shot.surface, scene.surfaceY, scene.inner);
    SCOPED_TRACE(adaptive ? "fluidplaying" : "uniform-high");
    ASSERT_GT(r.pixels, 20000u);
    EXPECT_GE(r.coverage, kMinRestingCoverage);
    EXPECT_LE(r.rmsNormalDegrees, kMaxRestingNormalRms);
  }
}

TEST_F(WaterLookHighResolutionTest, AdaptiveWaterAtRestLooksLikeUniformWater) {
  // the 2 levels at the window's default size too (session 7: 1.90 over the water, 0.28 % over 24
  // levels; 1.94 before the near glass's polygon offset, 2.30 with the filter of 4 fine radii, 3.11 with
  // session 6's renderer). The margin is small (5 %): llvmpipe draws the same image on every run, so it fails
  // on a change of the look, not on noise.
  const test::LookShot uniform = test::shoot(*s_renderer, test::restingHandTank(false), kW, kH);
  const test::LookShot adaptive = test::shoot(*s_renderer, test::restingHandTank(true), kW, kH);
  const test::WaterDifference d =
      test::compareWater(uniform.image, adaptive.image, uniform.depth, adaptive.depth, 24);
  EXPECT_GT(d.waterPixels, 100000u);
  EXPECT_LE(d.meanLevels, kMaxWaterMeanDifference);
  EXPECT_LE(d.imageMeanLevels, kMaxImageMeanDifference);
  EXPECT_LE(d.fractionOver, kMaxWaterFractionOver);
}

TEST_F(WaterLookHighResolutionTest, TheToleranceFailsTheFullResolutionFilter) {
  // the filter at full resolution strides over its 12 pairs at this size and leaves ripples
  s_renderer->settings().filterHalfResolution = false;
  const test::LookScene scene = test::restingHandTank(true);
  const test::LookShot shot = test::shoot(*s_renderer, scene, kW, kH);
  EXPECT_GT(test::measureRestingSurface(shot.surface, scene.surfaceY, scene.inner).rmsNormalDegrees,
            kMaxRestingNormalRms);
}
