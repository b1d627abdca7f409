// The ThreadSanitizer stage's canary (built with FP_TSAN only; tests/CMakeLists.txt, docs/robustness.md,
// "Races"): proves that the stage can fail. Each mode runs two parallel calls of sim/parallel.h on two
// threads at once (a spin barrier holds each side until the other arrived, so both sides really run
// together):
//   clean   every body writes its own element, the caller reads them after the join: no report expected
//           (without the wrappers' annotations Debian's libtbb makes even this a report)
//   bodies  two bodies of one parallelFor write one int: the annotations must not order bodies
//   caller  a TaskGroup task and its caller write one int before wait(): the join edge comes only at wait()
//   reduce  two bodies of one parallelReduce write one int through the stack of TBB's reduction templates:
//           the suppressions of tests/tsan.supp must not cover our own frames under TBB's
// Exit status 0 when the run finished (TSan's own report, if any, decides the test), 3 when the two sides
// never met (the barrier gave up after 20 s), 2 on a bad argument.
#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

#include "sim/parallel.h"

namespace {

/// two parties; arrive() returns false when the other did not come within 20 s
class Meeting {
 public:
  bool arrive() {
    m_count.fetch_add(1);
    const auto giveUp = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (m_count.load() < 2) {
      if (std::chrono::steady_clock::now() > giveUp)
        return false;
      std::this_thread::yield();
    }
    return true;
  }

 private:
  std::atomic<int> m_count{0};
};

int g_shared = 0;  // the racy int of the bodies, caller and reduce modes
std::atomic<bool> g_met{true};

void meet(Meeting& m) {
  if (!m.arrive())
    g_met = false;
}

int runClean() {
  Meeting m;
  std::vector<int> out(2, 0);
  fp::sim::parallelFor(0, 2, [&](int i) {
    meet(m);
    out[std::size_t(i)] = i + 1;
  });
  return out[0] + out[1] == 3 ? 0 : 1;
}

int runBodies() {
  Meeting m;
  fp::sim::parallelFor(0, 2, [&](int i) {
    meet(m);
    g_shared = i;  // the race
  });
  return 0;
}

int runCaller() {
  Meeting m;
  fp::sim::TaskGroup group;
  group.run([&] {
    meet(m);
    g_shared = 1;  // the race
  });
  meet(m);
  g_shared = 2;  // the race
  group.wait();
  return 0;
}

int runReduce() {
  Meeting m;
  using Range = tbb::blocked_range<int>;
  const int sum = fp::sim::parallelReduce(
      Range(0, 2, 1), 0,
      [&](const Range& r, int acc) {
        meet(m);
        g_shared = r.begin();  // the race
        return acc + r.size();
      },
      [](int a, int b) { return a + b; });
  return sum == 2 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tsan_canary clean|bodies|caller|reduce\n");
    return 2;
  }
  tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
  int status = 2;
  if (std::strcmp(argv[1], "clean") == 0)
    status = runClean();
  else if (std::strcmp(argv[1], "bodies") == 0)
    status = runBodies();
  else if (std::strcmp(argv[1], "caller") == 0)
    status = runCaller();
  else if (std::strcmp(argv[1], "reduce") == 0)
    status = runReduce();
  else
    std::fprintf(stderr, "tsan_canary: unknown mode %s\n", argv[1]);
  if (!g_met) {
    std::fprintf(stderr, "tsan_canary: the two sides never ran together\n");
    return 3;
  }
  // reading the racy int keeps its stores (a global nothing reads is optimised away, and so is the race)
  std::printf("tsan_canary %s: done (%d)\n", argv[1], g_shared);
  return status;
}
