#include "sim/neighbor_search.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define FP_NEIGHBOR_AVX2 1
#endif

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "sim/parallel.h"

namespace fp::sim {

namespace {
// query points per parallel task; fixed so lists are deterministic, small enough that two threads share a
// few thousand particles evenly (fine and coarse particles cost very differently)
constexpr std::size_t kChunk = 128;
// chunks per task in the loops of a few operations a point (offsets, prefix sums): at 2 threads a parallel
// call costs a few microseconds of hand-over, more than such a loop over a few thousand points takes
constexpr std::size_t kLightChunks = 64;
// NeighborList::chunkCounts of a chunk no build has seen yet. A chunk seen with no neighbours is not one:
// it gets the slack of an empty list, not the first build's guess of 32 a point (the wall lists of the water
// away from the walls were given that guess in every build, room zero-filled and closed up again).
constexpr std::uint32_t kUnseenChunk = std::numeric_limits<std::uint32_t>::max();
// A chunk's room: its lists at the last build and a thirty-second of slack (a chunk that outgrows it spills,
// closed up in place). Capacity for lists gets a thirty-second too. (A sixteenth of each held the reference
// dam break's lists at 17 bytes a fluid particle above their size once spills no longer reallocated them.)
inline std::size_t roomsFor(std::size_t entries, std::size_t chunks) {
  return entries + entries / 32 + 32 * chunks;
}
inline std::size_t roomFor(std::size_t last) {
  return roomsFor(last, 1);
}
inline std::size_t withSlack(std::size_t entries) {
  return entries + entries / 32;
}
// UniformGrid::sort: below this many points a serial counting sort, above it TBB's parallel sort
constexpr std::size_t kRadixSortBelow = 16384;

/// |a - b|^2, the distance every pair test of the search uses, spelled out so that the scalar and the AVX2
/// candidate tests round alike: the order of Eigen's (a - b).squaredNorm() (x^2 + (y^2 + z^2)), with the two
/// fused multiply-adds GCC contracts it to where the build targets FMA (-DFP_NATIVE=ON), so the lists are
/// bit for bit those of the search before the AVX2 path.
inline Real distance2(const Vec3& a, const Vec3& b) {
  const Real dx = a.x() - b.x();
  const Real dy = a.y() - b.y();
  const Real dz = a.z() - b.z();
#ifdef __FMA__
  return std::fma(dx, dx, std::fma(dz, dz, dy * dy));
#else
  return dx * dx + (dy * dy + dz * dz);
#endif
}

/// One query point's test of a run of candidates: keeps j when j != skip, |x_i - x_j|^2 < h^2 and (sized
/// sources) H_j <= hCap, with h = hMax for a source of uniform support, (H_i + H_j) / 2 otherwise.
struct CandidateTest {
  Vec3 xi;
  Real Hi;
  Real hMax2;  // uniform sources
  Real hCap;   // sized sources
  std::uint32_t skip;
  std::uint32_t offset;
};

/// An entry of type T (a list's index, or its 16-bit offset from the row) from j + offset computed modulo
/// 2^32: the offset of a narrow list is its source's index offset minus the row, and the difference, which
/// the caller checked to fit, is its low 16 bits.
template <class T>
inline T entry(std::uint32_t value) {
  if constexpr (std::is_same_v<T, std::uint32_t>)
    return value;
  else
    return T(std::uint16_t(value));
}

/// Scalar test of candidates [b, e): writes entry(j + offset) of every candidate at o[kept] and keeps it by
/// advancing `kept` (room for e - b entries at o). Returns the number kept.
template <bool kSized, class T>
inline std::size_t testCandidates(const CandidateTest& t, const Vec3* sx, const Real* sH, std::uint32_t b,
                                  std::uint32_t e, T* o) {
  std::size_t kept = 0;
  for (std::uint32_t j = b; j < e; ++j) {
    o[kept] = entry<T>(j + t.offset);
    if constexpr (kSized) {
      const Real h = Real(0.5) * (t.Hi + sH[j]);
      kept += std::size_t((j != t.skip) & (distance2(t.xi, sx[j]) < h * h) & (sH[j] <= t.hCap));
    } else {
      kept += std::size_t((j != t.skip) & (distance2(t.xi, sx[j]) < t.hMax2));
    }
  }
  return kept;
}

/// A run of candidates [b, e): the cells of one row of the grid that a query point reaches.
struct Run {
  std::uint32_t b;
  std::uint32_t e;
};

#ifdef FP_NEIGHBOR_AVX2
static_assert(std::is_same_v<Real, float> && sizeof(Vec3) == 3 * sizeof(float),
              "the AVX2 candidate test reads 8 packed float triples");

/// For each 8-bit mask, the lanes of its set bits in ascending order, one byte each: the permutation that
/// packs the kept candidates to the front.
struct CompressTable {
  std::uint64_t lanes[256];
  constexpr CompressTable() : lanes() {
    for (int m = 0; m < 256; ++m) {
      std::uint64_t packed = 0;
      int k = 0;
      for (int lane = 0; lane < 8; ++lane) {
        if (m & (1 << lane))
          packed |= std::uint64_t(lane) << (8 * k++);
      }
      lanes[m] = packed;
    }
  }
};
constexpr CompressTable kCompress;

#ifdef __FMA__
#define FP_AVX2_TARGET __attribute__((target("avx2,fma")))
#else
#define FP_AVX2_TARGET __attribute__((target("avx2")))
#endif

/// testCandidates over the runs, 8 candidates at a time with AVX2 (the same rounding as distance2: the lists
/// are identical), the query's constants set up once for all its runs. Reads the positions (and supports) of
/// 8 points from each block's first: a block that would read past `limit` (the number of points of the
/// source) goes through the scalar test. Writes 8 entries at o[kept] per block: room for the runs' candidates
/// + 7 entries at o. 16-bit entries are packed with signed saturation: exact, since they fit.
template <bool kSized, class T>
FP_AVX2_TARGET std::size_t testRunsAvx2(const CandidateTest& t, const Vec3* sx, const Real* sH,
                                        const Run* runs, std::size_t nRuns, std::uint32_t limit, T* o) {
  const __m256 qx = _mm256_set1_ps(t.xi.x());
  const __m256 qy = _mm256_set1_ps(t.xi.y());
  const __m256 qz = _mm256_set1_ps(t.xi.z());
  const __m256 hi = _mm256_set1_ps(t.Hi);
  const __m256 half = _mm256_set1_ps(Real(0.5));
  const __m256 hMax2 = _mm256_set1_ps(t.hMax2);
  const __m256 hCap = _mm256_set1_ps(t.hCap);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i skip = _mm256_set1_epi32(int(t.skip));
  const __m256i offset = _mm256_set1_epi32(int(t.offset));
  std::size_t kept = 0;
  for (std::size_t r = 0; r < nRuns; ++r) {
    const std::uint32_t e = runs[r].e;
    const __m256i last = _mm256_set1_epi32(int(e) - 1);
    std::uint32_t j = runs[r].b;
    for (; j < e && std::size_t(j) + 8 <= limit; j += 8) {
      // 8 packed (x, y, z) into x0..x7, y0..y7, z0..z7 (two 128-bit halves of 4 points each)
      const float* p = sx[j].data();
      const __m256 m03 =
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
      const __m256 m14 =
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
      const __m256 m25 =
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
      const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
      const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
      const __m256 dx = _mm256_sub_ps(qx, _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0)));
      const __m256 dy = _mm256_sub_ps(qy, _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0)));
      const __m256 dz = _mm256_sub_ps(qz, _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1)));
