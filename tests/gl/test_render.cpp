// Image tests of the renderer (label gl), through OSMesa with no display. A small fixed scene (a
// 2,250-particle water block in a glass tank, 160x120 pixels) is rendered and measured in numbers: coverage
// of the projected fluid, red pixels of split children, spray pixels, a reference image under a stated
// tolerance, the errors of missing or broken shaders, and the headless renderer (PNG frames, splash as
// spray).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "engine/frame_splash.h"
#include "engine/headless_render.h"
#include "engine/headless_runner.h"
#include "engine/scene_loader.h"
#include "render/fluid_renderer.h"
#include "render/image.h"
#include "render/offscreen_context.h"
#include "render/render_error.h"
#include "render/shader_program.h"
#include "render/video_writer.h"
#include "synthetic_scene.h"

using namespace fp;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 160;
constexpr int kHeight = 120;
// Reference image tolerance: a pixel may differ by up to 24 levels in a channel, at most 1% of the pixels may
// differ by more, and the mean channel difference must stay under 1.5 levels. Mesa's llvmpipe is
// deterministic for one version; the slack covers another LLVM vector width or Mesa release.
constexpr int kPixelTolerance = 24;
constexpr double kMaxFractionOver = 0.01;
constexpr double kMaxMeanDifference = 1.5;

// The block: x in [-0.25, 0.05] m, 10 cm high, in a 60 x 40 x 40 cm tank; children of a split left of x =
// -0.1.
constexpr float kSplitX = -0.1f;
test::SyntheticScene blockScene() {
  return test::makeBlockScene(Eigen::Vector3f(-0.25f, 0.0f, -0.15f), Eigen::Vector3f(0.05f, 0.2f, 0.15f),
                              0.01f, Eigen::Vector3f(0.3f, 0.2f, 0.2f), kSplitX);
}

// A cloud of spray droplets above the right part of the tank, where there is no water.
void addSpray(test::SyntheticScene& s) {
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 6; ++k) {
      s.sprayPositions.emplace_back(0.1f + 0.022f * float(i), 0.28f + 0.01f * float((i + k) % 3),
                                    -0.1f + 0.04f * k);
      s.sprayRadii.push_back(0.006f);
    }
  }
}

bool isRed(const std::uint8_t* p) {
  return p[0] >= 120 && p[0] >= 1.8 * p[1] && p[0] >= 1.8 * p[2];
}

class GlRenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    m_context = std::make_unique<render::OffscreenContext>(kWidth, kHeight);
    m_renderer = std::make_unique<render::FluidRenderer>(render::defaultShaderDir());
  }

  render::Image draw(const render::FrameData& frame) {
    m_renderer->update(frame);
    render::RenderTarget target;
    target.width = kWidth;
    target.height = kHeight;
    m_renderer->renderView(m_camera.view(), m_camera.projection(aspect()), target);
    return render::readFramebuffer(0, 0, 0, kWidth, kHeight);
  }

  // pixel position (x right, y down) of a world point
  Eigen::Vector2f project(const Eigen::Vector3f& p) const {
    const Eigen::Vector4f q = m_camera.projection(aspect()) * m_camera.view() * p.homogeneous();
    return Eigen::Vector2f((q.x() / q.w() * 0.5f + 0.5f) * kWidth, (0.5f - q.y() / q.w() * 0.5f) * kHeight);
  }

  void frame(const test::SyntheticScene& s) { m_camera = test::frameCamera(s, aspect()); }
  static float aspect() { return float(kWidth) / float(kHeight); }
  render::FluidRenderer& renderer() { return *m_renderer; }

 private:
  std::unique_ptr<render::OffscreenContext> m_context;
  std::unique_ptr<render::FluidRenderer> m_renderer;
  render::OrbitCamera m_camera;
};

// pixels whose colour differs by more than `threshold` in some channel
std::vector<Eigen::Vector2i> changedPixels(const render::Image& a, const render::Image& b, int threshold) {
  std::vector<Eigen::Vector2i> out;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        if (std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c])) > threshold) {
          out.emplace_back(x, y);
          break;
        }
      }
    }
  }
  return out;
}

fs::path copyShaders(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::copy(render::defaultShaderDir(), dir, fs::copy_options::recursive);
  return dir;
}

// appends `text` to line `line` (from 1) of a file
void appendToLine(const fs::path& file, int line, const std::string& text) {
  std::ifstream in(file);
  std::stringstream out;
  std::string l;
  for (int n = 1; std::getline(in, l); ++n)
    out << l << (n == line ? text : "") << "\n";
  in.close();
  std::ofstream(file) << out.str();
}

}  // namespace

