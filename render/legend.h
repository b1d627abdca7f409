#pragma once
/// The particle view's colour legend: a title, the colour bar and its two end values, as overlay triangles
/// (shaders/overlay.vert) in the bottom-right corner of the view, where the window's panel (top left, full
/// height at most) never is.

#include <vector>

#include "render/particle_colors.h"

namespace fp::render {

/// Overlay vertices (pixel x, y from the top-left, rgba, colour-map coordinate or -1), 7 floats each, of the
/// legend of `field` over `range` in a width x height view [px].
std::vector<float> legendVertices(ColorField field, const ColorRange& range, int width, int height);

}  // namespace fp::render
