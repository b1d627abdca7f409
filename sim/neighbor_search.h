#pragma once
/// Neighbour search on a uniform grid (after Green 2008 / Ihmsen et al. 2011 "compact" grids), correct when
/// particles of different sizes are mixed: cells are as large as the smallest support radius and each
/// particle looks as many cells far as its largest possible pair support needs. Parallel with TBB and
/// deterministic: lists come out in the same order whatever the thread count.

#include <cstdint>
#include <vector>

#include "sim/types.h"

namespace fp::sim {

/// Read access to the cell ranges that UniformGrid::sort writes into one array. Compact: only the rows of
/// cells (along x) that hold a point carry per-cell entries, so a grid over a large domain costs one word
/// per row, not per cell. Layout: [0] the number of points, [1] the number of rows (dims.y * dims.z), then
/// one word per row (the position of its dims.x + 1 cell starts in the array, 0 for an empty row), then the
/// starts of the non-empty rows. An array whose point count is 0 (or an empty array) holds no point.
class CellRanges {
 public:
  explicit CellRanges(const std::vector<std::uint32_t>& data)
      : m_data(data.empty() ? nullptr : data.data()) {}
  /// number of points sorted
  std::uint32_t count() const { return m_data ? m_data[0] : 0; }
  /// position in the array of the dims.x + 1 starts of row `row` (= cy + cz * dims.y), 0 when it is empty
  std::uint32_t rowOffset(std::uint32_t row) const { return m_data[2 + row]; }
  /// the array itself (the starts of a row at rowOffset: the sorted points of cell cx of the row are
  /// [starts[cx], starts[cx + 1]))
  const std::uint32_t* data() const { return m_data; }

 private:
  const std::uint32_t* m_data;
};

/// Geometry of a dense grid over the simulation domain, and a sort of points into it.
class UniformGrid {
 public:
  /// covers `domain` (plus one cell of margin) with cubic cells of edge `cellSize` [m]; throws InputError
  /// when the grid would exceed `maxCells`
  void setup(const Aabb& domain, Real cellSize, std::size_t maxCells = std::size_t(1) << 27);

  /// edge of a cell [m]
  Real cellSize() const { return m_cellSize; }
  /// corner of cell (0, 0, 0) [m]
  const Vec3& origin() const { return m_origin; }
  /// number of cells along x, y, z
  const Eigen::Vector3i& dims() const { return m_dims; }
  /// total number of cells
  std::size_t cellCount() const { return std::size_t(m_dims.x()) * m_dims.y() * m_dims.z(); }
  /// integer cell coordinates of a point, clamped to the grid
  Eigen::Vector3i cellCoord(const Vec3& p) const;
  /// linear index of integer cell coordinates (x fastest)
  std::uint32_t linear(int cx, int cy, int cz) const {
    return std::uint32_t((cz * m_dims.y() + cy) * m_dims.x() + cx);
  }

  /// Sorts x[0..n) by cell (linear index, then original index: stable, hence deterministic), in parallel.
  /// Fills `order` (sorted k <- original order[k]) and `cells`, the cell ranges of the sorted points in the
  /// compact form CellRanges reads. With `subset` (n ascending indices), only the points x[subset[k]] are
  /// sorted and `order` holds their indices: the order that compacting x to the subset and sorting that
  /// gives.
  void sort(const Vec3* x, std::size_t n, std::vector<std::uint32_t>& order,
            std::vector<std::uint32_t>& cells, const std::uint32_t* subset = nullptr);
  /// the sorted points of cell (cx, cy, cz): [first, second) (tests; the split blend's parent density)
  std::pair<std::uint32_t, std::uint32_t> cellRange(const std::vector<std::uint32_t>& cells, int cx, int cy,
                                                    int cz) const;
  /// bytes held by scratch buffers
  std::size_t memoryBytes() const {
    return m_keys.capacity() * sizeof(std::uint64_t) +
           (m_rowFirst.capacity() + m_radix.capacity() + m_bucket.capacity()) * sizeof(std::uint32_t);
  }