TEST_F(GlRenderTest, MatchesTheReferenceImage) {
  test::SyntheticScene s = blockScene();
  addSpray(s);
  frame(s);
  const render::Image image = draw(s.frame());
  const std::string reference = std::string(FP_GL_TEST_DIR) + "/reference_fluid.png";
  if (std::getenv("FP_UPDATE_REFERENCE")) {
    render::writePng(reference, image);
    GTEST_SKIP() << "reference written to " << reference;
  }
  const render::ImageDiff d = render::compareImages(image, render::readPng(reference), kPixelTolerance);
  const std::string actual = ::testing::TempDir() + "/fp_render_actual.png";
  render::writePng(actual, image);
  EXPECT_LE(d.fractionOver, kMaxFractionOver) << "rendered image in " << actual;
  EXPECT_LE(d.meanDifference, kMaxMeanDifference) << "rendered image in " << actual;
}

TEST_F(GlRenderTest, AChangedShaderFailsTheReference) {
  // water that no longer absorbs light: the same geometry, a different look
  const fs::path dir = copyShaders("fp_shaders_changed");
  std::ifstream in(dir / "fluid_composite.frag");
  std::stringstream text;
  text << in.rdbuf();
  in.close();
  std::string source = text.str();
  const std::string from = "vec3 transmitted = exp(-uAbsorption * thickness.x);";
  ASSERT_NE(source.find(from), std::string::npos);
  source.replace(source.find(from), from.size(), "vec3 transmitted = vec3(1.0);");
  std::ofstream(dir / "fluid_composite.frag") << source;

  render::OffscreenContext context(kWidth, kHeight);
  render::FluidRenderer changed(dir.string());
  test::SyntheticScene s = blockScene();
  addSpray(s);
  const render::OrbitCamera camera = test::frameCamera(s, aspect());
  changed.update(s.frame());
  render::RenderTarget target;
  target.width = kWidth;
  target.height = kHeight;
  changed.renderView(camera.view(), camera.projection(aspect()), target);
  const render::Image image = render::readFramebuffer(0, 0, 0, kWidth, kHeight);
  const render::ImageDiff d = render::compareImages(
      image, render::readPng(std::string(FP_GL_TEST_DIR) + "/reference_fluid.png"), kPixelTolerance);
  EXPECT_TRUE(d.fractionOver > kMaxFractionOver || d.meanDifference > kMaxMeanDifference)
      << "fraction over " << d.fractionOver << ", mean " << d.meanDifference;
}

TEST_F(GlRenderTest, WaterCoversTheProjectedFluidAndNothingFarOutside) {
  const test::SyntheticScene s = blockScene();
  frame(s);
  renderer().settings().highlightSplits = false;
  const render::Image water = draw(s.frame());
  test::SyntheticScene empty = s;
  empty.particles.clear();
  const render::Image background = draw(empty.frame());
  const std::vector<Eigen::Vector2i> changed = changedPixels(water, background, 6);

  // the projected bounding box of the spheres, widened by two pixels
  Eigen::AlignedBox2f rect;
  const Eigen::Vector3f lo(-0.25f, 0.0f, -0.15f), hi(0.05f, 0.2f, 0.15f);
  for (int k = 0; k < 8; ++k)
    rect.extend(
        project(Eigen::Vector3f(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z())));
  rect.min() -= Eigen::Vector2f(2, 2);
  rect.max() += Eigen::Vector2f(2, 2);
  std::vector<char> mask(std::size_t(kWidth) * kHeight, 0);
  std::size_t outside = 0;
  for (const auto& p : changed) {
    mask[std::size_t(p.y()) * kWidth + p.x()] = 1;
    outside += !rect.contains(Eigen::Vector2f(float(p.x()) + 0.5f, float(p.y()) + 0.5f));
  }
  EXPECT_EQ(outside, 0u) << "water pixels outside the projected fluid";
  // every particle centre lands on water
  std::size_t hits = 0;
  for (const sim::Vec3& x : s.particles.x) {
    const Eigen::Vector2f q = project(x);
    hits += mask[std::size_t(q.y()) * kWidth + std::size_t(q.x())];
  }
  EXPECT_GE(double(hits), 0.98 * double(s.particles.size()));
  // and the water fills most of its projected box (a box seen from above and aside fills about 70%)
  const double rectArea = double(rect.sizes().prod());
  EXPECT_GE(double(changed.size()), 0.5 * rectArea) << changed.size() << " of " << rectArea;
  // neither blank nor saturated
  std::size_t white = 0, black = 0;
  for (std::size_t p = 0; p < water.rgba.size(); p += 4) {
    white += water.rgba[p] >= 250 && water.rgba[p + 1] >= 250 && water.rgba[p + 2] >= 250;
    black += water.rgba[p] <= 5 && water.rgba[p + 1] <= 5 && water.rgba[p + 2] <= 5;
  }
  EXPECT_GE(changed.size(), std::size_t(0.05 * kWidth * kHeight));
  EXPECT_LE(white, std::size_t(0.01 * kWidth * kHeight));
  EXPECT_LE(black, std::size_t(0.01 * kWidth * kHeight));
}

