#pragma once
/// The project's parallel calls: TBB's parallel_for, parallel_reduce, parallel_deterministic_reduce,
/// parallel_sort and task_group with the same arguments, and nothing in sim/ or engine/ calls TBB's loops
/// directly (the ThreadSanitizer stage of scripts/bootstrap.sh checks it).
///
/// Why a wrapper: Debian's libtbb is not built with ThreadSanitizer, so TSan cannot see that a worker's loop
/// body runs after the caller spawned it, nor that the caller continues after every body finished; every
/// write the caller made before a loop and every write of a body then reads as a data race
/// (docs/robustness.md, "Races"). Built with -fsanitize=thread the wrappers state those edges themselves:
/// the caller releases a `start` token before the TBB call and each body acquires it on entry; each body
/// releases a `done` token on exit and the caller acquires it after the call. A reduction's join acquires
/// `done` too (it reads what bodies returned) and releases it. Bodies never acquire `done`: two bodies of one
/// loop stay unordered, so a race between them is still reported. In every other build the annotations
/// compile to nothing and the wrappers are the TBB calls (same ranges, grain sizes, partitioners).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_group.h>

#include <algorithm>
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
  /// a body, on entry
  void enter() {
    __tsan_acquire(&m_start);
  }
  /// a reduction's join, on entry: it reads what the bodies returned
  void enterJoin() {
    __tsan_acquire(&m_start);
    __tsan_acquire(&m_done);
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
  void enterJoin() {}
  void leave() {}
  void join() {}
#endif
};

/// calls leave() of `edges` on scope exit (a body that throws too)
struct Leave {
  ParallelEdges& edges;
  ~Leave() { edges.leave(); }
};

/// runs `f` between enter() and leave() of `edges`, returning its result as an `R` (converted while the
/// arguments live: a join may return an Eigen expression that refers to its by-value parameters)
template <class R, class F, class... Args>
R within(ParallelEdges& edges, const F& f, Args&&... args) {
  edges.enter();
  Leave leave{edges};
  return R(f(std::forward<Args>(args)...));
}

/// runs the join `f` between enterJoin() and leave() of `edges`, returning its result as an `R`
template <class R, class F, class... Args>
R withinJoin(ParallelEdges& edges, const F& f, Args&&... args) {
  edges.enterJoin();
  Leave leave{edges};
  return R(f(std::forward<Args>(args)...));
}

}  // namespace detail

/// tbb::parallel_for(range, body)
template <class Range, class Body>
void parallelFor(const Range& range, const Body& body) {
  detail::ParallelEdges edges;
  edges.spawn();
  tbb::parallel_for(range, [&](const Range& r) { detail::within<void>(edges, body, r); });
  edges.join();
}

/// tbb::parallel_for(first, last, body): body(i) for i in [first, last)
template <class Index, class Body>
void parallelFor(Index first, Index last, const Body& body) {
  detail::ParallelEdges edges;
  edges.spawn();
  tbb::parallel_for(first, last, [&](Index i) { detail::within<void>(edges, body, i); });
  edges.join();
}

/// tbb::parallel_reduce(range, identity, body, join)
template <class Range, class Value, class Body, class Join>
Value parallelReduce(const Range& range, const Value& identity, const Body& body, const Join& join) {
  detail::ParallelEdges edges;
  edges.spawn();
  Value result = tbb::parallel_reduce(
      range, identity,
      [&](const Range& r, const Value& acc) -> Value { return detail::within<Value>(edges, body, r, acc); },
      [&](const Value& a, const Value& b) -> Value { return detail::withinJoin<Value>(edges, join, a, b); });
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
      [&](const Range& r, const Value& acc) -> Value { return detail::within<Value>(edges, body, r, acc); },
      [&](const Value& a, const Value& b) -> Value { return detail::withinJoin<Value>(edges, join, a, b); });
  edges.join();
  return result;
}

/// tbb::parallel_sort(first, last). Under ThreadSanitizer a sequential std::sort: TBB's quick sort moves
/// elements while it splits its ranges, outside any body a wrapper could annotate. Both sorts are unstable;
/// for unique keys (the only use: the grid's cell-and-index keys) they give the same order.
template <class Iterator>
void parallelSort(Iterator first, Iterator last) {
#ifdef FP_TSAN_ANNOTATE
  std::sort(first, last);
#else
  tbb::parallel_sort(first, last);
#endif
}

/// tbb::task_group: run() a function on a worker, wait() for every function run so far
class TaskGroup {
 public:
  template <class F>
  void run(F&& f) {
    m_edges.spawn();
    m_group.run([this, f = std::forward<F>(f)] {
      m_edges.enter();
      detail::Leave leave{m_edges};
      f();
    });
  }
  void wait() {
    m_group.wait();
    m_edges.join();
  }

 private:
  detail::ParallelEdges m_edges;
  tbb::task_group m_group;
};

}  // namespace fp::sim
