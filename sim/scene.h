#pragma once
/// Description of a scene: the domain, the fluid to create, the colliders and the parameters. Plain data, so
/// a test builds one in a few lines and the engine fills one from a JSON file.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/mesh.h"
#include "sim/params.h"
#include "sim/types.h"

namespace fp::sim {

/// How the resolution is chosen (docs/method.md, Levels). The first two are uniform references; `Surface` is
/// the surface-only adaptivity of Winchenbach et al. 2017 (R_omega = R_nu = 1); `FluidPlaying` uses all three
/// levels.
enum class AdaptivityMode { UniformLow, UniformHigh, Surface, FluidPlaying };

/// the scene-file and command-line name of a mode: uniform-low, uniform-high, surface, fluidplaying
inline const char* modeName(AdaptivityMode m) {
  switch (m) {
    case AdaptivityMode::UniformLow:
      return "uniform-low";
    case AdaptivityMode::UniformHigh:
      return "uniform-high";
    case AdaptivityMode::Surface:
      return "surface";
    case AdaptivityMode::FluidPlaying:
      return "fluidplaying";
  }
  return "?";
}

/// the mode named `name`, or nothing
inline std::optional<AdaptivityMode> parseMode(std::string_view name) {
  for (AdaptivityMode m : {AdaptivityMode::UniformLow, AdaptivityMode::UniformHigh, AdaptivityMode::Surface,
                           AdaptivityMode::FluidPlaying}) {
    if (name == modeName(m))
      return m;
  }
  return std::nullopt;
}

/// the names of all modes, for messages: "uniform-low, uniform-high, surface, fluidplaying"
inline const char* modeNames() {
  return "uniform-low, uniform-high, surface, fluidplaying";
}

/// Shape of a collider, in its local frame (centred at the origin).
enum class ShapeType { Box, Sphere, Capsule, Mesh };

/// A rigid collider sampled with boundary particles (Akinci et al. 2012). Static when it has no velocity and
/// is not driven; kinematic otherwise (its pose moves with the given velocities, or is set from outside every
/// step).
struct ColliderDesc {
  std::string name;                          ///< for messages and the GUI
  ShapeType shape = ShapeType::Box;          ///< local shape
  Vec3d halfExtents{0.5, 0.5, 0.5};          ///< box half sizes [m]
  double radius = 0.1;                       ///< sphere and capsule radius [m]
  double halfLength = 0.1;                   ///< capsule: half distance between the cap centres, local y [m]
  std::shared_ptr<const TriangleMesh> mesh;  ///< mesh shape, already scaled, local frame
  bool container = false;                    ///< box only: the fluid is inside, the walls face inwards
  double headroom = 0.0;                     ///< container only: walls and lid raised this far, unseen [m]
  Vec3d position{0.0, 0.0, 0.0};             ///< origin of the local frame in the world [m]
  Quatd orientation = Quatd::Identity();     ///< rotation local -> world
  Vec3d linearVelocity{0.0, 0.0, 0.0};       ///< constant velocity [m/s]
  Vec3d angularVelocity{0.0, 0.0, 0.0};      ///< constant angular velocity about `position`, world [rad/s]
  bool driven = false;                       ///< the pose is set from outside every step (hand)

  /// true when the collider moves
  bool kinematic() const {
    return driven || linearVelocity.squaredNorm() > 0.0 || angularVelocity.squaredNorm() > 0.0;
  }
};

/// An axis-aligned block filled with fluid particles on a regular lattice of spacing 2r.
struct FluidBlock {
  Aabb box;                       ///< extent [m]
  Vec3d velocity{0.0, 0.0, 0.0};  ///< initial velocity [m/s]
};

/// Everything needed to start a simulation.
struct SceneDesc {
  std::string name = "scene";                      ///< shown in messages
  Aabb domain{Vec3d(-1, -1, -1), Vec3d(1, 1, 1)};  ///< a fluid particle leaving it is an instability [m]
  SimParams params;                                ///< simulation parameters
  std::vector<FluidBlock> fluid;                   ///< fluid to create
  std::vector<ColliderDesc> colliders;             ///< walls and moving bodies
  double simTime = 2.0;                            ///< default simulated time of a run [s]
  double frameRate = 60.0;  ///< frames per simulated second for export and rendering [1/s]
  AdaptivityMode mode = AdaptivityMode::UniformHigh;  ///< resolution mode
};

}  // namespace fp::sim
