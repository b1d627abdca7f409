#pragma once
/// Binary PLY export of the fluid particles (position, velocity, mass, support radius, flags, id), a format
/// that ParaView, Blender and Houdini open.

#include <string>

#include "sim/particle_set.h"

namespace fp::sim {

/// Writes the particles as binary little-endian PLY vertices with float x y z vx vy vz mass support and uint
/// flags id. Throws InputError naming the file when it cannot be written.
void writePly(const std::string& path, const ParticleSet& particles);

/// Particles read back from a PLY written by writePly (for tests and tools). Throws InputError on a bad file.
ParticleSet readPly(const std::string& path);

}  // namespace fp::sim