 private:
  Vec3 m_origin = Vec3::Zero();
  Real m_cellSize = 1;
  Real m_invCellSize = 1;
  Eigen::Vector3i m_dims{1, 1, 1};
  std::vector<std::uint64_t> m_keys;      // cell << 32 | original index, sorted
  std::vector<std::uint32_t> m_rowFirst;  // first sorted point of every row of cells
  // sort() of fewer than kRadixSortBelow points: the first pass's order, then the sorted cells; bucket starts
  std::vector<std::uint32_t> m_radix;
  std::vector<std::uint32_t> m_bucket;
};

/// How a list of neighbours of the points themselves stores its indices: 32-bit indices, or 16-bit offsets
/// j - i from the row (half the bytes: the lists are the largest arrays of a step). Points sorted by cell lie
/// close to their neighbours in the order; a build whose offsets do not all fit 16 bits writes wide lists.
enum class ListForm { kWide, kNarrow };

/// Reads the entries of wide lists (NeighborList::visit): neighbour j of entry k of row i is rows(i, k), or
/// base(i) + offset(k), which lets a hot loop address its arrays from the row's base as (x + base)[offset].
struct WideRows {
  const std::uint32_t* index;
  std::uint32_t operator()(std::size_t, std::uint32_t k) const { return index[k]; }
  static std::ptrdiff_t base(std::size_t) { return 0; }
  std::uint32_t offset(std::uint32_t k) const { return index[k]; }
};
/// Reads the entries of narrow lists (NeighborList::visit, NeighborList::neighbor).
struct NarrowRows {
  const std::int16_t* delta;
  std::size_t operator()(std::size_t i, std::uint32_t k) const {
    return std::size_t(std::ptrdiff_t(i) + std::ptrdiff_t(delta[k]));
  }
  static std::ptrdiff_t base(std::size_t i) { return std::ptrdiff_t(i); }
  std::ptrdiff_t offset(std::uint32_t k) const { return delta[k]; }
};

/// Neighbour lists in compressed-row form: the neighbours of particle i are the entries offsets[i] ..
/// offsets[i+1], read with neighbor(i, k): indices[k] (wide lists) or i + deltas[k] (narrow lists).
struct NeighborList {
  std::vector<std::uint32_t> offsets;  ///< size n + 1
  std::vector<std::uint32_t> indices;  ///< neighbour indices (wide lists)
  std::vector<std::int16_t> deltas;    ///< j - i of each neighbour j of row i (narrow lists)
  bool narrow = false;                 ///< whether the entries are in `deltas`
  /// neighbours per chunk of query points at the last build: the next build's room estimate
  std::vector<std::uint32_t> chunkCounts;
  /// number of neighbours of particle i
  std::uint32_t count(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
  /// number of entries of all lists
  std::size_t entries() const { return offsets.empty() ? 0 : offsets.back(); }
  /// entry k of row i: a neighbour of particle i
  std::uint32_t neighbor(std::size_t i, std::uint32_t k) const {
    return narrow ? std::uint32_t(NarrowRows{deltas.data()}(i, k)) : indices[k];
  }
  /// f(rows) with rows(i, k) == neighbor(i, k), resolved once for a whole pass instead of for every entry
  template <class F>
  decltype(auto) visit(F&& f) const {
    if (narrow)
      return f(NarrowRows{deltas.data()});
    return f(WideRows{indices.data()});
  }
  /// empties the lists (keeps capacity)
  void clear() {
    offsets.clear();
    indices.clear();
    deltas.clear();
    narrow = false;
  }
  /// bytes held
  std::size_t memoryBytes() const {
    return (offsets.capacity() + indices.capacity() + chunkCounts.capacity()) * sizeof(std::uint32_t) +
           deltas.capacity() * sizeof(std::int16_t);
  }
};

/// Bounding box of points, for the search's test of a whole source against a query point.
using PointBounds = Eigen::AlignedBox<Real, 3>;

/// The bounding box of x[0..n) (empty when n is 0), in parallel. A source whose points never move (the static
/// walls) computes it once and passes it in GridPoints::bounds.
PointBounds pointBounds(const Vec3* x, std::size_t n);

/// For every cell of a grid, a lower bound of the distance from any point of the cell to the nearest of a set
/// of points that never moves (the static walls), in 1/32 of a cell, one byte a cell: the search then skips
/// the whole set for a query point that it cannot reach (in the hand tank three fluid particles in four have
/// no wall within their support, and each would otherwise visit a dozen rows of the walls' grid to find
/// none). Within `reach` the bound is the distance from the cell's box to the nearest point less at most a
/// cell's 1/16 (a unit of rounding, a unit of margin); beyond, it is as far as the whole cells looked at
/// (more than the reach). The search skips the set only where its own support is shorter than the bound, so
/// the lists are the same.
class CellClearance {
 public:
  /// the bounds for the points x[0..n) in `grid`, each point looked at as far as `reach` [m] and beyond to
  /// the next whole cell (at most 7 cells)
  void build(const UniformGrid& grid, const Vec3* x, std::size_t n, Real reach);
  /// a lower bound [m] of the distance from `p` to every point of the set (0 outside the grid, or before
  /// build)
  Real lowerBound(const Vec3& p) const {
    if (m_bound.empty())
      return 0;
    int c[3];
    for (int d = 0; d < 3; ++d) {
      const Real f = (p[d] - m_origin[d]) * m_invCellSize;
      if (!(f >= Real(0) && f < Real(m_dims[d])))
        return 0;
      c[d] = int(f);
    }
    return Real(m_bound[(std::size_t(c[2]) * std::size_t(m_dims.y()) + std::size_t(c[1])) *
                            std::size_t(m_dims.x()) +
                        std::size_t(c[0])]) *
           m_unit;
  }
  /// bytes held
  std::size_t memoryBytes() const { return m_bound.capacity(); }