#ifdef __FMA__
      const __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dz, dz, _mm256_mul_ps(dy, dy)));
#else
      const __m256 d2 =
          _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_add_ps(_mm256_mul_ps(dy, dy), _mm256_mul_ps(dz, dz)));
#endif
      __m256 keep;
      if constexpr (kSized) {
        const __m256 hj = _mm256_loadu_ps(sH + j);
        const __m256 h = _mm256_mul_ps(half, _mm256_add_ps(hi, hj));
        keep = _mm256_and_ps(_mm256_cmp_ps(d2, _mm256_mul_ps(h, h), _CMP_LT_OQ),
                             _mm256_cmp_ps(hj, hCap, _CMP_LE_OQ));
      } else {
        keep = _mm256_cmp_ps(d2, hMax2, _CMP_LT_OQ);
      }
      const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(int(j)), lane);
      // lanes past the run, and the query point itself
      const __m256i out = _mm256_or_si256(_mm256_cmpgt_epi32(index, last), _mm256_cmpeq_epi32(index, skip));
      const int mask = _mm256_movemask_ps(_mm256_andnot_ps(_mm256_castsi256_ps(out), keep));
      const __m256i perm =
          _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kCompress.lanes[mask])));
      const __m256i entries = _mm256_permutevar8x32_epi32(_mm256_add_epi32(index, offset), perm);
      if constexpr (std::is_same_v<T, std::uint32_t>)
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + kept), entries);
      else
        _mm_storeu_si128(
            reinterpret_cast<__m128i*>(o + kept),
            _mm_packs_epi32(_mm256_castsi256_si128(entries), _mm256_extracti128_si256(entries, 1)));
      kept += std::size_t(__builtin_popcount(unsigned(mask)));
    }
    if (j < e)
      kept += testCandidates<kSized>(t, sx, sH, j, e, o + kept);
  }
  return kept;
}
#undef FP_AVX2_TARGET

bool detectAvx2() {
#ifdef __AVX2__
  return true;  // the build targets AVX2 (-DFP_NATIVE=ON on such a CPU)
#else
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
#endif
}
#else
bool detectAvx2() {
  return false;
}
#endif

std::atomic<bool>& simdSetting() {
  static std::atomic<bool> on(detectAvx2());
  return on;
}

}  // namespace

bool neighborSimdAvailable() {
  return detectAvx2();
}

bool setNeighborSimd(bool on) {
  simdSetting().store(on && detectAvx2());
  return simdSetting().load();
}

PointBounds pointBounds(const Vec3* x, std::size_t n) {
  using Range = tbb::blocked_range<std::size_t>;
  return parallelReduce(
      Range(0, n, 4096), PointBounds(),
      [&](const Range& r, PointBounds acc) {
        for (std::size_t j = r.begin(); j < r.end(); ++j)
          acc.extend(x[j]);
        return acc;
      },
      [](PointBounds a, const PointBounds& b) { return a.extend(b); });
}

void UniformGrid::setup(const Aabb& domain, Real cellSize, std::size_t maxCells) {
  if (!(cellSize > 0))
    throw InputError("grid cell size must be positive");
  m_cellSize = cellSize;
  m_invCellSize = Real(1) / cellSize;
  m_origin = (domain.min().array() - double(cellSize)).cast<Real>();
  const Vec3d extent = domain.sizes().array() + 2.0 * double(cellSize);
  // counted in double first: a huge domain (or a tiny cell) must not overflow the int dimensions
  Vec3d dims;
  for (int d = 0; d < 3; ++d)
    dims[d] = std::max(1.0, std::ceil(extent[d] / double(cellSize)));
  if (!(dims.prod() <= double(maxCells))) {
    std::ostringstream s;
    s << "neighbour grid of " << dims.x() << " x " << dims.y() << " x " << dims.z()
      << " cells is too large: shrink the domain or enlarge the particle radius";
    throw InputError(s.str());
  }
  for (int d = 0; d < 3; ++d)
    m_dims[d] = int(dims[d]);
}

Eigen::Vector3i UniformGrid::cellCoord(const Vec3& p) const {
  Eigen::Vector3i c;
  for (int d = 0; d < 3; ++d) {
    const Real f = (p[d] - m_origin[d]) * m_invCellSize;
    // NaN and far-away points clamp to the border; the simulation reports them separately
    const int k = f >= Real(0) ? int(std::min(f, Real(m_dims[d] - 1))) : 0;
    c[d] = k;
  }
  return c;
}

