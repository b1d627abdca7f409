// Joint recordings of tracked hands (the headset's CSV): any bytes are loaded (no crash, no sanitizer
// report); a track that loads is sampled across and beyond its span, every valid hand's joints must be finite
// with a positive radius, and the hand's colliders are placed on them (input::partPosesFromJoints) without a
// NaN.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "input/joint_track.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = fp::fuzz::writeInput(data, size, ".csv");
  try {
    const fp::input::JointTrack track = fp::input::JointTrack::load(path);
    const double duration = track.duration();
    for (int k = -1; k <= 9; ++k) {
      const fp::input::JointFrame frame = track.sample(duration * k / 8.0);
      for (const fp::input::HandJoints& hand : frame.hands) {
        if (!hand.valid)
          continue;
        for (const fp::input::JointPose& j : hand.joint) {
          if (!j.position.allFinite() || !j.orientation.coeffs().allFinite() || !std::isfinite(j.radius) ||
              !(j.radius > 0.0))
            std::abort();  // a loaded track that samples to a bad joint: a bug of the loader or sampler
        }
        for (const fp::input::PartPose& part : fp::input::partPosesFromJoints(hand)) {
          if (!part.position.allFinite() || !part.orientation.coeffs().allFinite())
            std::abort();
        }
      }
    }
  } catch (const fp::sim::InputError&) {
  }
  return 0;
}