 private:
  std::vector<std::uint8_t> m_bound;  // per cell, x fastest, in units of m_unit
  Vec3 m_origin = Vec3::Zero();
  Real m_invCellSize = 1;
  Real m_unit = 1;
  Eigen::Vector3i m_dims{0, 0, 0};
};

/// A set of points sorted into a grid, to be searched: positions, support radii and cell ranges.
struct GridPoints {
  const Vec3* x = nullptr;  ///< sorted positions
  const Real* H = nullptr;  ///< support radii (nullptr: all equal to `uniformH`)
  Real uniformH = 0;        ///< support when H is nullptr
  const std::vector<std::uint32_t>* cellStart = nullptr;  ///< cell ranges (from UniformGrid::sort)
  std::uint32_t indexOffset = 0;                          ///< added to every index written to the lists
  const PointBounds* bounds = nullptr;  ///< pointBounds of the points (nullptr: computed by every build)
  /// distance bounds of the points, for points that never move (nullptr: none); the lists are the same
  const CellClearance* clearance = nullptr;
};

/// The sources of a boundary search: the static walls (sorted once; their bounding box and clearance given
/// when known, else nullptr) and, after them in the lists' indices, the moving boundary particles; a part
/// with no points is left out.
std::vector<GridPoints> wallSources(Real support, const Vec3* staticX, std::size_t nStatic,
                                    const std::vector<std::uint32_t>& staticCells,
                                    const PointBounds* staticBounds, const CellClearance* staticClearance,
                                    const Vec3* kinematicX, std::size_t nKinematic,
                                    const std::vector<std::uint32_t>& kinematicCells);

/// Whether the neighbour search tests its candidates 8 at a time with AVX2 (chosen at run time from the CPU;
/// the lists are the same either way). Tests switch it off to compare with the scalar path; switching it on
/// on a CPU without AVX2 keeps it off. Returns the setting in force.
bool neighborSimdAvailable();
bool setNeighborSimd(bool on);

/// Builds neighbour lists: all pairs with |x_i - x_j| < (H_i + H_j) / 2.
class NeighborSearch {
 public:
  /// Lists, for every query point, its neighbours among each source in `sources` (concatenated, with each
  /// source's indexOffset added), excluding the query point itself when `selfSource` is that source's
  /// position in `sources`
  /// (-1: none). `maxH` is the largest support radius among the sources with per-point radii (a source with
  /// a uniform radius is searched only as far as that radius needs). Every list is in ascending index order.
  /// `form` kNarrow writes narrow lists where that is possible: lists of the query points among themselves
  /// (one source, the queries, selfSource 0, index offset 0) whose offsets all fit 16 bits; else wide ones.
  void build(const UniformGrid& grid, const std::vector<Vec3>& qx, const std::vector<Real>& qH,
             const std::vector<GridPoints>& sources, int selfSource, Real maxH, NeighborList& out,
             ListForm form = ListForm::kWide);