std::vector<GridPoints> wallSources(Real support, const Vec3* staticX, std::size_t nStatic,
                                    const std::vector<std::uint32_t>& staticCells,
                                    const PointBounds* staticBounds, const CellClearance* staticClearance,
                                    const Vec3* kinematicX, std::size_t nKinematic,
                                    const std::vector<std::uint32_t>& kinematicCells) {
  std::vector<GridPoints> walls;
  if (nStatic > 0)
    walls.push_back(GridPoints{staticX, nullptr, support, &staticCells, 0, staticBounds, staticClearance});
  if (nKinematic > 0)
    walls.push_back(GridPoints{kinematicX, nullptr, support, &kinematicCells, std::uint32_t(nStatic)});
  return walls;
}

void CellClearance::build(const UniformGrid& grid, const Vec3* x, std::size_t n, Real reach) {
  m_dims = grid.dims();
  m_origin = grid.origin();
  const double cell = double(grid.cellSize());
  m_invCellSize = Real(1) / grid.cellSize();
  m_unit = Real(cell / 32.0);
  // k whole cells on every side of a point's own cell, more than the reach (so that a reach of whole cells,
  // the uniform modes' one cell, still finds cells beyond it)
  const int k = std::clamp(int(std::floor(double(reach) / cell)) + 1, 1, 7);
  // Every point is at least k cells from a cell it does not look at. Each bound is one unit short of the
  // distance: a query's cell is found in float arithmetic, and near a face it may be the neighbour of the one
  // it lies in by a few ulps (covered up to 10^5 cells from the grid's origin).
  m_bound.assign(grid.cellCount(), std::uint8_t(32 * k - 1));
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i c = grid.cellCoord(x[i]);
    const Eigen::Vector3d p = x[i].cast<double>();
    for (int cz = std::max(0, c.z() - k); cz <= std::min(m_dims.z() - 1, c.z() + k); ++cz) {
      for (int cy = std::max(0, c.y() - k); cy <= std::min(m_dims.y() - 1, c.y() + k); ++cy) {
        for (int cx = std::max(0, c.x() - k); cx <= std::min(m_dims.x() - 1, c.x() + k); ++cx) {
          // distance from the point to the cell's box, rounded down to the unit
          const Eigen::Vector3d lo = m_origin.cast<double>() + cell * Eigen::Vector3d(cx, cy, cz);
          const Eigen::Vector3d hi = lo + Eigen::Vector3d::Constant(cell);
          const double d = (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
          std::uint8_t& b = m_bound[grid.linear(cx, cy, cz)];
          b = std::uint8_t(std::min<double>(b, std::max(0.0, std::floor(d * 32.0 / cell) - 1.0)));
        }
      }
    }
  }
}

void UniformGrid::sort(const Vec3* x, std::size_t n, std::vector<std::uint32_t>& order,
                       std::vector<std::uint32_t>& cells, const std::uint32_t* subset) {
  using Range = tbb::blocked_range<std::size_t>;
  const std::uint32_t nx = std::uint32_t(m_dims.x());
  const std::size_t nRows = std::size_t(m_dims.y()) * std::size_t(m_dims.z());
  m_keys.resize(n);
  parallelFor(Range(0, n, 4096), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const std::uint32_t point = subset ? subset[i] : std::uint32_t(i);
      const Eigen::Vector3i c = cellCoord(x[point]);
      m_keys[i] = (std::uint64_t(linear(c.x(), c.y(), c.z())) << 32) | std::uint64_t(point);
    }
  });
  order.resize(n);
  m_rowFirst.resize(nRows + 1);
  if (n < kRadixSortBelow) {
    // Few points (the hand tank, the hand's boundary): a stable counting sort by the cell's x, then by its
    // row (the keys are unique, so this is the order of sorting them), serial, in two passes of n plus the
    // buckets, with the rows' first points as the second pass's bucket starts. A comparison sort of the
    // nearly sorted keys cost 5 times as much.
    m_radix.resize(n);
    m_bucket.assign(std::max<std::size_t>(nx, nRows) + 1, 0);
    std::fill(m_rowFirst.begin(), m_rowFirst.end(), 0u);
    auto cellOf = [&](std::uint32_t i) { return std::uint32_t(m_keys[i] >> 32); };
    // cell / nx without a division: the product with 1 / nx in double is off by at most one
    const double invNx = 1.0 / double(nx);
    auto rowOf = [&](std::uint32_t cell) {
      std::uint32_t q = std::uint32_t(double(cell) * invNx);
      if ((q + 1) * nx <= cell)
        ++q;
      else if (q * nx > cell)
        --q;
      return q;
    };
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t cell = cellOf(std::uint32_t(i));
      const std::uint32_t row = rowOf(cell);
      ++m_bucket[cell - row * nx + 1];
      ++m_rowFirst[row + 1];
    }
    for (std::size_t b = 0; b < nx; ++b)
      m_bucket[b + 1] += m_bucket[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t cell = cellOf(std::uint32_t(i));
      m_radix[m_bucket[cell - rowOf(cell) * nx]++] = std::uint32_t(i);
    }
    for (std::size_t row = 0; row < nRows; ++row)
      m_rowFirst[row + 1] += m_rowFirst[row];
    std::copy(m_rowFirst.begin(), m_rowFirst.begin() + std::ptrdiff_t(nRows), m_bucket.begin());
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t i = m_radix[k];
      order[m_bucket[rowOf(cellOf(i))]++] = i;
    }
    // the keys in sorted order, which the cell starts below read (`order` held places in the keys so far:
    // from here the points' indices)
    for (std::size_t k = 0; k < n; ++k)
      m_radix[k] = cellOf(order[k]);
    if (subset) {
      for (std::size_t k = 0; k < n; ++k)
        order[k] = subset[order[k]];
    }
    for (std::size_t k = 0; k < n; ++k)
      m_keys[k] = (std::uint64_t(m_radix[k]) << 32) | std::uint64_t(order[k]);
  } else {
    // the keys are unique, so the sorted order is the same whatever the thread count (and the same as a
    // stable counting sort's); the particles come in nearly sorted from the last step
    parallelSort(m_keys.begin(), m_keys.end());
    // the first sorted point of every row (rows are runs of nx cells), by bisection
    parallelFor(Range(0, nRows + 1, 256), [&](const Range& r) {
      for (std::size_t row = r.begin(); row < r.end(); ++row) {
        const std::uint64_t key = std::uint64_t(row) * nx << 32;
        m_rowFirst[row] = std::uint32_t(std::lower_bound(m_keys.begin(), m_keys.end(), key) - m_keys.begin());
      }
    });
    parallelFor(Range(0, n, 4096), [&](const Range& r) {
      for (std::size_t k = r.begin(); k < r.end(); ++k)
        order[k] = std::uint32_t(m_keys[k]);
    });
  }
  // header, one word per row (a loop over rows, not points), then the starts of the non-empty rows
  cells.resize(2 + nRows);
  std::size_t pos = 2 + nRows;
  for (std::size_t row = 0; row < nRows; ++row) {
    if (m_rowFirst[row] == m_rowFirst[row + 1]) {
      cells[2 + row] = 0;
    } else {
      cells[2 + row] = std::uint32_t(pos);
      pos += nx + 1;
    }
  }
  cells[0] = std::uint32_t(n);
  cells[1] = std::uint32_t(nRows);
  cells.resize(pos);
  parallelFor(Range(0, nRows, 64), [&](const Range& r) {
    for (std::size_t row = r.begin(); row < r.end(); ++row) {
      const std::uint32_t off = cells[2 + row];
      if (off == 0)
        continue;
      std::uint32_t* start = cells.data() + off;
      std::uint32_t k = m_rowFirst[row];
      const std::uint32_t end = m_rowFirst[row + 1];
      const std::uint64_t base = std::uint64_t(row) * nx;
      for (std::uint32_t cx = 0; cx < nx; ++cx) {
        while (k < end && (m_keys[k] >> 32) < base + cx)
          ++k;
        start[cx] = k;
      }
      start[nx] = end;
    }
  });
}

