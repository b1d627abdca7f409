#include "render/particle_colors.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace fp::render {

namespace {
// One row per colour field: its command-line name and its legend label.
struct FieldInfo {
  ColorField field;
  const char* name;
  const char* label;
};
constexpr FieldInfo kFields[] = {
    {ColorField::MassLevel, "mass", "mass level m/m_fine"},
    {ColorField::Phi, "phi", "R_phi (visible level)"},
    {ColorField::Omega, "omega", "R_omega (vorticity level)"},
    {ColorField::Nu, "nu", "R_nu (velocity difference level)"},
    {ColorField::Speed, "speed", "speed [m/s]"},
    {ColorField::DensityError, "density-error", "density error rho/rho0 - 1"},
};

const FieldInfo* findField(ColorField field) {
  for (const FieldInfo& f : kFields) {
    if (f.field == field)
      return &f;
  }
  return nullptr;
}

std::string joinedNames() {
  std::string names;
  for (const FieldInfo& f : kFields)
    names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
}
}  // namespace

const char* colorFieldName(ColorField field) {
  const FieldInfo* f = findField(field);
  return f ? f->name : "?";
}

std::optional<ColorField> parseColorField(std::string_view name) {
  for (const FieldInfo& f : kFields) {
    if (name == f.name)
      return f.field;
  }
  return std::nullopt;
}

const char* colorFieldNames() {
  static const std::string names = joinedNames();
  return names.c_str();
}

const char* colorFieldLabel(ColorField field) {
  const FieldInfo* f = findField(field);
  return f ? f->label : "?";
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
      return p.levelPhiOf(i);
    case ColorField::Omega:
      return p.levelOmegaOf(i);
    case ColorField::Nu:
      return p.levelNuOf(i);
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
