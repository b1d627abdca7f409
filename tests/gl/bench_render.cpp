// Renderer benchmark (not a test): frame time per pass at 1280x720 for about 30k and 120k particles of a wavy
// water body in a glass tank, through OSMesa (llvmpipe here). Prints a table and CSV.
//   fp_bench_render [--frames N] [--png DIR] [--width W --height H] [--set KEY=VALUE]... [--help]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>

#include "engine/cli.h"
#include "engine/cli_app.h"
#include "render/fluid_renderer.h"
#include "render/image.h"
#include "render/offscreen_context.h"
#include "render/render_settings.h"
#include "render/shader_program.h"
#include "synthetic_scene.h"

using namespace fp;

namespace {

// A tank 2 x 1.2 x 1 m half full of water with a wave on it, at the particle radius that gives about `count`
// particles, plus 1% of that as spray above the crest.
test::SyntheticScene waveScene(int count) {
  const Eigen::Vector3f tank(1.0f, 0.6f, 0.5f);
  auto surface = [](float x, float z) {
    return 0.45f + 0.18f * std::sin(3.0f * x) + 0.05f * std::cos(5.0f * z);
  };
  const float volume = 2.0f * 1.0f * 0.45f;  // mean water depth 0.45 m over the 2 x 1 m floor
  const float r = 0.5f * std::cbrt(volume / float(count));
  test::SyntheticScene s = test::makeBlockScene(Eigen::Vector3f(-1.0f, 0.0f, -0.5f),
                                                Eigen::Vector3f(1.0f, 0.7f, 0.5f), r, tank, -0.6f, surface);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int k = 0; k < count / 100; ++k) {
    const float x = 0.2f + 0.5f * u(rng), z = -0.45f + 0.9f * u(rng);
    s.sprayPositions.emplace_back(x, surface(x, z) + 0.05f + 0.25f * u(rng), z);
    s.sprayRadii.push_back(0.4f * r);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 5, width = 1280, height = 720;
  std::string pngDir;
  std::vector<std::string> sets;
  engine::CommandLine line("fp_bench_render",
                           "fp_bench_render: frame time per pass of the fluid renderer at about 30k and 120k "
                           "particles of a wavy water body, through OSMesa. Prints a table and CSV.");
  line.addInteger(
      "--frames", [&](long long n) { frames = int(n); }, 1, 100000,
      "frames measured after one warm-up (default 5)");
  line.app()
      .add_option("--png", pngDir, "write each configuration's last frame as PNG into DIR")
      ->type_name("DIR");
  line.addInteger(
      "--width", [&](long long n) { width = int(n); }, 16, 8192, "image width in pixels (default 1280)");
  line.addInteger(
      "--height", [&](long long n) { height = int(n); }, 16, 8192, "image height in pixels (default 720)");
  line.addSet(sets)->description(
      "set a render setting over the defaults (repeatable), e.g. --set filter_iterations=3; the view "
      "is set by the benchmark");
  if (const std::optional<int> exit = line.parse(argc, argv))
    return *exit;
  for (const std::string& kv : sets) {
    if (!engine::isRenderSetting(kv)) {
      std::cerr << engine::usageErrorLine("fp_bench_render", "--set " + kv + ": not a render setting")
                << "\n";
      return engine::kExitUsage;
    }
  }
  render::OffscreenContext context(width, height);
  render::FluidRenderer renderer(render::defaultShaderDir());
  renderer.settings().profile = true;
  if (const std::string error = render::RenderSettingsTable::get().assignAll(renderer.settings(), sets);
      !error.empty()) {
    std::cerr << engine::usageErrorLine("fp_bench_render", "--set: " + error) << "\n";
    return engine::kExitUsage;
  }
  std::cout << "renderer benchmark, " << width << "x" << height << ", " << frames
            << " frames after one warm-up, " << context.description() << "\n\n";
  const char* header =
      "| view | particles | spray | scene ms | thickness ms | depth ms | filter ms | composite ms | "
      "overlay ms | total ms | fps |";
  std::cout << header << "\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::string csv =
      "view,particles,spray,scene_ms,thickness_ms,depth_ms,filter_ms,composite_ms,overlay_ms,total_ms\n";
  for (int count : {30000, 120000}) {
    const test::SyntheticScene scene = waveScene(count);
    const float aspect = float(width) / float(height);
    const render::OrbitCamera camera = test::frameCamera(scene, aspect);
    for (auto view : {render::RenderSettings::View::Fluid, render::RenderSettings::View::Particles}) {
      renderer.settings().view = view;
      renderer.update(scene.frame());
      render::RenderTarget target;
      target.width = width;
      target.height = height;
      render::PassTimes sum;
      for (int f = 0; f <= frames; ++f) {
        renderer.renderView(camera.view(), camera.projection(aspect), target);
        if (f == 0)
          continue;  // warm-up: shader variants and buffer allocation
        const render::PassTimes& t = renderer.passTimes();
        sum.scene += t.scene;
        sum.thickness += t.thickness;
        sum.depth += t.depth;
        sum.filter += t.filter;
        sum.composite += t.composite;
        sum.overlay += t.overlay;
      }
      const double n = frames;
      const char* name = view == render::RenderSettings::View::Fluid ? "fluid" : "particles";
      char row[512];
      std::snprintf(row, sizeof(row),
                    "| %s | %zu | %zu | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |", name,
                    scene.particles.size(), scene.sprayPositions.size(), sum.scene / n, sum.thickness / n,
                    sum.depth / n, sum.filter / n, sum.composite / n, sum.overlay / n, sum.total() / n,
                    1000.0 * n / sum.total());
      std::cout << row << "\n";
      std::snprintf(row, sizeof(row), "%s,%zu,%zu,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f\n", name,
                    scene.particles.size(), scene.sprayPositions.size(), sum.scene / n, sum.thickness / n,
                    sum.depth / n, sum.filter / n, sum.composite / n, sum.overlay / n, sum.total() / n);
      csv += row;
      if (!pngDir.empty()) {
        std::filesystem::create_directories(pngDir);
        render::writePng(pngDir + "/bench_" + name + "_" + std::to_string(count) + ".png",
                         render::readFramebuffer(0, 0, 0, width, height));
      }
    }
  }
  std::cout << "\n" << csv;
  return 0;
}