std::pair<std::uint32_t, std::uint32_t> UniformGrid::cellRange(const std::vector<std::uint32_t>& cells,
                                                               int cx, int cy, int cz) const {
  const CellRanges ranges(cells);
  if (ranges.count() == 0)
    return {0, 0};
  const std::uint32_t off = ranges.rowOffset(std::uint32_t(cz * m_dims.y() + cy));
  if (off == 0)
    return {0, 0};
  return {cells[off + std::uint32_t(cx)], cells[off + std::uint32_t(cx) + 1]};
}

namespace {

/// Distance from coordinate `p` to the slab [lo, lo + cell) along one axis, shrunk by a margin so that
/// points the cell index rounded into a neighbouring cell are never pruned.
inline Real slabDistance(Real p, Real lo, Real cell, Real margin) {
  const Real d = std::max(lo - p, p - (lo + cell)) - margin;
  return d > Real(0) ? d : Real(0);
}

/// The entries of `list` in the form T: its indices (wide) or its offsets from the row (narrow).
template <class T>
std::vector<T>& entriesOf(NeighborList& list) {
  if constexpr (std::is_same_v<T, std::int16_t>)
    return list.deltas;
  else
    return list.indices;
}

/// The neighbour of row i that entry e of a list in the form T holds.
template <class T>
inline std::uint32_t neighborOf(std::size_t i, T e) {
  if constexpr (std::is_same_v<T, std::int16_t>)
    return std::uint32_t(std::int32_t(i) + std::int32_t(e));
  else
    return e;
}

/// The entry of row i that holds neighbour j, in the form T.
template <class T>
inline T entryFor(std::size_t i, std::uint32_t j) {
  if constexpr (std::is_same_v<T, std::int16_t>)
    return T(std::int32_t(j) - std::int32_t(i));
  else
    return j;
}

/// floor(f) for the cell bounds of a row; anything below zero (NaN included) gives -1, which the caller
/// clamps like any cell left of the grid (std::floor is a library call on baseline x86-64)
inline int floorCell(Real f) {
  return f >= Real(0) ? int(std::min(f, Real(1 << 30))) : -1;
}

}  // namespace

