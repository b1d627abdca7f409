#include "sim/ply_writer.h"

#include <cstring>
#include <fstream>
#include <sstream>

namespace fp::sim {

namespace {
constexpr const char* kProperties[] = {"float x",  "float y",    "float z",       "float vx",   "float vy",
                                       "float vz", "float mass", "float support", "uint flags", "uint id"};
constexpr std::size_t kRecordBytes = 8 * sizeof(float) + 2 * sizeof(std::uint32_t);
static_assert(sizeof(float) == 4, "PLY floats are 32-bit");

void put(char*& out, const void* value, std::size_t bytes) {
  std::memcpy(out, value, bytes);
  out += bytes;
}
}  // namespace

void writePly(const std::string& path, const ParticleSet& p) {
  std::ofstream file(path, std::ios::binary);
  if (!file)
    throw InputError(path + ": cannot open for writing");
  file << "ply\nformat binary_little_endian 1.0\ncomment FluidPlaying particles\n";
  file << "element vertex " << p.size() << "\n";
  for (const char* prop : kProperties)
    file << "property " << prop << "\n";
  file << "end_header\n";
  std::string buffer(p.size() * kRecordBytes, '\0');
  char* out = buffer.data();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const float values[8] = {float(p.x[i].x()), float(p.x[i].y()), float(p.x[i].z()), float(p.v[i].x()),
                             float(p.v[i].y()), float(p.v[i].z()), float(p.m[i]),     float(p.H[i])};
    put(out, values, sizeof(values));
    put(out, &p.flags[i], sizeof(std::uint32_t));
    put(out, &p.id[i], sizeof(std::uint32_t));
  }
  file.write(buffer.data(), std::streamsize(buffer.size()));
  if (!file)
    throw InputError(path + ": write failed");
}

ParticleSet readPly(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file)
    throw InputError(path + ": cannot open");
  std::string line;
  std::size_t count = 0;
  std::size_t properties = 0;
  bool binary = false;
  while (std::getline(file, line)) {
    if (line == "end_header")
      break;
    std::istringstream s(line);
    std::string word;
    s >> word;
    if (word == "format")
      binary = line.find("binary_little_endian") != std::string::npos;
    if (word == "element") {
      std::string kind;
      s >> kind >> count;
    }
    if (word == "property")
      ++properties;
  }
  if (!binary || properties != std::size(kProperties)) {
    throw InputError(path + ": not a FluidPlaying particle PLY");
  }
  std::string buffer(count * kRecordBytes, '\0');
  file.read(buffer.data(), std::streamsize(buffer.size()));
  if (std::size_t(file.gcount()) != buffer.size())
    throw InputError(path + ": truncated");
  ParticleSet p;
  const char* in = buffer.data();
  for (std::size_t i = 0; i < count; ++i) {
    float values[8];
    std::uint32_t flags, id;
    std::memcpy(values, in, sizeof(values));
    std::memcpy(&flags, in + sizeof(values), 4);
    std::memcpy(&id, in + sizeof(values) + 4, 4);
    in += kRecordBytes;
    p.add(Vec3(values[0], values[1], values[2]), Vec3(values[3], values[4], values[5]), values[6], values[7],
          0);
    p.flags.back() = flags;
    p.id.back() = id;
  }
  return p;
}

}  // namespace fp::sim
