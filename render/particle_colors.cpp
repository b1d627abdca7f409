#include "render/particle_colors.h"

#include <algorithm>
#include <cmath>

namespace fp::render {

namespace {
constexpr ColorField kFields[] = {ColorField::MassLevel, ColorField::Phi,   ColorField::Omega,
                                  ColorField::Nu,        ColorField::Speed, ColorField::DensityError};
}  // namespace

const char* colorFieldName(ColorField field) {
  switch (field) {
    case ColorField::MassLevel:
      return "mass";
    case ColorField::Phi:
      return "phi";
    case ColorField::Omega:
      return "omega";
    case ColorField::Nu:
      return "nu";
    case ColorField::Speed:
      return "speed";
    case ColorField::DensityError:
      return "density-error";
  }
  return "?";
}

std::optional<ColorField> parseColorField(std::string_view name) {
  for (ColorField f : kFields) {
    if (name == colorFieldName(f))
      return f;
  }
  return std::nullopt;
}

const char* colorFieldNames() {
  return "mass, phi, omega, nu, speed, density-error";
}

const char* colorFieldLabel(ColorField field) {
  switch (field) {
    case ColorField::MassLevel:
      return "mass level m/m_fine";
    case ColorField::Phi:
      return "R_phi (visible level)";
    case ColorField::Omega:
      return "R_omega (vorticity level)";
    case ColorField::Nu:
      return "R_nu (velocity difference level)";
    case ColorField::Speed:
      return "speed [m/s]";
    case ColorField::DensityError:
      return "density error rho/rho0 - 1";
  }
  return "?";
}

ColorRange defaultColorRange(ColorField field, const sim::SimParams& params) {
  switch (field) {
    case ColorField::MassLevel:
      return {1.0f, float(std::max(2.0, params.massRatio)), true};
    case ColorField::Phi:
      return {0.0f, 1.0f, false};
    case ColorField::Omega:
      return {1.0f, float(std::max(2.0, params.vorticityRmax)), false};
    case ColorField::Nu:
      return {1.0f, float(std::max(2.0, params.velocityDifferenceRmax)), false};
    case ColorField::Speed:
      return {0.0f, 3.0f, false};
    case ColorField::DensityError:
      return {-0.02f, 0.02f, false};
  }
  return {};
}

float colorFieldValue(ColorField field, const sim::ParticleSet& p, std::size_t i, const FieldScales& scales) {
  switch (field) {
    case ColorField::MassLevel:
      return float(double(p.m[i]) / scales.fineMass);
    case ColorField::Phi:
      return p.levelPhi[i];
    case ColorField::Omega:
      return p.levelOmega[i];
    case ColorField::Nu:
      return p.levelNu[i];
    case ColorField::Speed:
      return p.v[i].norm();
    case ColorField::DensityError:
      return float(double(p.rho[i]) / scales.restDensity - 1.0);
  }
  return 0.0f;
}

float normalizeColorValue(float value, const ColorRange& range) {
  float t = 0.0f;
  if (range.log && range.lo > 0.0f) {
    t = (std::log(std::max(value, range.lo)) - std::log(range.lo)) /
        (std::log(range.hi) - std::log(range.lo));
  } else {
    t = (value - range.lo) / (range.hi - range.lo);
  }
  return std::isfinite(t) ? std::clamp(t, 0.0f, 1.0f) : 0.0f;
}

}  // namespace fp::render
