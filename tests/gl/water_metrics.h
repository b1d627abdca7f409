#pragma once
// Measures of how the water looks, read from the renderer's own buffers (issue 14): the normal of the
// filtered depth over the visible free surface of a resting tank, the rendered surface height against the
// simulated one, the image difference between two renderings over the water, and a crease metric that finds
// seams, rings and blobs in a moving surface. Shared by the image tests and the tool that prints the figures.

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "render/camera.h"
#include "render/fluid_renderer.h"
#include "render/image.h"
#include "sim/particle_set.h"
#include "sim/ply_writer.h"
#include "synthetic_scene.h"

namespace fp::test {

// A particle state exported by `fluidplaying --headless --export` (tests/gl/data/*.ply) in its box tank
// standing on y = 0, with the scene's fine particle radius.
inline SyntheticScene loadTankState(const std::string& ply, const Eigen::Vector3f& tankHalf,
                                    float fineRadius) {
  SyntheticScene s;
  s.particles = sim::readPly(ply);
  for (std::size_t i = 0; i < s.particles.size(); ++i)
    s.particles.splitTime[i] = -1.0f;
  s.params.particleRadius = fineRadius;
  s.params.restDensity = 1000.0;
  addBoxTank(s, tankHalf);
  return s;
}

// The simulated free surface: the median over x-z columns (2 fine radii wide, inside `inner`) of the highest
// sphere top y + H/4 [m].
inline float simulatedSurfaceHeight(const sim::ParticleSet& p, float fineRadius,
                                    const Eigen::AlignedBox2f& inner) {
  const float cell = 2.0f * fineRadius;
  std::unordered_map<long long, float> tops;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2f xz(p.x[i].x(), p.x[i].z());
    if (!inner.contains(xz))
      continue;
    const long long key =
        (long long)(std::floor(xz.x() / cell)) * 100000 + (long long)(std::floor(xz.y() / cell));
    const float top = p.x[i].y() + 0.25f * p.H[i];
    auto [it, fresh] = tops.emplace(key, top);
    if (!fresh)
      it->second = std::max(it->second, top);
  }
  std::vector<float> v;
  for (const auto& kv : tops)
    v.push_back(kv.second);
  if (v.empty())
    return 0.0f;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Reconstructs view-space positions and normals from an eye-depth buffer (rows from the bottom) as the
// composite shader does: differences towards the neighbour with the smaller depth step.
class DepthSurface {
 public:
  DepthSurface(std::vector<float> depth, int width, int height, const render::Mat4& view,
               const render::Mat4& projection)
      : m_depth(std::move(depth)), m_w(width), m_h(height), m_proj(projection) {
    m_invView = view.inverse();
  }

  int width() const { return m_w; }
  int height() const { return m_h; }
  float depth(int x, int y) const {
    return x < 0 || y < 0 || x >= m_w || y >= m_h ? 0.0f : m_depth[std::size_t(y) * m_w + x];
  }
  bool water(int x, int y) const { return depth(x, y) > 0.0f; }

  Eigen::Vector3f viewPosition(int x, int y, float z) const {
    const float nx = (float(x) + 0.5f) / float(m_w) * 2.0f - 1.0f;
    const float ny = (float(y) + 0.5f) / float(m_h) * 2.0f - 1.0f;
    return {(nx + m_proj(0, 2)) * z / m_proj(0, 0), (ny + m_proj(1, 2)) * z / m_proj(1, 1), -z};
  }
  Eigen::Vector3f worldPosition(int x, int y) const {
    return (m_invView * viewPosition(x, y, depth(x, y)).homogeneous()).head<3>();
  }
  // world direction of the ray through pixel (x, y) and the eye
  Eigen::Vector3f rayDirection(int x, int y) const {
    return (m_invView.block<3, 3>(0, 0) * viewPosition(x, y, 1.0f)).normalized();
  }
  Eigen::Vector3f eye() const { return m_invView.block<3, 1>(0, 3); }