  /// The pairs of build(grid, x, H, {{x, H, 0, &cells, 0}}, 0, maxH, out), found with less work when sizes
  /// are mixed: each point searches only as far as its own support, for the points no larger than itself,
  /// and receives the pairs with larger points from their searches. Each list holds first the neighbours
  /// with H_j <= H_i, then those with H_j > H_i, each part in ascending index order: the same lists whatever
  /// the thread count (build() lists in ascending order throughout). `x`, `H` and `cells` are the points
  /// sorted by UniformGrid::sort; `maxH` their largest support [m].
  void buildSymmetric(const UniformGrid& grid, const std::vector<Vec3>& x, const std::vector<Real>& H,
                      const std::vector<std::uint32_t>& cells, Real maxH, NeighborList& out,
                      ListForm form = ListForm::kWide);

  /// bytes held by scratch buffers (the lists are written in place)
  std::size_t memoryBytes() const {
    return (m_ownOffsets.capacity() + m_received.capacity() + m_blockSlots.capacity()) *
               sizeof(std::uint32_t) +
           (m_chunkPairs.capacity() + m_blockFirst.capacity()) * sizeof(std::size_t);
  }

 private:
  /// build(); with `ownSupport`, a source with per-point supports yields, for query i, only its points j with
  /// H_j <= H_i (searched as far as H_i)
  /// The lists written as T: std::uint32_t (wide) or std::int16_t (narrow: false, and the lists unusable,
  /// where an offset does not fit).
  template <class T>
  bool buildLists(const UniformGrid& grid, const std::vector<Vec3>& qx, const std::vector<Real>& qH,
                  const std::vector<GridPoints>& sources, int selfSource, Real maxH, NeighborList& out,
                  bool ownSupport);
  /// buildSymmetric's lists written as T (as buildLists)
  template <class T>
  bool buildSymmetricAs(const UniformGrid& grid, const std::vector<Vec3>& x, const std::vector<Real>& H,
                        const std::vector<std::uint32_t>& cells, Real maxH, NeighborList& out);

  // buildSymmetric: where each point's own list (its neighbours no larger than itself) was written
  std::vector<std::uint32_t> m_ownOffsets;
  // buildSymmetric: the size of the last lists (the next build's room)
  std::size_t m_lastTotal = 0;
  // buildSymmetric: pairs each point receives from larger points, then where the next one goes
  std::vector<std::uint32_t> m_received;
  // buildSymmetric: pairs received by the points of the chunks before each chunk
  std::vector<std::size_t> m_chunkPairs;
  // buildSymmetric: the first sender of each block of senders, and per block and point the pairs the block
  // sends it, then the block's next slot among them
  std::vector<std::size_t> m_blockFirst;
  std::vector<std::uint32_t> m_blockSlots;
};

}  // namespace fp::sim
