// The figures of issue 14 (not a test): renders the resting hand tank at uniform-high and fluidplaying and a
// moving propeller frame through OSMesa, and prints the resting surface's normal rms and height error, the
// adaptive-vs-uniform difference and the crease fraction of each, read from the renderer's own buffers.
//   fp_water_look [--width W --height H] [--png DIR] [--set KEY=VALUE ...]
// --set changes a render setting (filter_radius=6, filter_max_taps=24, wet_reach=0, ...) for experiments.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "render/image.h"
#include "render/offscreen_context.h"
#include "render/shader_program.h"
#include "water_look_scenes.h"

using namespace fp;

namespace {

// The angle of the reconstructed normal from the vertical over the measured free surface (grey: no
// surface pixel; black 0, white 10 degrees or more), to see where the rms comes from.
render::Image angleMap(const test::DepthSurface& s, float surfaceY, const Eigen::AlignedBox2f& inner) {
  render::Image m;
  m.width = s.width();
  m.height = s.height();
  m.rgba.assign(std::size_t(m.width) * std::size_t(m.height) * 4, 0);
  const Eigen::Vector3f eye = s.eye();
  for (int y = 0; y < s.height(); ++y) {
    for (int x = 0; x < s.width(); ++x) {
      std::uint8_t* px =
          &m.rgba[(std::size_t(s.height() - 1 - y) * std::size_t(m.width) + std::size_t(x)) * 4];
      px[0] = px[1] = px[2] = 96;
      px[3] = 255;
      const Eigen::Vector3f d = s.rayDirection(x, y);
      if (d.y() >= -1e-4f)
        continue;
      const Eigen::Vector3f hit = eye + d * ((surfaceY - eye.y()) / d.y());
      const Eigen::Vector3f n = s.normal(x, y);
      if (!inner.contains(Eigen::Vector2f(hit.x(), hit.z())) || n.squaredNorm() == 0.0f)
        continue;
      const float a = std::acos(std::clamp(std::abs(n.y()), 0.0f, 1.0f)) * 180.0f / float(M_PI);
      px[0] = px[1] = px[2] = std::uint8_t(std::min(255.0f, a * 25.5f));
      px[0] = 255;
    }
  }
  return m;
}

// Percentiles of the normal angle over the measured free surface [deg]: where the rms comes from.
std::string anglePercentiles(const test::DepthSurface& s, float surfaceY, const Eigen::AlignedBox2f& inner) {
  std::vector<float> a;
  test::forEachRestingSurfacePixel(s, surfaceY, inner, [&](int, int, const Eigen::Vector3f& n) {
    a.push_back(float(test::angleFromVerticalDegrees(n)));
  });
  if (a.empty())
    return "";
  std::sort(a.begin(), a.end());
  auto at = [&](double q) { return a[std::min(a.size() - 1, std::size_t(q * double(a.size())))]; };
  char line[160];
  double body = 0;
  std::size_t over = 0;
  for (float v : a) {
    body += v <= 20.0f ? double(v) * double(v) : 0.0;
    over += v > 20.0f;
  }
  std::snprintf(line, sizeof line,
                "angle p50 %.2f p90 %.2f p99 %.2f max %.2f deg; %zu px over 20 deg, rms without them %.2f",
                double(at(0.5)), double(at(0.9)), double(at(0.99)), double(a.back()), over,
                std::sqrt(body / double(a.size() - over)));
  return line;
}

// |a - b| times 8 (the channel differences, 32 levels white)
render::Image differenceMap(const render::Image& a, const render::Image& b) {
  render::Image m = a;
  for (std::size_t k = 0; k < m.rgba.size(); ++k)
    m.rgba[k] = k % 4 == 3 ? 255 : std::uint8_t(std::min(255, 8 * std::abs(int(a.rgba[k]) - int(b.rgba[k]))));
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  int width = 640, height = 360;
  std::string pngDir;
  std::vector<std::string> sets;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--width" && k + 1 < argc)
      width = std::atoi(argv[++k]);
    else if (a == "--height" && k + 1 < argc)
      height = std::atoi(argv[++k]);
    else if (a == "--png" && k + 1 < argc)
      pngDir = argv[++k];
    else if (a == "--set" && k + 1 < argc)
      sets.push_back(argv[++k]);
    else {
      std::cerr << "usage: fp_water_look [--width W --height H] [--png DIR] [--set KEY=VALUE ...]\n";
      return 2;
    }
  }
  render::OffscreenContext context(width, height);
  render::FluidRenderer renderer(render::defaultShaderDir());
  for (const std::string& s : sets) {
    const std::string error = test::applySetting(renderer.settings(), s);
    if (!error.empty()) {
      std::cerr << error << "\n";
      return 2;
    }
  }
  if (!pngDir.empty())
    std::filesystem::create_directories(pngDir);
  std::cout << width << "x" << height << ", " << context.description() << "\n";

