#pragma once
/// The simulation's parallel loops: TBB's parallel_for, parallel_reduce and parallel_deterministic_reduce
/// with the same arguments, and nothing else in sim/ calls TBB's loops directly (tests/architecture checks
/// it).
///
/// Why a wrapper: Debian's libtbb is not built with ThreadSanitizer, so TSan cannot see that a worker's loop
/// body runs after the caller spawned it, nor that the caller continues after every body finished; every
/// write the caller made before a loop and every write of a body then reads as a data race
/// (docs/robustness.md, "Races"). Built with -fsanitize=thread the wrappers state those two edges themselves:
/// the caller releases a token before the TBB call and each body (and each join of a reduction) acquires it
/// on entry; each body releases a second token on exit and the caller (and the next join) acquires it. In
/// every other build the annotations compile to nothing and the wrappers are the TBB calls.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <utility>

#if defined(__SANITIZE_THREAD__)
#define FP_TSAN_ANNOTATE 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define FP_TSAN_ANNOTATE 1
#endif
#endif

#ifdef FP_TSAN_ANNOTATE
#include <sanitizer/tsan_interface.h>
#endif

namespace fp::sim {

namespace detail {

/// The happens-before edges of one parallel call (empty without ThreadSanitizer).
class ParallelEdges {
 public:
#ifdef FP_TSAN_ANNOTATE
  /// the caller, before the TBB call: its writes so far are visible to every body
  void spawn() {
    __tsan_release(&m_start);
  }
  /// a body or join, on entry
  void enter() {
    __tsan_acquire(&m_start);
    __tsan_acquire(&m_done);  // a join reads what bodies returned
  }
  /// a body or join, on exit
  void leave() {
    __tsan_release(&m_done);
  }
  /// the caller, after the TBB call returned: every body's writes are visible
  void join() {
    __tsan_acquire(&m_done);
  }

 private:
  char m_start = 0;
  char m_done = 0;
#else
  void spawn() {}
  void enter() {}
  void leave() {}
  void join() {}
#endif
};

/// runs `f` between enter() and leave() of `edges`, returning its result
template <class F, class... Args>
decltype(auto) within(ParallelEdges& edges, F& f, Args&&... args) {
  struct Leave {
    ParallelEdges& e;
    ~Leave() { e.leave(); }
  };
  edges.enter();
  Leave leave{edges};
  return f(std::forward<Args>(args)...);
}

}  // namespace detail

/// tbb::parallel_for(range, body)
template <class Range, class Body>
void parallelFor(const Range& range, const Body& body) {
  detail::ParallelEdges edges;
  edges.spawn();
  tbb::parallel_for(range, [&](const Range& r) { detail::within(edges, body, r); });
  edges.join();
}

/// tbb::parallel_for(first, last, body): body(i) for i in [first, last)
template <class Index, class Body>
void parallelFor(Index first, Index last, const Body& body) {
  detail::ParallelEdges edges;
  edges.spawn();
  tbb::parallel_for(first, last, [&](Index i) { detail::within(edges, body, i); });
  edges.join();
}

/// tbb::parallel_reduce(range, identity, body, join)
template <class Range, class Value, class Body, class Join>
Value parallelReduce(const Range& range, const Value& identity, const Body& body, const Join& join) {
  detail::ParallelEdges edges;
  edges.spawn();
  Value result = tbb::parallel_reduce(
      range, identity,
      [&](const Range& r, const Value& acc) -> Value { return detail::within(edges, body, r, acc); },
      [&](const Value& a, const Value& b) -> Value { return detail::within(edges, join, a, b); });
  edges.join();
  return result;
}

/// tbb::parallel_deterministic_reduce(range, identity, body, join): the same split and join order for every
/// thread count
template <class Range, class Value, class Body, class Join>
Value parallelDeterministicReduce(const Range& range, const Value& identity, const Body& body,
                                  const Join& join) {
  detail::ParallelEdges edges;
  edges.spawn();
  Value result = tbb::parallel_deterministic_reduce(
      range, identity,
      [&](const Range& r, const Value& acc) -> Value { return detail::within(edges, body, r, acc); },
      [&](const Value& a, const Value& b) -> Value { return detail::within(edges, join, a, b); });
  edges.join();
  return result;
}

}  // namespace fp::sim
