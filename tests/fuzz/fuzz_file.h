#pragma once
// The loaders of presets and hand recordings read files: the fuzzers write each input to a file of their own
// (in /dev/shm when there is one, so no disk is involved) and hand the loader its path.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace fp::fuzz {

/// writes `data` to this process's scratch file and returns its path
inline const std::string& writeInput(const std::uint8_t* data, std::size_t size, const char* extension) {
  static const std::string path = [extension] {
    const std::filesystem::path dir =
        std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    return (dir / ("fp_fuzz_" + std::to_string(::getpid()) + extension)).string();
  }();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

}  // namespace fp::fuzz
