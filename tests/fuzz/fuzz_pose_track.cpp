// Hand recordings (pose-track CSV): any bytes are loaded (no crash, no sanitizer report); a track that loads
// is sampled across and beyond its span and every sample must be finite.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "input/pose_track.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = fp::fuzz::writeInput(data, size, ".csv");
  try {
    const fp::input::PoseTrack track = fp::input::PoseTrack::load(path);
    const double duration = track.duration();
    for (int k = -1; k <= 9; ++k) {
      const fp::input::PoseSample s = track.sample(duration * k / 8.0);
      if (!s.position.allFinite() || !s.orientation.coeffs().allFinite() || !s.linearVelocity.allFinite() ||
          !s.angularVelocity.allFinite() || !std::isfinite(s.grip) || !std::isfinite(s.point))
        std::abort();  // a loaded track that samples to a non-finite pose: a bug of the loader or sampler
    }
  } catch (const fp::sim::InputError&) {
  }
  return 0;
}
