#pragma once
/// Saved simulation state (after SPlisHSPlasH's Tests/ReadWriteState): a versioned little-endian binary file
/// holding everything a step reads that is not rebuilt from the scene, so that a run resumed from it is
/// bit-identical with the uninterrupted run on one thread:
///
///   magic "FPSTATE\0", u32 version, u64 scene hash, mode, time, step size, step counter, boundary impulse,
///   every parameter of the table (live edits included), the collider poses (the hand), every field of the
///   fluid particles in their current order, the boundary particles, the run statistics, the owner's
///   extra numbers (the hand pose of the app), and an FNV-1a checksum of all bytes before it.
///
/// Random choices are counter-based hashes of (seed, particle id, step), so the seed (a parameter) and the
/// step counter are the whole of the random state. A file that is truncated, corrupt, of another version or
/// of another scene is refused with a one-line StateError and the simulation is left as it was.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/scene.h"
#include "sim/types.h"

namespace fp::sim {

class Simulation;

/// A saved state that cannot be used; the message is one line.
class StateError : public InputError {
 public:
  explicit StateError(const std::string& what) : InputError(what) {}
};

/// version of the format written by this build (3: the uniform modes store no adaptivity fields, and static
/// boundary particles no velocity nor local position; 4: the run's fastest particle, its time, the caged,
/// held and time-level-1 particle-steps, so that a resumed run reports the whole run's; files of other
/// versions are refused with the version)
constexpr std::uint32_t kStateVersion = 4;

/// FNV-1a hash of what a simulation is built from: domain, fluid blocks, colliders (meshes included),
/// parameters as loaded, mode and frame rate (not the name nor the default run length)
std::uint64_t sceneHash(const SceneDesc& scene);

/// The state of `sim`, with `extra` numbers of its owner (e.g. the hand pose), as the bytes of a state file.
std::string encodeState(const Simulation& sim, const std::vector<double>& extra = {});

/// Restores a state encoded by encodeState into `sim`, which must be built from the same scene. Returns the
/// owner's extra numbers. Throws StateError (sim unchanged) for truncated, corrupt, foreign or invalid
/// bytes; `verifyChecksum` = false skips only the checksum (for the fuzzer, which would not get past it).
std::vector<double> decodeState(std::string_view bytes, Simulation& sim, bool verifyChecksum = true);

/// Writes encodeState(sim, extra) to `path`; throws InputError when it cannot be written completely.
void saveState(const std::string& path, const Simulation& sim, const std::vector<double>& extra = {});

/// Reads `path` and restores it into `sim` (see decodeState); throws StateError naming the file.
std::vector<double> loadState(const std::string& path, Simulation& sim);

}  // namespace fp::sim
