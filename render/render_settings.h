#pragma once
/// What the renderer draws and how, as a parameter table like the simulation's (sim/param_table.h): each
/// user-facing setting declared once, in render/render_settings.cpp, with key, group, unit, range, default
/// and description, so that the panel, the command line (`--set KEY=VALUE`) and files share it.

#include <Eigen/Core>

#include "render/particle_colors.h"
#include "sim/param_table.h"

namespace fp::render {

/// What is drawn and how; every member may change between frames. The members without a default here are
/// declared in the table (RenderSettingsTable), which a default-constructed RenderSettings takes its values
/// from; the others are internal (benchmarks, tuning).
struct RenderSettings {
  /// every table setting at its default
  RenderSettings();

  enum class View { Fluid, Particles };
  View view;                  ///< screen-space water, or coloured spheres for inspection
  ColorField colorField;      ///< the quantity of the particle view
  bool highlightSplits;       ///< tint split children red
  float highlightDuration;    ///< how long after its split a child is tinted [s], > 0
  float highlightStrength;    ///< red density of a fresh child, per particle radius of thickness
  bool showSpray;             ///< draw splash particles
  bool showColliders;         ///< draw floor, container and bodies
  int filterIterations;       ///< narrow-range filter passes (each horizontal + vertical), >= 0
  float filterRadius;         ///< filter half-width in fine particle radii, > 0
  float filterMaxPixels;      ///< cap on the filter half-width [px]
  float filterRange;          ///< depth range kept by the filter, in fine particle radii
  bool filterHalfResolution;  ///< filter the depth at half resolution (else at full resolution)
  float thicknessBlur;  ///< sigma of the thickness blur in fine radii, each filter pass (half resolution; 0:
                        ///< off)
  float wetReach;       ///< spheres whose centre is this many radii from a side of the glass wet it (0: off)
  float refraction;     ///< screen-space refraction offset at full thickness [view units]

  bool autoRange = true;  ///< particle view: range from the parameters, else colorRange
  ColorRange colorRange;  ///< particle view range when autoRange is off
  Eigen::Vector3f absorption{2.2f, 0.55f, 0.3f};  ///< Beer-Lambert coefficient per channel [1/m]
  int filterMaxTaps = 12;  ///< most sample pairs a pixel and filter pass; a wider filter strides, >= 1
  /// fill the pinholes of the surface: a gap between spheres through which a pixel sees water far behind
  /// (or nothing) takes the filtered surface around it (at half resolution only)
  bool fillHoles = true;
  bool profile = false;  ///< finish each pass and time it (slower; for the benchmark)
};

/// The table of the render settings, immutable. For the command line:
///   /// applies "KEY=VALUE" (e.g. "view=particles", "color_field=omega", "highlight_duration=1"); "" or the
///   /// table's one-line error (unknown key with suggestion, type, range)
///   std::string error = RenderSettingsTable::get().assign(settings, "view=particles");
///   /// several, in order
///   std::string error = RenderSettingsTable::get().assignAll(settings, {"show_spray=off",
///   "filter_iterations=3"});
class RenderSettingsTable : public sim::ParamTableOf<RenderSettings> {
 public:
  /// the renderer's table
  static const RenderSettingsTable& get();

 private:
  RenderSettingsTable();
};

}  // namespace fp::render
