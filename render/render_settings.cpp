#include "render/render_settings.h"

namespace fp::render {

// The one declaration of every user-facing render setting. Panel order; every setting is live.
RenderSettingsTable::RenderSettingsTable() : sim::ParamTableOf<RenderSettings>("render setting") {
  using R = RenderSettings;
  std::vector<std::string> fields;
  for (ColorField f : {ColorField::MassLevel, ColorField::Phi, ColorField::Omega, ColorField::Nu,
                       ColorField::Speed, ColorField::DensityError}) {
    if (int(f) != int(fields.size()))
      throw std::logic_error("ColorField values must be 0, 1, 2, ... in this order");
    fields.push_back(colorFieldName(f));
  }
  addChoice<&R::view>("view", "view", "screen-space water, or coloured spheres for inspection", true,
                      {"fluid", "particles"}, int(R::View::Fluid));
  addChoice<&R::colorField>("color_field", "view", "the quantity the particle view colours by", true,
                            std::move(fields), int(ColorField::Nu));
  add("highlight_splits", "view", "-", 0, 1, true, "tint split children red", &R::highlightSplits, true);
  add("highlight_duration", "view", "s", 0.01, 10.0, true, "how long after its split a child is tinted",
      &R::highlightDuration, 0.5f);
  add("highlight_strength", "view", "-", 0.0, 10.0, true,
      "red density of a fresh child, per particle radius of thickness", &R::highlightStrength, 1.0f);
  add("show_spray", "view", "-", 0, 1, true, "draw splash particles", &R::showSpray, true);
  add("show_colliders", "view", "-", 0, 1, true, "draw floor, container and bodies", &R::showColliders, true);
  add("filter_iterations", "water", "-", 0, 10, true,
      "narrow-range filter passes (each horizontal + vertical)", &R::filterIterations, 2);
  add("filter_radius", "water", "r", 0.1, 20.0, true, "filter half-width in fine particle radii",
      &R::filterRadius, 5.0f);
  add("filter_max_pixels", "water", "px", 1.0, 256.0, true, "cap on the filter half-width",
      &R::filterMaxPixels, 64.0f);
  add("filter_range", "water", "r", 0.1, 20.0, true, "depth range kept by the filter in fine particle radii",
      &R::filterRange, 15.0f);
  add("filter_half_resolution", "water", "-", 0, 1, true,
      "filter the depth at half resolution (cheaper, smoother at high resolution)", &R::filterHalfResolution,
      true);
  add("thickness_blur", "water", "r", 0.0, 20.0, true,
      "sigma of the thickness blur in fine radii, each filter pass at half resolution (0: off)",
      &R::thicknessBlur, 2.0f);
  add("wet_reach", "water", "r", 0.0, 10.0, true,
      "spheres this many radii from a side of the glass wet it (flat water at the glass; 0: off)",
      &R::wetReach, 2.0f);
  add("refraction", "water", "-", 0.0, 1.0, true,
      "screen-space refraction offset at full thickness (view units)", &R::refraction, 0.04f);
}

const RenderSettingsTable& RenderSettingsTable::get() {
  static const RenderSettingsTable table;
  return table;
}

RenderSettings::RenderSettings() {
  RenderSettingsTable::get().applyDefaults(*this);
}

}  // namespace fp::render
