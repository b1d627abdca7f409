#pragma once
/// The per-particle quantities the inspection view colours spheres by, with their names and ranges.

#include <optional>
#include <string_view>

#include "sim/params.h"
#include "sim/particle_set.h"

namespace fp::render {

/// What the particle view colours by.
enum class ColorField {
  MassLevel,     ///< m / m_fine in [1, mass_ratio], log scale
  Phi,           ///< visible level R_phi in [0, 1]
  Omega,         ///< vorticity level R_omega in [1, Rmax_omega]
  Nu,            ///< velocity-difference level R_nu in [1, Rmax_nu]
  Speed,         ///< |v| [m/s]
  DensityError,  ///< rho / rho0 - 1 [-]
};

/// the command-line name: mass, phi, omega, nu, speed, density-error
const char* colorFieldName(ColorField field);
/// the field named `name`, or nothing
std::optional<ColorField> parseColorField(std::string_view name);
/// "mass, phi, omega, nu, speed, density-error", for messages
const char* colorFieldNames();
/// the legend's title, e.g. "R_nu (velocity difference level)"
const char* colorFieldLabel(ColorField field);

/// A value range mapped onto the colour map.
struct ColorRange {
  float lo = 0.0f;   ///< value at the start of the map
  float hi = 1.0f;   ///< value at the end of the map, > lo
  bool log = false;  ///< map log(value) (lo > 0)
};

/// the range of a field implied by the parameters (levels: [1, Rmax]; speed: [0, 3] m/s; density error: +-2%)
ColorRange defaultColorRange(ColorField field, const sim::SimParams& params);

/// What a field value needs besides the particle.
struct FieldScales {
  double fineMass = 1.0;        ///< m_fine, mass of level 1 [kg], > 0
  double restDensity = 1000.0;  ///< rho0 [kg/m^3], > 0
};

/// the value of `field` for particle i
float colorFieldValue(ColorField field, const sim::ParticleSet& particles, std::size_t i,
                      const FieldScales& scales);
/// `value` mapped to [0, 1] over `range`, clamped
float normalizeColorValue(float value, const ColorRange& range);

}  // namespace fp::render