  // world normal of the water at (x, y), facing the eye; zero without water there
  Eigen::Vector3f normal(int x, int y) const {
    const float z = depth(x, y);
    if (z <= 0.0f)
      return Eigen::Vector3f::Zero();
    const Eigen::Vector3f c = viewPosition(x, y, z);
    auto diff = [&](int dx, int dy) -> Eigen::Vector3f {
      const float zf = depth(x + dx, y + dy), zb = depth(x - dx, y - dy);
      const Eigen::Vector3f f =
          zf > 0 ? Eigen::Vector3f(viewPosition(x + dx, y + dy, zf) - c) : Eigen::Vector3f::Zero();
      const Eigen::Vector3f b =
          zb > 0 ? Eigen::Vector3f(c - viewPosition(x - dx, y - dy, zb)) : Eigen::Vector3f::Zero();
      if (zf <= 0)
        return b;
      if (zb <= 0)
        return f;
      return std::abs(f.z()) < std::abs(b.z()) ? f : b;
    };
    Eigen::Vector3f n = diff(1, 0).cross(diff(0, 1));
    if (n.squaredNorm() == 0.0f)
      return Eigen::Vector3f::Zero();
    n.normalize();
    if (n.dot(-c) < 0.0f)
      n = -n;
    return m_invView.block<3, 3>(0, 0) * n;
  }

 private:
  std::vector<float> m_depth;
  int m_w, m_h;
  render::Mat4 m_proj, m_invView;
};

// The free surface of a resting tank as rendered: pixels whose view ray meets the simulated surface plane
// y = surfaceY inside `inner` (x-z, away from the walls).
struct RestingSurface {
  std::size_t pixels = 0;       // pixels that should show the free surface
  double coverage = 0;          // fraction of them with water
  double rmsNormalDegrees = 0;  // rms angle between the reconstructed normal and +y [deg]
  double meanHeightError = 0;   // mean rendered surface height minus surfaceY [m]
  double rmsHeightError = 0;    // rms of the same [m]
};

// Calls f(x, y, n) for each pixel whose view ray meets the plane y = surfaceY inside `inner` (x-z) and that
// shows water (n: its reconstructed normal); returns how many pixels meet the plane there, water or not.
template <class F>
std::size_t forEachRestingSurfacePixel(const DepthSurface& s, float surfaceY,
                                       const Eigen::AlignedBox2f& inner, F&& f) {
  std::size_t pixels = 0;
  const Eigen::Vector3f eye = s.eye();
  for (int y = 0; y < s.height(); ++y) {
    for (int x = 0; x < s.width(); ++x) {
      const Eigen::Vector3f d = s.rayDirection(x, y);
      if (d.y() >= -1e-4f)
        continue;
      const Eigen::Vector3f hit = eye + d * ((surfaceY - eye.y()) / d.y());
      if (!inner.contains(Eigen::Vector2f(hit.x(), hit.z())))
        continue;
      ++pixels;
      const Eigen::Vector3f n = s.normal(x, y);
      if (n.squaredNorm() > 0.0f)
        f(x, y, n);
    }
  }
  return pixels;
}

// the angle between a normal and the vertical [deg]
inline double angleFromVerticalDegrees(const Eigen::Vector3f& n) {
  return std::acos(std::clamp(double(std::abs(n.y())), 0.0, 1.0)) * 180.0 / M_PI;
}

inline RestingSurface measureRestingSurface(const DepthSurface& s, float surfaceY,
                                            const Eigen::AlignedBox2f& inner) {
  RestingSurface r;
  double angle2 = 0, dh = 0, dh2 = 0;
  std::size_t water = 0;
  r.pixels = forEachRestingSurfacePixel(s, surfaceY, inner, [&](int x, int y, const Eigen::Vector3f& n) {
    ++water;
    const double a = angleFromVerticalDegrees(n);
    angle2 += a * a;
    const double e = double(s.worldPosition(x, y).y() - surfaceY);
    dh += e;
    dh2 += e * e;
  });
  if (water) {
    r.coverage = double(water) / double(r.pixels);
    r.rmsNormalDegrees = std::sqrt(angle2 / double(water));
    r.meanHeightError = dh / double(water);
    r.rmsHeightError = std::sqrt(dh2 / double(water));
  }
  return r;
}

// How two renderings differ over the water (pixels where either has water).
struct WaterDifference {
  std::size_t waterPixels = 0;
  double meanLevels = 0;  // mean absolute channel difference over the water [0, 255]
  double fractionOver =
      0;  // fraction of the water's pixels with a channel differing by more than the tolerance
  double imageMeanLevels = 0;  // the same mean over the whole image
};

// `depthA` and `depthB` rows from the bottom, images rows from the top.
inline WaterDifference compareWater(const render::Image& a, const render::Image& b,
                                    const std::vector<float>& depthA, const std::vector<float>& depthB,
                                    int tolerance) {
  WaterDifference d;
  double sum = 0, all = 0;
  std::size_t over = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const std::size_t k = std::size_t(a.height - 1 - y) * a.width + x;
      int worst = 0, total = 0;
      for (int c = 0; c < 3; ++c) {
        const int e = std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c]));
        worst = std::max(worst, e);
        total += e;
      }
      all += total;
      if (depthA[k] <= 0.0f && depthB[k] <= 0.0f)
        continue;
      ++d.waterPixels;
      sum += total;
      over += worst > tolerance;
    }
  }
  d.meanLevels = d.waterPixels ? sum / (3.0 * double(d.waterPixels)) : 0.0;
  d.fractionOver = d.waterPixels ? double(over) / double(d.waterPixels) : 0.0;
  d.imageMeanLevels = all / (3.0 * double(a.width) * double(a.height));
  return d;
}