TEST_F(GlRenderTest, FreshSplitChildrenAreRedOnlyWithTheHighlightOn) {
  test::SyntheticScene s = blockScene();
  frame(s);
  const float splitPixel = project(Eigen::Vector3f(kSplitX, 0.1f, 0.0f)).x();
  auto countRed = [&](const render::Image& image, std::size_t& leftOfSplit) {
    std::size_t red = 0;
    leftOfSplit = 0;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        if (isRed(image.at(x, y))) {
          ++red;
          // the block is seen from the front right, so the split plane leans: allow ten pixels
          leftOfSplit += float(x) < splitPixel + 10.0f;
        }
      }
    }
    return red;
  };
  std::size_t left = 0;
  renderer().settings().highlightSplits = true;
  const std::size_t on = countRed(draw(s.frame()), left);
  EXPECT_GE(on, 300u);
  EXPECT_GE(double(left), 0.95 * double(on)) << "red pixels away from the split children";

  renderer().settings().highlightSplits = false;
  EXPECT_EQ(countRed(draw(s.frame()), left), 0u);

  // the highlight fades: a split older than the highlight duration is not red
  renderer().settings().highlightSplits = true;
  s.time += 1.0;
  EXPECT_EQ(countRed(draw(s.frame()), left), 0u);
}

TEST_F(GlRenderTest, SprayIsDropletsAndFoamOnlyWhenOn) {
  test::SyntheticScene s = blockScene();
  frame(s);
  const render::Image without = draw(s.frame(false));
  addSpray(s);
  renderer().settings().showSpray = true;
  const render::Image with = draw(s.frame());
  const std::vector<Eigen::Vector2i> spray = changedPixels(with, without, 6);
  EXPECT_GE(spray.size(), 40u);
  // droplets in the air are clear, not white dots: few of their pixels are near white
  std::size_t white = 0;
  for (const auto& p : spray) {
    const std::uint8_t* c = with.at(p.x(), p.y());
    white += c[0] >= 235 && c[1] >= 235 && c[2] >= 235;
  }
  EXPECT_LE(double(white), 0.1 * double(spray.size()));

  // foam: droplets lying on the water are whiter than the water under them
  test::SyntheticScene foam = blockScene();
  for (int i = 0; i < 10; ++i) {
    for (int k = 0; k < 10; ++k) {
      foam.sprayPositions.emplace_back(-0.22f + 0.024f * float(i), 0.2f, -0.12f + 0.024f * float(k));
      foam.sprayRadii.push_back(0.006f);
    }
  }
  const render::Image water = draw(foam.frame(false));
  const render::Image foamy = draw(foam.frame());
  const std::vector<Eigen::Vector2i> foamPixels = changedPixels(foamy, water, 6);
  ASSERT_GE(foamPixels.size(), 40u);
  double brighter = 0;
  for (const auto& p : foamPixels) {
    for (int c = 0; c < 3; ++c)
      brighter += double(foamy.at(p.x(), p.y())[c]) - double(water.at(p.x(), p.y())[c]);
  }
  EXPECT_GE(brighter / (3.0 * double(foamPixels.size())), 10.0);

  renderer().settings().showSpray = false;
  EXPECT_EQ(changedPixels(draw(s.frame()), without, 0).size(), 0u);
}

TEST_F(GlRenderTest, ParticleViewDrawsSprayGreen) {
  test::SyntheticScene s = blockScene();
  frame(s);
  renderer().settings().view = render::RenderSettings::View::Particles;
  const render::Image without = draw(s.frame(false));
  addSpray(s);
  const render::Image with = draw(s.frame());
  const std::vector<Eigen::Vector2i> spray = changedPixels(with, without, 12);
  ASSERT_GE(spray.size(), 40u);
  std::size_t green = 0;
  for (const auto& p : spray) {
    const std::uint8_t* c = with.at(p.x(), p.y());
    green += c[1] >= 60 && c[1] >= 2 * c[0] && c[1] >= 2 * c[2];
  }
  EXPECT_GE(double(green), 0.8 * double(spray.size()));
}

