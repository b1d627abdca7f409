#include "render/legend.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Core>

namespace fp::render {

std::vector<float> legendVertices(ColorField field, const ColorRange& range, int width, int height) {
  // stb_easy_font glyphs are about 7 px tall, scaled up on large images
  const float scale = std::max(1.0f, std::round(float(height) / 360.0f));
  std::vector<float> v;
  auto quad = [&](float x0, float y0, float x1, float y1, const Eigen::Vector4f& c, float t0, float t1) {
    const float pts[6][3] = {{x0, y0, t0}, {x1, y0, t1}, {x1, y1, t1},
                             {x0, y0, t0}, {x1, y1, t1}, {x0, y1, t0}};
    for (const auto& p : pts)
      v.insert(v.end(), {p[0], p[1], c.x(), c.y(), c.z(), c.w(), p[2]});
  };
  auto text = [&](float x, float y, const std::string& s, const Eigen::Vector4f& c) {
    std::vector<float> buffer(s.size() * 16 * 40);  // stb_easy_font: at most ~40 quads a character
    const int quads = stb_easy_font_print(0.0f, 0.0f, const_cast<char*>(s.c_str()), nullptr, buffer.data(),
                                          int(buffer.size() * sizeof(float)));
    const float* q = buffer.data();
    for (int k = 0; k < quads; ++k, q += 16)  // 4 vertices of x, y, z, rgba8 each
      quad(x + scale * q[0], y + scale * q[1], x + scale * q[8], y + scale * q[9], c, -1.0f, -1.0f);
  };
  auto label = [](float value) {
    char s[32];
    std::snprintf(s, sizeof(s), std::abs(value) < 0.1f && value != 0.0f ? "%.3f" : "%.2g", double(value));
    return std::string(s);
  };
  const char* title = colorFieldLabel(field);
  const float pad = 8.0f * scale, barH = 12.0f * scale, line = 10.0f * scale;
  const float barW = std::min(std::max(160.0f, float(stb_easy_font_width(const_cast<char*>(title)))) * scale,
                              float(width) - 4.0f * pad);
  const float boxW = barW + 2.0f * pad;
  const float x0 = std::max(0.0f, float(width) - pad - boxW);
  const float y0 = float(height) - pad - (barH + 2.0f * line + 2.0f * pad);
  const Eigen::Vector4f white(1.0f, 1.0f, 1.0f, 1.0f);
  quad(x0, y0, x0 + boxW, float(height) - pad, Eigen::Vector4f(0.0f, 0.0f, 0.0f, 0.55f), -1, -1);
  text(x0 + pad, y0 + pad, title, white);
  const float barY = y0 + pad + line + 2.0f * scale;
  quad(x0 + pad, barY, x0 + pad + barW, barY + barH, white, 0.0f, 1.0f);
  const std::string lo = label(range.lo), hi = label(range.hi);
  text(x0 + pad, barY + barH + 3.0f * scale, lo, white);
  text(x0 + pad + barW - float(stb_easy_font_width(const_cast<char*>(hi.c_str()))) * scale,
       barY + barH + 3.0f * scale, hi, white);
  return v;
}

}  // namespace fp::render