template <class T>
bool NeighborSearch::buildLists(const UniformGrid& grid, const std::vector<Vec3>& qx,
                                const std::vector<Real>& qH, const std::vector<GridPoints>& sources,
                                int selfSource, Real maxH, NeighborList& out, bool ownSupport) {
  // narrow lists: offsets from the row, for lists of the query points among themselves
  constexpr bool kNarrow = std::is_same_v<T, std::int16_t>;
  std::vector<T>& store = entriesOf<T>(out);
  const std::size_t n = qx.size();
  const std::size_t nChunks = (n + kChunk - 1) / kChunk;
  const Eigen::Vector3i dims = grid.dims();
  const Real cell = grid.cellSize();
  const Real invCell = Real(1) / cell;
  const Vec3 origin = grid.origin();
  const Real margin = Real(1e-4) * cell;
  out.offsets.resize(n + 1);
  out.offsets[0] = 0;

  // Lists are written once, straight into `out.indices`: each chunk of query points gets a room sized from
  // its count in the previous build plus slack, and the rooms are then closed up in place. A chunk that
  // outgrows its room (the first build; adaptivity moving coarse particles into it) spills the rest into a
  // buffer, copied behind its list when the rooms are closed up.
  out.chunkCounts.resize(nChunks, kUnseenChunk);
  std::vector<std::size_t> roomStart(nChunks + 1, 0);
  std::vector<std::uint8_t> overflowed(nChunks, 0);
  std::vector<std::vector<std::uint32_t>> spills(nChunks);
  // The largest support in each cell of every source with per-point supports (0 where empty): a fine
  // particle then skips the cells of the coarsest reach that hold only fine particles. The lists come out
  // the same, in the same order.
  // every source's bounding box, widened by the margin (an empty source gets an empty box)
  std::vector<PointBounds> bounds(sources.size());
  // the source's sizes, and whether the AVX2 candidate test is on
  std::vector<std::uint32_t> sourceCount(sources.size());
  const bool simd = simdSetting().load(std::memory_order_relaxed);
  for (std::size_t s = 0; s < sources.size(); ++s) {
    const std::size_t count = CellRanges(*sources[s].cellStart).count();
    sourceCount[s] = std::uint32_t(count);
    PointBounds box = sources[s].bounds ? *sources[s].bounds : pointBounds(sources[s].x, count);
    if (!box.isEmpty()) {
      box.min().array() -= margin;
      box.max().array() += margin;
    }
    bounds[s] = box;
  }
  // (narrow lists) set by the first query whose offsets might not fit 16 bits: the chunks not yet begun are
  // skipped, since the caller builds wide lists then (whatever the order, the outcome is the same)
  std::atomic<bool> anyTooFar{false};
  auto searchChunk = [&](std::size_t chunk) {
    if (kNarrow && anyTooFar.load(std::memory_order_relaxed))
      return;
    const std::size_t room = roomStart[chunk + 1] - roomStart[chunk];
    T* dst = store.data() + roomStart[chunk];
    std::size_t count = 0;
    std::vector<std::uint32_t>* spill = nullptr;
    auto emit = [&](std::uint32_t j) {
      if (count < room) {
        dst[count] = entry<T>(j);
      } else {
        if (!spill)
          spill = &spills[chunk];
        spill->push_back(j);
      }
      ++count;
    };
    const std::size_t i0 = chunk * kChunk;
    const std::size_t i1 = std::min(n, i0 + kChunk);
    // squared slab distances of the query's reach, per cell along each axis (computed once per query and
    // source instead of once per row or per trimmed cell)
    std::vector<Real> slab2;
    // the runs of candidates of one query point in one source
    std::vector<Run> runs;
    for (std::size_t i = i0; i < i1; ++i) {
      const Vec3 xi = qx[i];
      const Real Hi = qH[i];
      const Eigen::Vector3i c = grid.cellCoord(xi);
      for (int s = 0; s < int(sources.size()); ++s) {
        const GridPoints& src = sources[s];
        const Vec3* sx = src.x;
        const CellRanges ranges(*src.cellStart);
        const std::uint32_t skip =
            s == selfSource ? std::uint32_t(i) : std::numeric_limits<std::uint32_t>::max();
        // (narrow lists: minus the row, whose offsets are written)
        const std::uint32_t offset = src.indexOffset - (kNarrow ? std::uint32_t(i) : std::uint32_t(0));
        // the largest pair support this particle can have with this source (with its own support only:
        // H_i, since then H_j <= H_i)
        const Real hMax = ownSupport && src.H ? std::min(Hi, Real(0.5) * (Hi + maxH))
                                              : Real(0.5) * (Hi + (src.H ? maxH : src.uniformH));
        // the largest support of the points kept
        const Real hCap = ownSupport ? Hi : std::numeric_limits<Real>::infinity();
        const Real hMax2 = hMax * hMax;
        const CandidateTest test{xi, Hi, hMax2, hCap, skip, offset};
        // a source wholly out of reach (the hand, far from most of the water; walls farther than the query's
        // support by their clearance) costs no row at all
        if ((xi - xi.cwiseMax(bounds[std::size_t(s)].min()).cwiseMin(bounds[std::size_t(s)].max()))
                .squaredNorm() >= hMax2)
          continue;
        if (src.clearance && src.clearance->lowerBound(xi) >= hMax + margin)
          continue;
        const int reach = std::max(1, int(std::ceil(hMax * invCell)));
        int x0 = std::max(0, c.x() - reach), x1 = std::min(dims.x() - 1, c.x() + reach);
        int y0 = std::max(0, c.y() - reach), y1 = std::min(dims.y() - 1, c.y() + reach);
        int z0 = std::max(0, c.z() - reach), z1 = std::min(dims.z() - 1, c.z() + reach);
        if (ownSupport) {
          // The cells that x_i -+ (hMax + margin) fall in, as the sort rounds: a superset of build()'s
          // (a pair of supports H_i = H_j = one cell, 2r apart twice, lies two cells apart when the cell
          // index rounds down for i and up for j; build() finds it through the coarser reach, a reach of
          // ceil(H_i / cell) cells would miss it).
          const Real w = hMax + margin;
          x0 = std::max(0, floorCell((xi.x() - w - origin.x()) * invCell));
          x1 = std::min(dims.x() - 1, floorCell((xi.x() + w - origin.x()) * invCell));
          y0 = std::max(0, floorCell((xi.y() - w - origin.y()) * invCell));
          y1 = std::min(dims.y() - 1, floorCell((xi.y() + w - origin.y()) * invCell));
          z0 = std::max(0, floorCell((xi.z() - w - origin.z()) * invCell));
          z1 = std::min(dims.z() - 1, floorCell((xi.z() + w - origin.z()) * invCell));
        }
        // dy^2 of cells y0..y1, dz^2 of z0..z1 (the same expressions as a per-row evaluation: only which rows
        // are tested depends on them, never the lists)
        const std::size_t spanY = std::size_t(std::max(0, y1 - y0 + 1));
        const std::size_t spanZ = std::size_t(std::max(0, z1 - z0 + 1));
        if (slab2.size() < spanY + spanZ)
          slab2.resize(spanY + spanZ);
        Real* const dy2 = slab2.data() - y0;
        Real* const dz2 = slab2.data() + spanY - z0;
        for (int cy = y0; cy <= y1; ++cy) {
          const Real d = slabDistance(xi.y(), origin.y() + Real(cy) * cell, cell, margin);
          dy2[cy] = d * d;
        }
        for (int cz = z0; cz <= z1; ++cz) {
          const Real d = slabDistance(xi.z(), origin.z() + Real(cz) * cell, cell, margin);
          dz2[cz] = d * d;
        }
        if (runs.size() < spanY * spanZ)
          runs.resize(spanY * spanZ);
        std::size_t nRuns = 0;
        std::size_t candidates = 0;
        for (int cz = z0; cz <= z1; ++cz) {
          const Real dzz = dz2[cz];
          if (dzz >= hMax2)
            continue;
          const std::uint32_t* rowOffsets = ranges.data() + 2 + std::uint32_t(cz * dims.y());
          for (int cy = y0; cy <= y1; ++cy) {
            // Each row of the plane is written as a run and kept by advancing the count when it is within
            // reach and holds a point in x0..x1 (an empty row reads as zeros): no branch per row, whose
            // outcome the predictor could not learn. The whole row x0..x1 is tested: trimming its ends to
            // the cells within reach (by geometry, or by the cells' largest supports) cost more in
            // mispredicted branches than the candidates it saved, with the candidates tested 8 at a time or
            // branch-free (the search of the hand tank at r = 5 mm took 1.7x as long with the trimming).
            // Cells x0..x1 of one row are contiguous in the sorted arrays.
            // (masks, not conditional expressions: the compiler made branches of those)
            const std::uint32_t rowBase = rowOffsets[cy];
            const std::uint32_t nonEmpty = std::uint32_t(0) - std::uint32_t(rowBase != 0);
            const std::uint32_t b = ranges.data()[(rowBase + std::uint32_t(x0)) & nonEmpty] & nonEmpty;
            const std::uint32_t e = ranges.data()[(rowBase + std::uint32_t(x1) + 1) & nonEmpty] & nonEmpty;
            const std::uint32_t inReach = std::uint32_t(0) - std::uint32_t(dy2[cy] + dzz < hMax2);
            const std::uint32_t length = (e - b) & inReach;
            runs[nRuns] = Run{b, e};
            candidates += length;
            nRuns += std::size_t(length != 0);
          }
        }
        // the candidates of all rows, in row order (ascending: the first run starts at the least, the last
        // ends at the largest). Narrow lists take offsets within +-32,767, not down to -32,768: the symmetric
        // build writes each pair it finds into the other point's list too, with the opposite offset.
        const Real* sH = src.H;
        if constexpr (kNarrow) {
          if (nRuns > 0 && (std::int64_t(i) - std::int64_t(runs[0].b) > 32767 ||
                            std::int64_t(runs[nRuns - 1].e) - 1 - std::int64_t(i) > 32767)) {
            anyTooFar.store(true, std::memory_order_relaxed);
          }
        }
#ifdef FP_NEIGHBOR_AVX2
        if (simd && count + candidates + 7 <= room) {
          count += sH ? testRunsAvx2<true>(test, sx, sH, runs.data(), nRuns, sourceCount[std::size_t(s)],
                                           dst + count)
                      : testRunsAvx2<false>(test, sx, sH, runs.data(), nRuns, sourceCount[std::size_t(s)],
                                            dst + count);
          continue;
        }
#endif
        if (count + candidates <= room) {
          // room for every candidate: written unconditionally, kept by advancing the count
          for (std::size_t k = 0; k < nRuns; ++k) {
            const Run& run = runs[k];
            count += sH ? testCandidates<true>(test, sx, sH, run.b, run.e, dst + count)
                        : testCandidates<false>(test, sx, sH, run.b, run.e, dst + count);
          }
        } else {
          for (std::size_t k = 0; k < nRuns; ++k) {
            const Run& run = runs[k];
            for (std::uint32_t j = run.b; j < run.e; ++j) {
              const Real h = sH ? Real(0.5) * (Hi + sH[j]) : hMax;
              if (j != skip && distance2(xi, sx[j]) < h * h && (!sH || sH[j] <= hCap))
                emit(j + offset);
            }
          }
        }
      }
      // local end of i's list within the chunk; made global below
      out.offsets[i + 1] = std::uint32_t(count);
    }
    out.chunkCounts[chunk] = std::uint32_t(count);
    overflowed[chunk] = count > room;
  };

  for (std::size_t chunk = 0; chunk < nChunks; ++chunk) {
    // last build's count with slack (roomFor; a chunk that outgrows it spills, see above); a chunk
    // never seen gets a guess
    const std::uint32_t last = out.chunkCounts[chunk];
    const std::size_t room = last == kUnseenChunk ? 32 * kChunk : roomFor(last);
    roomStart[chunk + 1] = roomStart[chunk] + room;
  }
  const std::size_t total = roomStart[nChunks];
  if (store.capacity() < total)
    store.reserve(withSlack(total));
  store.resize(total);
  parallelFor(tbb::blocked_range<std::size_t>(0, nChunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
    for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk)
      searchChunk(chunk);
  });
  // (narrow lists: the chunks stopped early left their counts unwritten; nothing below may read them)
  if (kNarrow && anyTooFar.load(std::memory_order_relaxed))
    return false;
  std::vector<std::size_t> listStart(nChunks + 1, 0);
  for (std::size_t chunk = 0; chunk < nChunks; ++chunk)
    listStart[chunk + 1] = listStart[chunk] + out.chunkCounts[chunk];
  // Close up the rooms in place: each chunk's list (what fits its room, then its spill) moves to its final
  // start. A chunk that spilled may have to move right, into room that chunks after it held. Those that move
  // right go first, last chunk first, then those that move left, first chunk first: no chunk's destination
  // then covers entries of a chunk not yet moved (a right mover ends before the destination of every later
  // chunk, so before the room of every later left mover; a left mover's destination ends before every later
  // room that still holds entries). Until session 24 a spill gathered all lists into a new array: on the
  // reference dam break some 40 of 812 chunks spill in nearly every step (the water's chunks of 128 sorted
  // particles gain and lose neighbours faster than the rooms' slack), and the new array, its page faults,
  // the reallocation of the next build's rooms and their zero-filling cost more than the search itself.
  const std::size_t needed = listStart[nChunks];
  // the rooms the next build will ask for, at most
  const std::size_t nextRooms = roomsFor(needed, nChunks);
  if (needed > store.size()) {
    // (room for the next build's rooms too, not the doubling a resize past the capacity would make)
    if (needed > store.capacity())
      store.reserve(withSlack(nextRooms));
    store.resize(needed);
  }
  T* lists = store.data();
  auto moveChunk = [&](std::size_t chunk) {
    const std::size_t room = roomStart[chunk + 1] - roomStart[chunk];
    const std::size_t inRoom = std::min<std::size_t>(room, out.chunkCounts[chunk]);
    if (listStart[chunk] != roomStart[chunk] && inRoom > 0)
      std::memmove(lists + listStart[chunk], lists + roomStart[chunk], inRoom * sizeof(T));
    if (overflowed[chunk])
      std::transform(spills[chunk].begin(), spills[chunk].end(), lists + listStart[chunk] + inRoom, entry<T>);
  };
  for (std::size_t chunk = nChunks; chunk-- > 0;) {
    if (listStart[chunk] > roomStart[chunk])
      moveChunk(chunk);
  }
  for (std::size_t chunk = 0; chunk < nChunks; ++chunk) {
    if (listStart[chunk] <= roomStart[chunk])
      moveChunk(chunk);
  }
  store.resize(needed);
  // The first build's rooms are a guess (32 a query point, where walls give a handful), and lists shrink when
  // coarse particles replace fine ones: capacity beyond what the next build's rooms need is released (the
  // dam break's wall lists held 130 bytes a particle of it).
  // (Not for buildSymmetric's own lists: it sizes the array for the whole lists.)
  if (!ownSupport && store.capacity() > nextRooms + nextRooms / 8) {
    std::vector<T> fitted;
    fitted.reserve(withSlack(nextRooms));
    fitted.assign(store.begin(), store.end());
    store.swap(fitted);
  }
  parallelFor(tbb::blocked_range<std::size_t>(0, nChunks, kLightChunks),
              [&](const tbb::blocked_range<std::size_t>& cr) {
                for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
                  const std::uint32_t base = std::uint32_t(listStart[chunk]);
                  const std::size_t i1 = std::min(n, (chunk + 1) * kChunk);
                  for (std::size_t i = chunk * kChunk; i < i1; ++i)
                    out.offsets[i + 1] += base;
                }
              });
  return true;
}