TEST_F(GlRenderTest, ParticleViewColoursByTheFieldAndDrawsALegend) {
  const test::SyntheticScene s = blockScene();
  frame(s);
  renderer().settings().view = render::RenderSettings::View::Particles;
  renderer().settings().colorField = render::ColorField::Nu;  // 1 at the bottom layer, 8 at the top
  const render::Image image = draw(s.frame());
  test::SyntheticScene empty = s;
  empty.particles.clear();
  const render::Image legendOnly = draw(empty.frame());
  // viridis runs from purple (low) to yellow (high)
  auto isPurple = [](const std::uint8_t* p) { return p[2] > p[1] + 12 && p[0] > p[1] && p[2] > 25; };
  auto isYellow = [](const std::uint8_t* p) { return p[0] > 150 && p[1] > 150 && p[2] < 90; };
  std::size_t purple = 0, yellow = 0, legendPurple = 0, legendYellow = 0;
  for (const auto& q : changedPixels(image, legendOnly, 6)) {
    purple += isPurple(image.at(q.x(), q.y()));
    yellow += isYellow(image.at(q.x(), q.y()));
  }
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      legendPurple += isPurple(legendOnly.at(x, y));
      legendYellow += isYellow(legendOnly.at(x, y));
    }
  }
  EXPECT_GE(yellow, 50u);  // the top layers, seen from above
  EXPECT_GE(purple, 5u);   // the bottom layer, seen from the side
  EXPECT_GE(legendPurple, 10u);
  EXPECT_GE(legendYellow, 10u);
  // the legend sits in the bottom-right corner, away from the window's panel (top left): its bar reaches the
  // right edge and none of it is in the top half
  std::size_t top = 0, legendPixels = 0;
  int right = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if (!isPurple(legendOnly.at(x, y)) && !isYellow(legendOnly.at(x, y)))
        continue;
      ++legendPixels;
      top += y < kHeight / 2;
      right = std::max(right, x);
    }
  }
  EXPECT_GE(legendPixels, 20u);
  EXPECT_EQ(top, 0u);
  EXPECT_GE(right, kWidth - 24);
}

TEST_F(GlRenderTest, CollidersAreDrawn) {
  test::SyntheticScene s = blockScene();
  frame(s);
  const render::Image before = draw(s.frame());
  sim::ColliderState hand;
  hand.desc.shape = sim::ShapeType::Sphere;
  hand.desc.radius = 0.05;
  hand.desc.driven = true;
  hand.position = sim::Vec3d(0.18, 0.15, 0.0);
  s.colliders.push_back(hand);
  const render::Image after = draw(s.frame());
  const std::vector<Eigen::Vector2i> changed = changedPixels(after, before, 12);
  const Eigen::Vector2f c = project(Eigen::Vector3f(0.18f, 0.15f, 0.0f));
  const float radiusPx = (project(Eigen::Vector3f(0.18f, 0.2f, 0.0f)) - c).norm();
  EXPECT_GE(double(changed.size()), 0.6 * 3.14159 * radiusPx * radiusPx);
  for (const auto& p : changed)
    EXPECT_LE((p.cast<float>() - c).norm(), 1.5f * radiusPx + 2.0f);
}

