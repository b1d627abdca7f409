// Scene files: any bytes are parsed (no crash, no hang, no sanitizer report); what parses is a scene whose
// small cases are built into a simulation and stepped once.

#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/scene_loader.h"
#include "sim/simulation.h"

namespace {

/// fluid lattice points and boundary samples, roughly: only small scenes are built, so an input cannot make
/// the fuzzer spend seconds or gigabytes on a legitimate but large scene
double roughParticleCount(const fp::sim::SceneDesc& scene) {
  const double d = 2.0 * scene.params.particleRadius;
  double count = 0.0;
  for (const fp::sim::FluidBlock& b : scene.fluid)
    count += (b.box.sizes() / d).prod();
  for (const fp::sim::ColliderDesc& c : scene.colliders) {
    const double size = c.shape == fp::sim::ShapeType::Box ? 2.0 * c.halfExtents.maxCoeff()
                        : c.shape == fp::sim::ShapeType::Mesh
                            ? (c.mesh ? c.mesh->bounds().sizes().maxCoeff() : 0.0)
                            : 2.0 * (c.radius + c.halfLength);
    count += 6.0 * (size / d) * (size / d);
  }
  return count;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fp::sim::SceneDesc scene;
  try {
    scene = fp::engine::parseScene(text, "fuzz.json", FP_SOURCE_DIR "/assets/scenes");
  } catch (const fp::sim::InputError&) {
    return 0;
  }
  const double count = roughParticleCount(scene);
  if (!(count < 3000.0))
    return 0;
  try {
    fp::sim::Simulation simulation(scene);
    simulation.step();
  } catch (const fp::sim::InputError&) {
  } catch (const fp::sim::InstabilityError&) {
  }
  return 0;
}