/// Releases the entries of the form a build did not write, and marks the form it did.
template <class T>
void settleForm(NeighborList& out) {
  out.narrow = std::is_same_v<T, std::int16_t>;
  if (out.narrow) {
    out.indices.clear();
    out.indices.shrink_to_fit();
  } else {
    out.deltas.clear();
    out.deltas.shrink_to_fit();
  }
}

void NeighborSearch::build(const UniformGrid& grid, const std::vector<Vec3>& qx, const std::vector<Real>& qH,
                           const std::vector<GridPoints>& sources, int selfSource, Real maxH,
                           NeighborList& out, ListForm form) {
  // narrow lists only for the query points among themselves, and where every offset fits
  if (form == ListForm::kNarrow && sources.size() == 1 && selfSource == 0 && sources[0].indexOffset == 0 &&
      buildLists<std::int16_t>(grid, qx, qH, sources, selfSource, maxH, out, false)) {
    settleForm<std::int16_t>(out);
    return;
  }
  buildLists<std::uint32_t>(grid, qx, qH, sources, selfSource, maxH, out, false);
  settleForm<std::uint32_t>(out);
}

void NeighborSearch::buildSymmetric(const UniformGrid& grid, const std::vector<Vec3>& x,
                                    const std::vector<Real>& H, const std::vector<std::uint32_t>& cells,
                                    Real maxH, NeighborList& out, ListForm form) {
  if (form == ListForm::kNarrow && buildSymmetricAs<std::int16_t>(grid, x, H, cells, maxH, out)) {
    settleForm<std::int16_t>(out);
    return;
  }
  buildSymmetricAs<std::uint32_t>(grid, x, H, cells, maxH, out);
  settleForm<std::uint32_t>(out);
}