TEST(ShaderErrorTest, AMissingShaderFileGivesAOneLineErrorNamingIt) {
  render::OffscreenContext context(32, 32);
  const fs::path dir = copyShaders("fp_shaders_missing");
  fs::remove(dir / "depth_filter.frag");
  try {
    render::FluidRenderer renderer(dir.string());
    FAIL() << "no error for a missing shader";
  } catch (const render::ShaderError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("depth_filter.frag"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(ShaderErrorTest, ABrokenShaderNamesTheFileAndLine) {
  render::OffscreenContext context(32, 32);
  const fs::path dir = copyShaders("fp_shaders_broken");
  appendToLine(dir / "depth_filter.frag", 23, " float broken = undeclaredName;");
  try {
    render::FluidRenderer renderer(dir.string());
    FAIL() << "no error for a broken shader";
  } catch (const render::ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("depth_filter.frag:23:"), std::string::npos) << e.what();
  }
  // a line of an included file is reported in that file
  const fs::path dir2 = copyShaders("fp_shaders_broken_include");
  appendToLine(dir2 / "common.glsl", 7, "vec3 broken = undeclaredName;");
  try {
    render::FluidRenderer renderer(dir2.string());
    FAIL() << "no error for a broken include";
  } catch (const render::ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("common.glsl:7:"), std::string::npos) << e.what();
  }
}

TEST(ShaderErrorTest, DriverLogsAreRewrittenAsFileAndLine) {
  const std::vector<std::string> files = {"a.frag", "common.glsl"};
  EXPECT_EQ(render::formatShaderLog("0:12(5): error: `x' undeclared", files),
            "a.frag:12: error: `x' undeclared");
  EXPECT_EQ(render::formatShaderLog("0(100007) : error C1008: undefined variable", files),
            "common.glsl:7: error C1008: undefined variable");
  EXPECT_EQ(render::formatShaderLog("ERROR: 0:3: bad", files), "a.frag:3: bad");
}

TEST(HeadlessRenderTest, WritesPngFramesWithNoDisplay) {
  const fs::path dir = fs::path(::testing::TempDir()) / "fp_headless_png";
  fs::remove_all(dir);
  const std::string exe = FP_FLUIDPLAYING_EXE;
  const std::string scene = std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json";
  const std::string common = "env -u DISPLAY " + exe + " --headless --render --quiet --threads 1 --scene " +
                             scene + " --frames 2 --width 96 --height 64";
  int status = std::system((common + " --out " + dir.string() + " > /dev/null 2>&1").c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  for (int f = 0; f <= 2; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", f);
    const render::Image image = render::readPng((dir / name).string());
    EXPECT_EQ(image.width, 96);
    EXPECT_EQ(image.height, 64);
  }
  // a missing shader folder: exit code 3 with one line naming the file, and no image
  const fs::path dir2 = fs::path(::testing::TempDir()) / "fp_headless_png_noshader";
  fs::remove_all(dir2);
  const std::string log = ::testing::TempDir() + "/fp_headless_png_noshader.log";
  status = std::system(
      (common + " --shaders /nonexistent/shaders --out " + dir2.string() + " > " + log + " 2>&1").c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("shader file not found: /nonexistent/shaders/"), std::string::npos) << text.str();
  EXPECT_FALSE(fs::exists(dir2 / "frame_00000.png"));
}

TEST(HeadlessRenderTest, ADamBreakFrameWithSplashHasSprayPixels) {
  // the tiny dam break when its front has run up the far wall and sprays
  sim::Simulation simulation(
      engine::loadScene(std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json"));
  while (simulation.time() < 0.4)
    simulation.step();
  const int frame = 24;
  auto renderTo = [&](const std::string& name, bool noSpray) {
    engine::CliOptions o;
    o.outDir = (fs::path(::testing::TempDir()) / name).string();
    o.width = kWidth;
    o.height = kHeight;
    o.noSpray = noSpray;
    engine::HeadlessRender r(o);
    r.renderFrame(frame, simulation);
    return std::make_pair(render::readPng(o.outDir + "/frame_00024.png"), r.sprayCount());
  };
  const auto [with, sprayCount] = renderTo("fp_headless_spray_on", false);
  const auto [without, noCount] = renderTo("fp_headless_spray_off", true);
  EXPECT_GT(sprayCount, 0u);
  EXPECT_EQ(noCount, 0u);
  EXPECT_GE(changedPixels(with, without, 12).size(), 20u);
  // splash_enabled = false draws no spray either
  simulation.params().splashEnabled = false;
  const auto [disabled, disabledCount] = renderTo("fp_headless_spray_disabled", false);
  EXPECT_EQ(disabledCount, 0u);
  EXPECT_EQ(changedPixels(disabled, without, 0).size(), 0u);
}

TEST(HeadlessRenderTest, StatisticsAndRendererShareOneSplashAFrame) {
  // the run's statistics generate each frame's splash once and hand it to the frame callback (the renderer's)
  engine::CliOptions o;
  o.scenePath = std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json";
  o.frames = 30;  // 0.5 s: the front has run up the far wall and sprays
  o.threads = 1;
  o.quiet = true;
  std::ostringstream out, progress;
  double sum = 0.0;
  int calls = 0;
  const engine::RunSummary summary =
      engine::runHeadless(o, out, progress, [&](int, const sim::Simulation&, const sim::SplashParticles& sp) {
        sum += double(sp.size());
        ++calls;
      });
  EXPECT_EQ(calls, 31);  // frames 0 to 30
  EXPECT_GT(sum, 0.0);
  EXPECT_DOUBLE_EQ(summary.splashParticles, sum / double(calls));
  // the renderer draws the splash it is handed, without generating its own
  sim::Simulation simulation(engine::loadScene(o.scenePath));
  sim::SplashParticles given;
  for (int i = 0; i < 7; ++i) {
    given.x.emplace_back(0.01f * float(i), 0.3f, 0.0f);
    given.radius.push_back(0.004f);
    given.source.push_back(0);
  }
  engine::CliOptions r;
  r.outDir = (fs::path(::testing::TempDir()) / "fp_headless_given_splash").string();
  r.width = kWidth;
  r.height = kHeight;
  engine::HeadlessRender render(r);
  render.renderFrame(0, simulation, &given);
  EXPECT_EQ(render.sprayCount(), 7u);
}

TEST(FrameSplashTest, APausedWindowKeepsItsSplash) {
  // the window's splash (engine::FrameSplash): generated once a state, not once a frame while paused
  sim::Simulation simulation(
      engine::loadScene(std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json"));
  engine::FrameSplash splash;
  for (int frame = 0; frame < 5; ++frame)
    splash.of(simulation, std::uint64_t(frame));  // paused: five frames drawn, the same state
  EXPECT_EQ(splash.generations(), 1u);
  simulation.step();
  splash.of(simulation, 5);
  splash.of(simulation, 6);
  EXPECT_EQ(splash.generations(), 2u);
  sim::Simulation other(engine::loadScene(std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json"));
  splash.of(other, 7);  // another simulation (a reset or a new scene)
  EXPECT_EQ(splash.generations(), 3u);
}

TEST(HeadlessRenderTest, WritesAVideoAtTheSceneFrameRate) {
  if (render::VideoWriter::findFfmpeg().empty())
    GTEST_SKIP() << "ffmpeg is not on PATH: no video to write";
  const fs::path video = fs::path(::testing::TempDir()) / "fp_headless.mp4";
  fs::remove(video);
  const std::string scene = std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json";
  const int status =
      std::system(("env -u DISPLAY " + std::string(FP_FLUIDPLAYING_EXE) +
                   " --headless --render --quiet --threads 1 --scene " + scene +
                   " --frames 3 --width 96 --height 64 --video " + video.string() + " > /dev/null 2>&1")
                      .c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  ASSERT_TRUE(fs::exists(video));
  EXPECT_GT(fs::file_size(video), 0u);
  if (std::system("command -v ffprobe > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "ffprobe is not on PATH: frame count, size and rate not checked";
  // frames 0 to 3 (the initial state and three frames), at the scene's 60 frames a second
  std::string probe;
  if (FILE* pipe = popen(("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                          "stream=nb_read_frames,width,height,r_frame_rate -of csv=p=0 '" +
                          video.string() + "'")
                             .c_str(),
                         "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof(buffer), pipe))
      probe += buffer;
    pclose(pipe);
  }
  EXPECT_NE(probe.find("96,64,60/1,4"), std::string::npos) << probe;
}

TEST(HeadlessRenderTest, AVideoWithoutFfmpegIsAOneLineErrorBeforeAnySimulation) {
  // PATH without ffmpeg: exit code 3 and one line naming ffmpeg, no frame simulated or written
  const fs::path empty = fs::path(::testing::TempDir()) / "fp_headless_no_ffmpeg";
  fs::remove_all(empty);
  fs::create_directories(empty);
  const std::string log = (empty / "log.txt").string();
  const std::string scene = std::string(FP_SOURCE_DIR) + "/assets/scenes/tiny_dam_break.json";
  const int status = std::system(
      ("env -u DISPLAY PATH=" + empty.string() + " " + std::string(FP_FLUIDPLAYING_EXE) +
       " --headless --render --threads 1 --scene " + scene + " --frames 3 --width 96 --height 64 --out " +
       (empty / "png").string() + " --video " + (empty / "v.mp4").string() + " > " + log + " 2>&1")
          .c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("ffmpeg program is not on PATH"), std::string::npos) << text.str();
  EXPECT_EQ(text.str().find("t = "), std::string::npos) << text.str();  // no progress line: nothing simulated
  EXPECT_FALSE(fs::exists(empty / "png" / "frame_00000.png"));
  EXPECT_FALSE(fs::exists(empty / "v.mp4"));
}
