// Saved states: any bytes are decoded into a small simulation with the checksum check off (the fuzzer would
// not get past it); a state that is accepted must step without a crash or a sanitizer report.
// FP_FUZZ_WRITE_SEED=FILE writes a valid state of the fuzzer's scene to FILE and exits: the seed corpus
// (tests/fuzz/state/) stays valid as the format or the parameter table change. FP_FUZZ_CHECK_SEED=FILE
// decodes FILE with every check on, steps it once and exits 0, or 1 with the reason (CI runs it).

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string_view>

#include "sim/simulation.h"
#include "sim/state_io.h"
#include "tests/fuzz/fuzz_state_scene.h"

namespace {

fp::sim::Simulation& simulation() {
  static fp::sim::Simulation sim = [] {
    fp::sim::Simulation s(fp::test::fuzzStateScene());
    for (int k = 0; k < 3; ++k)
      s.step();
    return s;
  }();
  return sim;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* seed = std::getenv("FP_FUZZ_WRITE_SEED")) {
    fp::sim::saveState(seed, simulation(), {0.5, 0.25});
    std::cout << "wrote " << seed << "\n";
    std::exit(0);
  }
  if (const char* seed = std::getenv("FP_FUZZ_CHECK_SEED")) {
    // CI checks that the seed still decodes in full (checksum included): a seed rejected at the header or
    // the scene hash leaves the fuzzer nothing but the header to mutate
    fp::sim::Simulation sim = simulation();
    try {
      fp::sim::loadState(seed, sim);
      sim.step();
    } catch (const std::exception& e) {
      std::cerr << "the state seed is stale, write a new one with FP_FUZZ_WRITE_SEED: " << e.what() << "\n";
      std::exit(1);
    }
    std::cout << "the state seed " << seed << " decodes and steps\n";
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // a copy, so every input starts from the same simulation
  fp::sim::Simulation sim = simulation();
  try {
    fp::sim::decodeState(std::string_view(reinterpret_cast<const char*>(data), size), sim, false);
    sim.step();
  } catch (const fp::sim::InputError&) {
  } catch (const fp::sim::InstabilityError&) {
  }
  return 0;
}