template <class T>
bool NeighborSearch::buildSymmetricAs(const UniformGrid& grid, const std::vector<Vec3>& x,
                                      const std::vector<Real>& H, const std::vector<std::uint32_t>& cells,
                                      Real maxH, NeighborList& out) {
  using Range = tbb::blocked_range<std::size_t>;
  std::vector<T>& store = entriesOf<T>(out);
  const std::size_t n = x.size();
  const std::size_t nChunks = (n + kChunk - 1) / kChunk;
  // room for the whole lists of the last build, so that widening the own lists below seldom reallocates
  if (store.capacity() < m_lastTotal)
    store.reserve(withSlack(m_lastTotal));
  // A fine point next to coarse ones otherwise searches as far as the coarsest pair support, twice its own
  // in the adaptive modes; here it searches as far as its own, and the pairs with larger points come from
  // theirs (a pair is within reach of the larger point's support). The own lists are written straight into
  // `out` and then widened in place: no second copy of the lists.
  // (a pair received is the reverse of an own pair: its offset fits, since own offsets are within +-32,767)
  if (!buildLists<T>(grid, x, H, {GridPoints{x.data(), H.data(), 0, &cells, 0}}, 0, maxH, out, true))
    return false;
  m_ownOffsets.swap(out.offsets);
  const std::uint32_t* ownOff = m_ownOffsets.data();
  const Real* h = H.data();
  // The pairs a point receives from larger points are counted and placed per block of consecutive senders:
  // no atomics, and since each block's senders write in ascending order into the block's own slots, after
  // those of the blocks before it, every point's received pairs arrive in ascending order, whatever the
  // number of blocks or threads. Blocks hold about equal numbers of own pairs.
  const std::size_t threads =
      std::min<std::size_t>(std::size_t(tbb::this_task_arena::max_concurrency()),
                            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const std::size_t nBlocks = std::max<std::size_t>(1, std::min({2 * threads, std::size_t(16), nChunks}));
  m_blockFirst.resize(nBlocks + 1);
  m_blockFirst[0] = 0;
  for (std::size_t b = 1; b < nBlocks; ++b) {
    const std::size_t pairs = std::size_t(ownOff[n]) * b / nBlocks;
    m_blockFirst[b] =
        std::max(m_blockFirst[b - 1], std::size_t(std::lower_bound(ownOff, ownOff + n, pairs) - ownOff));
  }
  m_blockFirst[nBlocks] = n;
  // per block and point: the pairs it sends to that point, then where the block's next one goes in the
  // point's received part
  m_blockSlots.assign(nBlocks * n, 0);
  std::uint32_t* slots = m_blockSlots.data();
  {
    const T* own = store.data();
    parallelFor(Range(0, nBlocks, 1), [&](const Range& br) {
      for (std::size_t b = br.begin(); b < br.end(); ++b) {
        std::uint32_t* count = slots + b * n;
        for (std::size_t i = m_blockFirst[b]; i < m_blockFirst[b + 1]; ++i) {
          for (std::uint32_t k = ownOff[i]; k < ownOff[i + 1]; ++k) {
            const std::uint32_t j = neighborOf(i, own[k]);
            if (h[j] < h[i])
              ++count[j];
          }
        }
      }
    });
  }
  // each point's received pairs, and each block's first slot among them
  m_received.resize(n);
  std::uint32_t* received = m_received.data();
  parallelFor(Range(0, n, kLightChunks * kChunk), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      std::uint32_t sum = 0;
      for (std::size_t b = 0; b < nBlocks; ++b) {
        const std::uint32_t c = slots[b * n + i];
        slots[b * n + i] = sum;
        sum += c;
      }
      received[i] = sum;
    }
  });
  // i's list starts after the lists of the points before it: a prefix sum, per chunk and over chunks
  m_chunkPairs.assign(nChunks + 1, 0);
  parallelFor(Range(0, nChunks, kLightChunks), [&](const Range& cr) {
    for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
      std::size_t sum = 0;
      for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i)
        sum += received[i];
      m_chunkPairs[chunk + 1] = sum;
    }
  });
  for (std::size_t chunk = 0; chunk < nChunks; ++chunk)
    m_chunkPairs[chunk + 1] += m_chunkPairs[chunk];
  const std::size_t total = ownOff[n] + m_chunkPairs[nChunks];
  m_lastTotal = total;
  out.offsets.resize(n + 1);
  parallelFor(Range(0, nChunks, kLightChunks), [&](const Range& cr) {
    for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
      std::size_t before = m_chunkPairs[chunk];
      for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
        out.offsets[i] = std::uint32_t(ownOff[i] + before);
        before += received[i];
      }
    }
  });
  out.offsets[n] = std::uint32_t(total);
  // capacity for the whole lists with slack, and at least for the rooms the next build of the own lists asks
  // for (sparse lists, a few pairs a point, need more for those than for the whole lists); more than an
  // eighth beyond that is released
  const std::size_t own = ownOff[n];
  const std::size_t wanted = withSlack(std::max(total, roomsFor(own, nChunks)));
  if (store.capacity() < total) {
    store.reserve(wanted);
  } else if (store.capacity() > wanted + wanted / 8) {
    std::vector<T> fitted;
    fitted.reserve(wanted);
    fitted.assign(store.begin(), store.end());
    store.swap(fitted);
  }
  store.resize(total);
  T* dst = store.data();
  // Widen in place. First each chunk's own lists move, as one block, to the end of the chunk's final range,
  // last chunk first (every block moves right, and only into room that no later chunk uses any more) ...
  for (std::size_t chunk = nChunks; chunk-- > 0;) {
    const std::size_t i0 = chunk * kChunk;
    const std::size_t i1 = std::min(n, i0 + kChunk);
    const std::size_t length = ownOff[i1] - ownOff[i0];
    const std::size_t to = out.offsets[i1] - length;
    if (length > 0 && to != ownOff[i0])
      std::memmove(dst + to, dst + ownOff[i0], length * sizeof(T));
  }
  // ... then, chunk by chunk in parallel, each own list moves left to its final start (front to back, so no
  // list is overwritten before it moves); `received` becomes where i's received pairs start
  parallelFor(Range(0, nChunks, 1), [&](const Range& cr) {
    for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
      const std::size_t i0 = chunk * kChunk;
      const std::size_t i1 = std::min(n, i0 + kChunk);
      const std::size_t block = out.offsets[i1] - (ownOff[i1] - ownOff[i0]);
      for (std::size_t i = i0; i < i1; ++i) {
        const std::size_t from = block + (ownOff[i] - ownOff[i0]);
        const std::uint32_t a = ownOff[i + 1] - ownOff[i];
        if (a > 0 && from != out.offsets[i])
          std::memmove(dst + out.offsets[i], dst + from, a * sizeof(T));
        received[i] = out.offsets[i] + a;
      }
    }
  });
  // the pairs with larger points, read from the own lists in their final places, written after them: each
  // block into its own slots, in ascending sender order
  parallelFor(Range(0, nBlocks, 1), [&](const Range& br) {
    for (std::size_t b = br.begin(); b < br.end(); ++b) {
      std::uint32_t* next = slots + b * n;
      for (std::size_t i = m_blockFirst[b]; i < m_blockFirst[b + 1]; ++i) {
        const std::uint32_t first = out.offsets[i];
        const std::uint32_t last = first + (ownOff[i + 1] - ownOff[i]);
        for (std::uint32_t k = first; k < last; ++k) {
          const std::uint32_t j = neighborOf(i, dst[k]);
          if (h[j] < h[i])
            dst[received[j] + next[j]++] = entryFor<T>(j, std::uint32_t(i));
        }
      }
    }
  });
  // The two parts are left as they are, each ascending: merging them into build()'s order cost 17 % of this
  // search on the hand tank at r = 5 mm (3.8 % of a step), and a fixed order is all the sums need to be the
  // same whatever the thread count.
  return true;
}

}  // namespace fp::sim
