#pragma once
/// The project's parallel calls: TBB's parallel_for, parallel_reduce, parallel_deterministic_reduce,
/// parallel_sort and task_group with the same arguments, and nothing in sim/ or engine/ calls TBB's loops
/// directly (ctest Tsan.ParallelCallsGoThroughTheWrappers checks it).
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
#include <cstdint>
#include <utility>
#include <vector>

#if defined(__SANITIZE_THREAD__)
#define FP_TSAN_ANNOTATE 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define FP_TSAN_ANNOTATE 1
#endif
#endif

#ifdef FP_TSAN_ANNOTATE
#include <sanitizer/tsan_interface.h>

#include <cstdint>
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
  /// the caller, after the TBB call returned: every body's writes are visible. Inlined, so that
  /// acquireDeadStack() scans from where the frame of the caller's outOfLine() started.
  [[gnu::always_inline]] void join() {
    __tsan_acquire(&m_done);
    acquireDeadStack();
  }
  /// TBB keeps a loop's wait node and wait context (and a reduction's root body) on the caller's stack, in
  /// the frames of outOfLine() and below. The worker that finishes the loop's last task counts them down
  /// after its last body (fold_tree: `--m_ref_count`, then `m_wait.release()`, both seq_cst atomics, which
  /// ThreadSanitizer takes as releases on their addresses), and the caller's wait for them runs inside
  /// libtbb, uninstrumented: without an edge, the caller's next frames reusing that stack read as races with
  /// those decrements. The edge TBB's wait forms is stated here: the caller acquires every address of the
  /// dead frames (16 KiB below this function's frame, where outOfLine's was), which picks up exactly what
  /// workers released there; an address nothing released costs one lookup. (Resetting the memory instead,
  /// AnnotateNewMemory, is a no-op in GCC 12's libtsan.) Bodies are untouched: they still never order
  /// each other.
  [[gnu::noinline]] static void acquireDeadStack() {
    constexpr std::uintptr_t kSpan = 16384;
    const auto top = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
    for (std::uintptr_t a = top - kSpan; a < top; a += 4)
      __tsan_acquire(reinterpret_cast<void*>(a));
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

/// A reduction's value as TBB carries it between bodies and joins. TBB copies the identity into a new body
/// when it splits a reduction for a thief (before any of our bodies ran there), assigns the last join's
/// value to the root body after our join returned, possibly on a worker, and the caller copies it out
/// before the TBB call returns: under ThreadSanitizer every construction and assignment releases the
/// value's address and every copy acquires it. Otherwise a plain aggregate of the value.
template <class V>
struct Carried {
  V value;
#ifdef FP_TSAN_ANNOTATE
  explicit Carried(const V& v) : value(v) {
    __tsan_release(this);
  }
  Carried(const Carried& other) : value((__tsan_acquire(const_cast<Carried*>(&other)), other.value)) {
    __tsan_release(this);
  }
  Carried& operator=(const Carried& other) {
    __tsan_acquire(const_cast<Carried*>(&other));
    value = other.value;
    __tsan_release(this);
    return *this;
  }
#endif
};

/// Calls `f` (a TBB call). Under ThreadSanitizer in a frame of its own, so that TBB's objects on the stack
/// lie below the caller's frame, where ParallelEdges::join() acquires what workers released there; otherwise
/// inlined away.
template <class F>
#ifdef FP_TSAN_ANNOTATE
[[gnu::noinline]]
#endif
decltype(auto)
outOfLine(const F& f) {
  return f();
}

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
  detail::outOfLine(
      [&] { tbb::parallel_for(range, [&](const Range& r) { detail::within<void>(edges, body, r); }); });
  edges.join();
}

/// tbb::parallel_for(first, last, body): body(i) for i in [first, last)
template <class Index, class Body>
void parallelFor(Index first, Index last, const Body& body) {
  detail::ParallelEdges edges;
  edges.spawn();
  detail::outOfLine(
      [&] { tbb::parallel_for(first, last, [&](Index i) { detail::within<void>(edges, body, i); }); });
  edges.join();
}

namespace detail {
/// a reduction through `reduce` (tbb::parallel_reduce or tbb::parallel_deterministic_reduce) with the edges
template <class Reduce, class Range, class Value, class Body, class Join>
Value reduceWithEdges(const Reduce& reduce, const Range& range, const Value& identity, const Body& body,
                      const Join& join) {
  ParallelEdges edges;
  edges.spawn();
  using C = Carried<Value>;
  const C result = outOfLine([&] {
    return reduce(
        range, C{identity},
        [&](const Range& r, const C& acc) -> C { return C{within<Value>(edges, body, r, acc.value)}; },
        [&](const C& a, const C& b) -> C { return C{withinJoin<Value>(edges, join, a.value, b.value)}; });
  });
  edges.join();
  return result.value;
}
}  // namespace detail

/// tbb::parallel_reduce(range, identity, body, join)
template <class Range, class Value, class Body, class Join>
Value parallelReduce(const Range& range, const Value& identity, const Body& body, const Join& join) {
  return detail::reduceWithEdges([](const auto&... args) { return tbb::parallel_reduce(args...); }, range,
                                 identity, body, join);
}

/// tbb::parallel_deterministic_reduce(range, identity, body, join): the same split and join order for every
/// thread count
template <class Range, class Value, class Body, class Join>
Value parallelDeterministicReduce(const Range& range, const Value& identity, const Body& body,
                                  const Join& join) {
  return detail::reduceWithEdges(
      [](const auto&... args) { return tbb::parallel_deterministic_reduce(args...); }, range, identity, body,
      join);
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

/// The indices i in [0, n) with keep(i), ascending, into `out` (its capacity is kept): blocks of `grain`
/// indices count theirs in parallel, then write them from their offsets, so `keep` is called twice per index
/// and must be cheap and give the same answer both times. The result does not depend on the thread count;
/// n <= grain is one serial pass.
template <class Keep>
void parallelSelect(std::size_t n, std::size_t grain, std::vector<std::uint32_t>& out, const Keep& keep) {
  out.clear();
  grain = std::max<std::size_t>(grain, 1);
  const std::size_t blocks = (n + grain - 1) / grain;
  if (blocks <= 1) {
    for (std::size_t i = 0; i < n; ++i) {
      if (keep(i))
        out.push_back(std::uint32_t(i));
    }
    return;
  }
  using Range = tbb::blocked_range<std::size_t>;
  std::vector<std::size_t> first(blocks + 1, 0);
  parallelFor(Range(0, blocks, 1), [&](const Range& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::size_t count = 0;
      for (std::size_t i = b * grain; i < std::min(n, (b + 1) * grain); ++i)
        count += keep(i) ? 1 : 0;
      first[b + 1] = count;
    }
  });
  for (std::size_t b = 0; b < blocks; ++b)
    first[b + 1] += first[b];
  out.resize(first[blocks]);
  parallelFor(Range(0, blocks, 1), [&](const Range& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::size_t k = first[b];
      for (std::size_t i = b * grain; i < std::min(n, (b + 1) * grain); ++i) {
        if (keep(i))
          out[k++] = std::uint32_t(i);
      }
    }
  });
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
    detail::outOfLine([&] { m_group.wait(); });
    m_edges.join();
  }

 private:
  detail::ParallelEdges m_edges;
  tbb::task_group m_group;
};

}  // namespace fp::sim