// Seams, rings and blobs are creases of the rendered surface: places where the normal turns by much over a
// few pixels inside the water. The crease fraction is the share of interior water pixels (all neighbours
// within `step` pixels are water and no depth jump larger than `maxJump` metres, so silhouettes and sheets
// in front of others do not count) whose normal differs from the normal `step` pixels right or up by more
// than `degrees`.
struct Creases {
  std::size_t interior = 0;
  double fraction = 0;
};

inline Creases measureCreases(const DepthSurface& s, int step, float degrees, float maxJump) {
  Creases c;
  std::size_t creased = 0;
  const float cosLimit = std::cos(degrees * float(M_PI) / 180.0f);
  for (int y = step; y < s.height() - step; ++y) {
    for (int x = step; x < s.width() - step; ++x) {
      const float z = s.depth(x, y);
      if (z <= 0.0f)
        continue;
      bool inside = true;
      for (int k = -step; k <= step && inside; ++k) {
        for (const auto& q : {Eigen::Vector2i(x + k, y), Eigen::Vector2i(x, y + k)}) {
          const float zq = s.depth(q.x(), q.y());
          inside = inside && zq > 0.0f && std::abs(zq - z) < maxJump * float(std::abs(k) + 1);
        }
      }
      if (!inside)
        continue;
      ++c.interior;
      const Eigen::Vector3f n = s.normal(x, y);
      const Eigen::Vector3f nr = s.normal(x + step, y), nu = s.normal(x, y + step);
      creased += n.dot(nr) < cosLimit || n.dot(nu) < cosLimit;
    }
  }
  c.fraction = c.interior ? double(creased) / double(c.interior) : 0.0;
  return c;
}

// Speckles of the image over the water: water pixels whose brightness (R + G + B) differs by more than
// `levels` from each of its four neighbours in the same direction while those agree with each other within
// `levels` (single pixels flickering between two looks, e.g. a tie of depths).
struct ImageSpeckles {
  std::size_t water = 0;
  std::size_t speckled = 0;
};

inline ImageSpeckles measureImageSpeckles(const render::Image& image, const std::vector<float>& depth,
                                          int levels) {
  ImageSpeckles c;
  auto brightness = [&](int x, int y) {
    const std::uint8_t* p = image.at(x, y);
    return int(p[0]) + int(p[1]) + int(p[2]);
  };
  for (int y = 1; y < image.height - 1; ++y) {
    for (int x = 1; x < image.width - 1; ++x) {
      if (depth[std::size_t(image.height - 1 - y) * image.width + x] <= 0.0f)
        continue;
      ++c.water;
      const int b = brightness(x, y);
      const int n[4] = {brightness(x - 1, y), brightness(x + 1, y), brightness(x, y - 1),
                        brightness(x, y + 1)};
      const int lo = std::min(std::min(n[0], n[1]), std::min(n[2], n[3]));
      const int hi = std::max(std::max(n[0], n[1]), std::max(n[2], n[3]));
      c.speckled += hi - lo <= levels && (b > hi + levels || b < lo - levels);
    }
  }
  return c;
}

}  // namespace fp::test