  test::LookShot shots[2];
  const char* modes[2] = {"uniform-high", "fluidplaying"};
  for (int m = 0; m < 2; ++m) {
    const test::LookScene scene = test::restingHandTank(m == 1);
    shots[m] = test::shoot(renderer, scene, width, height);
    const test::RestingSurface r = test::measureRestingSurface(shots[m].surface, scene.surfaceY, scene.inner);
    const test::Creases c = test::measureCreases(shots[m].surface, 2, 20.0f, scene.fineRadius);
    std::printf(
        "resting %-13s normal rms %6.2f deg  height error mean %+6.2f mm rms %5.2f mm (%.2f fine radii)  "
        "coverage %.3f of %zu px  creases %.4f\n",
        modes[m], r.rmsNormalDegrees, 1e3 * r.meanHeightError, 1e3 * r.rmsHeightError,
        r.meanHeightError / scene.fineRadius, r.coverage, r.pixels, c.fraction);
    std::printf("  %s\n", anglePercentiles(shots[m].surface, scene.surfaceY, scene.inner).c_str());
    if (!pngDir.empty()) {
      render::writePng(pngDir + "/rest_" + modes[m] + ".png", shots[m].image);
      render::writePng(pngDir + "/rest_" + modes[m] + "_angle.png",
                       angleMap(shots[m].surface, scene.surfaceY, scene.inner));
    }
  }
  const test::WaterDifference d =
      test::compareWater(shots[0].image, shots[1].image, shots[0].depth, shots[1].depth, 24);
  std::printf(
      "adaptive vs uniform at rest: mean %.2f levels over %zu water px (%.2f over the image), %.2f %% over "
      "24 levels\n",
      d.meanLevels, d.waterPixels, d.imageMeanLevels, 100.0 * d.fractionOver);
  if (!pngDir.empty())
    render::writePng(pngDir + "/rest_difference.png", differenceMap(shots[0].image, shots[1].image));
  {
    // the renderer's part: the same uniform-high water drawn from the particles at fluidplaying's resolutions
    const test::LookScene scene = test::coarsenedRestingTank();
    const test::LookShot shot = test::shoot(renderer, scene, width, height);
    const test::RestingSurface r = test::measureRestingSurface(shot.surface, scene.surfaceY, scene.inner);
    const test::WaterDifference c =
        test::compareWater(shots[0].image, shot.image, shots[0].depth, shot.depth, 24);
    std::printf(
        "uniform-high state coarsened as fluidplaying (%zu particles): normal rms %.2f deg; against "
        "uniform-high: mean %.2f levels over %zu water px (%.2f over the image), %.2f %% over 24 levels\n",
        scene.state.particles.size(), r.rmsNormalDegrees, c.meanLevels, c.waterPixels, c.imageMeanLevels,
        100.0 * c.fractionOver);
    // the simulation's part: fluidplaying's own state against that water at about the same resolutions
    const test::WaterDifference f =
        test::compareWater(shot.image, shots[1].image, shot.depth, shots[1].depth, 24);
    std::printf(
        "fluidplaying state vs the coarsened uniform-high state: mean %.2f levels over %zu water px, %.2f %% "
        "over 24 levels\n",
        f.meanLevels, f.waterPixels, 100.0 * f.fractionOver);
    if (!pngDir.empty())
      render::writePng(pngDir + "/rest_coarsened.png", shot.image);
  }
  for (const auto& [name, scene] : {std::make_pair("propeller", test::movingPropeller()),
                                    std::make_pair("hand_tank_push", test::movingHandTank())}) {
    const test::LookShot shot = test::shoot(renderer, scene, width, height);
    const test::Creases c = test::measureCreases(shot.surface, 2, 20.0f, scene.fineRadius);
    const test::ImageSpeckles k = test::measureImageSpeckles(shot.image, shot.depth, 6);
    std::printf("moving %s fluidplaying: creases %.4f of %zu interior water px, %zu speckled px of %zu\n",
                name, c.fraction, c.interior, k.speckled, k.water);
    if (!pngDir.empty())
      render::writePng(pngDir + "/moving_" + name + ".png", shot.image);
  }
  return 0;
}
