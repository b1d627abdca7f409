// The grid neighbour search equals brute force on random clouds with mixed particle sizes.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <random>
#include <set>

#include "sim/kernels.h"
#include "sim/neighbor_search.h"
#include "sim/particle_set.h"

using namespace fp::sim;

namespace {

struct Cloud {
  std::vector<Vec3> x;
  std::vector<Real> H;
};

Cloud randomCloud(std::size_t n, Real hFine, double coarseShare, unsigned seed, const Aabb& box) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d p = box.min() + box.sizes().cwiseProduct(Vec3d(u(rng), u(rng), u(rng)));
    c.x.push_back(p.cast<Real>());
    c.H.push_back(u(rng) < coarseShare ? Real(3) * hFine : hFine);
  }
  return c;
}

/// sorts the cloud by cell of `grid` as the simulation does, filling `cells` with its cell ranges
void sortByCell(UniformGrid& grid, Cloud& c, std::vector<std::uint32_t>& cells) {
  std::vector<std::uint32_t> order;
  grid.sort(c.x.data(), c.x.size(), order, cells);
  Cloud s = c;
  for (std::size_t k = 0; k < order.size(); ++k) {
    s.x[k] = c.x[order[k]];
    s.H[k] = c.H[order[k]];
  }
  c = s;
}

std::set<std::uint32_t> listOf(const NeighborList& l, std::size_t i) {
  return std::set<std::uint32_t>(l.indices.begin() + l.offsets[i], l.indices.begin() + l.offsets[i + 1]);
}

}  // namespace

TEST(NeighborSearchTest, EqualsBruteForceWithMixedSizes) {
  const Aabb box(Vec3d(-0.3, 0.0, -0.2), Vec3d(0.4, 0.5, 0.2));
  const Real hFine = 0.04f;
  Cloud c = randomCloud(3000, hFine, 0.3, 11, box);
  UniformGrid grid;
  grid.setup(box, hFine);
  std::vector<std::uint32_t> order, cellStart;
  grid.sort(c.x.data(), c.x.size(), order, cellStart);
  // sort the cloud as the simulation does
  std::vector<Vec3> xs(c.x.size());
  std::vector<Real> Hs(c.x.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    xs[k] = c.x[order[k]];
    Hs[k] = c.H[order[k]];
  }
  const Real maxH = *std::max_element(Hs.begin(), Hs.end());
  NeighborSearch search;
  NeighborList list;
  GridPoints src{xs.data(), Hs.data(), 0, &cellStart, 0};
  search.build(grid, xs, Hs, {src}, 0, maxH, list);

  std::size_t pairs = 0, mixedPairs = 0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    std::set<std::uint32_t> expected;
    for (std::size_t j = 0; j < xs.size(); ++j) {
      const Real h = pairSupport(Hs[i], Hs[j]);
      if (j != i && (xs[i] - xs[j]).squaredNorm() < h * h) {
        expected.insert(std::uint32_t(j));
        if (Hs[i] != Hs[j])
          ++mixedPairs;
      }
    }
    pairs += expected.size();
    ASSERT_EQ(listOf(list, i), expected) << "particle " << i;
    ASSERT_EQ(list.count(i), expected.size()) << "duplicates in the list of particle " << i;
  }
  EXPECT_GT(pairs, 3000u * 5);
  EXPECT_GT(mixedPairs, 1000u);
}

TEST(NeighborSearchTest, RebuildWhereSomeListsOutgrowTheirRoomGivesTheBruteForceLists) {
  // A build places each chunk of 128 query points in a room sized from that chunk's lists at the last
  // build, plus a thirty-second and 32 entries. Here later builds make some chunks' lists several times
  // longer (they spill past their rooms, and the chunks after them must move right to make space) and others
  // shorter (they move left), the last one with a chunk that moves left between chunks that move right: every
  // list must still be the brute-force one, for build() and buildSymmetric(), on 1 and 2 threads.
  const Aabb box(Vec3d(0.0, 0.0, 0.0), Vec3d(0.5, 0.4, 0.3));
  const Real h = 0.03f;
  Cloud c = randomCloud(4000, h, 0.0, 41, box);
  UniformGrid grid;
  grid.setup(box, h);
  std::vector<std::uint32_t> cells;
  sortByCell(grid, c, cells);
  auto bruteForce = [&](const std::vector<Real>& H, std::size_t i) {
    std::set<std::uint32_t> expected;
    for (std::size_t j = 0; j < c.x.size(); ++j) {
      const Real hij = pairSupport(H[i], H[j]);
      if (j != i && (c.x[i] - c.x[j]).squaredNorm() < hij * hij)
        expected.insert(std::uint32_t(j));
    }
    return expected;
  };
  // per build, the chunks whose supports are not h and their factor, and the chunks whose lists that makes
  // outgrow the room the last build left them
  const std::vector<std::vector<std::pair<std::size_t, Real>>> changed = {
      {},
      {{2, 2.5f}, {5, 2.5f}, {6, 2.5f}, {9, 0.5f}},
      {{2, 0.5f}, {5, 0.5f}, {6, 0.5f}, {9, 2.5f}},
      {{2, 2.5f}, {5, 0.5f}, {6, 0.5f}, {9, 0.3f}, {12, 2.5f}}};
  const std::vector<std::vector<std::size_t>> outgrown = {{}, {2, 5, 6}, {9}, {2, 12}};
  auto supports = [&](std::size_t build) {
    std::vector<Real> H(c.x.size(), h);
    for (const auto& [chunk, factor] : changed[build]) {
      for (std::size_t i = chunk * 128; i < std::min(H.size(), (chunk + 1) * 128); ++i)
        H[i] = factor * h;
    }
    return H;
  };
  for (int threads : {1, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    NeighborSearch search, symmetric;
    NeighborList list, symmetricList;
    std::vector<std::size_t> lastChunkEntries;
    for (std::size_t build = 0; build < changed.size(); ++build) {
      const std::vector<Real> H = supports(build);
      const Real maxH = *std::max_element(H.begin(), H.end());
      search.build(grid, c.x, H, {GridPoints{c.x.data(), H.data(), 0, &cells, 0}}, 0, maxH, list);
      symmetric.buildSymmetric(grid, c.x, H, cells, maxH, symmetricList);
      for (const NeighborList* l : {&list, &symmetricList}) {
        ASSERT_EQ(l->offsets.size(), c.x.size() + 1);
        ASSERT_EQ(l->indices.size(), std::size_t(l->offsets.back()));
        for (std::size_t i = 0; i < c.x.size(); ++i) {
          const std::set<std::uint32_t> expected = bruteForce(H, i);
          ASSERT_EQ(listOf(*l, i), expected) << threads << " thread(s), build " << build << ", point " << i
                                             << (l == &list ? " (build)" : " (buildSymmetric)");
          ASSERT_EQ(l->count(i), expected.size()) << "duplicates, point " << i;
        }
      }
      // the case this test is for: a grown chunk's lists are far beyond the room the last build left it
      std::vector<std::size_t> chunkEntries;
      for (std::size_t i0 = 0; i0 < c.x.size(); i0 += 128) {
        const std::size_t i1 = std::min(c.x.size(), i0 + 128);
        chunkEntries.push_back(list.offsets[i1] - list.offsets[i0]);
      }
      for (std::size_t chunk : outgrown[build]) {
        const std::size_t last = lastChunkEntries[chunk];
        EXPECT_GT(chunkEntries[chunk], 2 * (last + last / 32 + 32))
            << "chunk " << chunk << ", build " << build;
      }
      if (build == 3) {
        // where each chunk's room started (its lists at the last build plus slack) and where its lists start
        // now: the chunks after chunk 2 move right, those after chunk 9 left, those after chunk 12 right
        // again
        std::vector<int> direction;
        std::size_t room = 0, start = 0;
        for (std::size_t k = 0; k < chunkEntries.size(); ++k) {
          direction.push_back(start > room ? 1 : start < room ? -1 : 0);
          room += lastChunkEntries[k] + lastChunkEntries[k] / 32 + 32;
          start += chunkEntries[k];
        }
        EXPECT_EQ(direction[4], 1);
        EXPECT_EQ(direction[11], -1);
        EXPECT_EQ(direction[14], 1);
      }
      lastChunkEntries = chunkEntries;
    }
  }
}

TEST(NeighborSearchTest, FindsBoundaryNeighborsAcrossTwoSources) {
  const Aabb box(Vec3d(0, 0, 0), Vec3d(0.5, 0.5, 0.5));
  const Real h = 0.05f;
  Cloud fluid = randomCloud(1000, h, 0.2, 3, box);
  Cloud wallA = randomCloud(700, h, 0.0, 4, box);
  Cloud wallB = randomCloud(500, h, 0.0, 5, box);
  UniformGrid grid;
  grid.setup(box, h);
  std::vector<std::uint32_t> cellsA, cellsB, cellsF;
  sortByCell(grid, fluid, cellsF);
  sortByCell(grid, wallA, cellsA);
  sortByCell(grid, wallB, cellsB);
  // walls concatenated: B's indices come after A's
  GridPoints a{wallA.x.data(), nullptr, h, &cellsA, 0};
  GridPoints b{wallB.x.data(), nullptr, h, &cellsB, std::uint32_t(wallA.x.size())};
  NeighborSearch search;
  NeighborList list;
  search.build(grid, fluid.x, fluid.H, {a, b}, -1, 3 * h, list);
  std::vector<Vec3> walls = wallA.x;
  walls.insert(walls.end(), wallB.x.begin(), wallB.x.end());
  for (std::size_t i = 0; i < fluid.x.size(); ++i) {
    std::set<std::uint32_t> expected;
    for (std::size_t j = 0; j < walls.size(); ++j) {
      const Real hij = pairSupport(fluid.H[i], h);
      if ((fluid.x[i] - walls[j]).squaredNorm() < hij * hij)
        expected.insert(std::uint32_t(j));
    }
    ASSERT_EQ(listOf(list, i), expected) << "particle " << i;
  }
}

TEST(NeighborSearchTest, ListsAreIdenticalForOneAndTwoThreads) {
  const Aabb box(Vec3d(0, 0, 0), Vec3d(0.6, 0.3, 0.3));
  Cloud c = randomCloud(5000, 0.03f, 0.25, 9, box);
  UniformGrid grid;
  grid.setup(box, 0.03f);
  std::vector<std::uint32_t> order, cells;
  grid.sort(c.x.data(), c.x.size(), order, cells);
  GridPoints src{c.x.data(), c.H.data(), 0, &cells, 0};
  NeighborList one, two;
  {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
    NeighborSearch s;
    s.build(grid, c.x, c.H, {src}, -1, 0.09f, one);
  }
  {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
    NeighborSearch s;
    s.build(grid, c.x, c.H, {src}, -1, 0.09f, two);
  }
  EXPECT_EQ(one.offsets, two.offsets);
  EXPECT_EQ(one.indices, two.indices);
}

TEST(NeighborSearchTest, CountingSortIsStableAndComplete) {
  // below and above the count where the sort switches from a serial counting sort to TBB's parallel sort
  for (const std::uint32_t n : {2000u, 20000u}) {
    const Aabb box(Vec3d(0, 0, 0), Vec3d(1, 1, 1));
    Cloud c = randomCloud(n, 0.1f, 0.0, 1, box);
    UniformGrid grid;
    grid.setup(box, 0.1f);
    std::vector<std::uint32_t> order, cells;
    grid.sort(c.x.data(), c.x.size(), order, cells);
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t k = 0; k < sorted.size(); ++k) {
      ASSERT_EQ(sorted[k], k);
    }
    EXPECT_EQ(CellRanges(cells).count(), n);
    // every point is in its own cell's range, in ascending original order within a cell, and the ranges of
    // all cells (linear order) tile [0, n)
    std::uint32_t next = 0;
    const Eigen::Vector3i dims = grid.dims();
    for (int cz = 0; cz < dims.z(); ++cz) {
      for (int cy = 0; cy < dims.y(); ++cy) {
        for (int cx = 0; cx < dims.x(); ++cx) {
          const auto [b, e] = grid.cellRange(cells, cx, cy, cz);
          if (b == e)
            continue;
          ASSERT_EQ(b, next) << n << " points";
          next = e;
          for (std::uint32_t k = b; k < e; ++k) {
            const Eigen::Vector3i cc = grid.cellCoord(c.x[order[k]]);
            ASSERT_EQ(cc, Eigen::Vector3i(cx, cy, cz)) << n << " points";
            if (k > b) {
              ASSERT_LT(order[k - 1], order[k]) << n << " points";  // stable
            }
          }
        }
      }
    }
    EXPECT_EQ(next, n);
  }
}

TEST(NeighborSearchTest, SortingASubsetGivesTheOrderOfSortingTheCompactedPoints) {
  // The simulation drops the particles an adaptation removed in the sort of the next search
  // (Simulation::sortFluid): the subset's sort must equal compacting first and sorting that, mapped back to
  // the original indices, with the same cells; on both sides of the switch to TBB's parallel sort.
  for (const std::uint32_t n : {2000u, 40000u}) {
    const Aabb box(Vec3d(0, 0, 0), Vec3d(1, 1, 1));
    Cloud c = randomCloud(n, 0.1f, 0.0, 1, box);
    UniformGrid grid;
    grid.setup(box, 0.1f);
    std::vector<std::uint32_t> keep;
    for (std::uint32_t i = 0; i < n; ++i) {
      if ((i * 2654435761u) % 10 >= 3)  // about 70 %
        keep.push_back(i);
    }
    std::vector<Vec3> compacted;
    for (std::uint32_t i : keep)
      compacted.push_back(c.x[i]);
    std::vector<std::uint32_t> order, cells, subsetOrder, subsetCells;
    grid.sort(compacted.data(), compacted.size(), order, cells);
    grid.sort(c.x.data(), keep.size(), subsetOrder, subsetCells, keep.data());
    ASSERT_EQ(subsetOrder.size(), keep.size());
    for (std::size_t k = 0; k < keep.size(); ++k) {
      ASSERT_EQ(subsetOrder[k], keep[order[k]]) << n << " points, place " << k;
    }
    EXPECT_EQ(subsetCells, cells) << n << " points";
  }
}

TEST(NeighborSearchTest, CompactCellsCostARowNotACellPerEmptyRow) {
  // a grid of 100 x 100 x 100 cells with points in one row: one word per row and the row's starts
  const Aabb box(Vec3d(0, 0, 0), Vec3d(1, 1, 1));
  UniformGrid grid;
  grid.setup(box, 0.01f);
  std::vector<Vec3> x;
  for (int k = 0; k < 50; ++k)
    x.emplace_back(Real(0.02 * k + 0.005), Real(0.5), Real(0.5));
  std::vector<std::uint32_t> order, cells;
  grid.sort(x.data(), x.size(), order, cells);
  const std::size_t rows = std::size_t(grid.dims().y()) * std::size_t(grid.dims().z());
  EXPECT_EQ(cells.size(), 2 + rows + std::size_t(grid.dims().x()) + 1);
  const Eigen::Vector3i c = grid.cellCoord(x[7]);
  const auto [b, e] = grid.cellRange(cells, c.x(), c.y(), c.z());
  ASSERT_EQ(e - b, 1u);
  EXPECT_EQ(order[b], 7u);
}

TEST(NeighborSearchTest, RejectsAGridThatIsTooLarge) {
  UniformGrid grid;
  EXPECT_THROW(grid.setup(Aabb(Vec3d(0, 0, 0), Vec3d(100, 100, 100)), 0.001f), InputError);
}

TEST(NeighborSearchTest, RejectsADomainWhoseCellsOverflowAnInt) {
  // found by fuzz_scene: a domain 2.2e63 m long made int(cells) undefined (on x86 INT_MIN, clamped to one
  // cell by std::max, so the grid passed the size check with a single cell along that axis)
  UniformGrid grid;
  EXPECT_THROW(grid.setup(Aabb(Vec3d(-0.3, -0.1, -5.2), Vec3d(0.3, 0.4, 2.2e63)), 0.02f), InputError);
  EXPECT_THROW(grid.setup(Aabb(Vec3d(0, 0, 0), Vec3d(1e12, 1e12, 1e12)), 0.02f), InputError);
}

TEST(NeighborSearchTest, SymmetricBuildGivesTheSamePairsNoLargerNeighboursFirst) {
  // supports spread continuously over [h, 3 h] as in the adaptive modes, with a share of exact ties
  const Aabb box(Vec3d(-0.2, 0.0, -0.1), Vec3d(0.3, 0.4, 0.2));
  const Real h = 0.03f;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c = randomCloud(4000, h, 0.0, 23, box);
  for (Real& H : c.H)
    H = u(rng) < 0.4 ? h : Real(h * (1.0 + 2.0 * u(rng)));
  // and a lattice of fine points 2r = h / 2 apart on the cell borders, as the scenes start: pairs twice that
  // apart lie at |x_ij| = H_ij up to round-off, where the cell index may round either way
  const Vec3d origin = box.min() - Vec3d::Constant(double(h));  // the grid's cell (0, 0, 0)
  for (int k = 0; k < 12 * 12 * 12; ++k) {
    const Vec3d step(k % 12 + 4, k / 12 % 12 + 4, k / 144 + 4);
    c.x.push_back((origin + 0.5 * double(h) * step).cast<Real>());
    c.H.push_back(h);
  }
  UniformGrid grid;
  grid.setup(box, h);
  std::vector<std::uint32_t> order, cells;
  grid.sort(c.x.data(), c.x.size(), order, cells);
  Cloud s = c;
  for (std::size_t k = 0; k < order.size(); ++k) {
    s.x[k] = c.x[order[k]];
    s.H[k] = c.H[order[k]];
  }
  const Real maxH = *std::max_element(s.H.begin(), s.H.end());
  NeighborSearch plain;
  NeighborList expected;
  plain.build(grid, s.x, s.H, {GridPoints{s.x.data(), s.H.data(), 0, &cells, 0}}, 0, maxH, expected);
  // build()'s lists in buildSymmetric's order: each list's neighbours no larger than the point first, then
  // the larger ones, each part ascending
  NeighborList reordered = expected;
  for (std::size_t i = 0; i + 1 < expected.offsets.size(); ++i) {
    const auto first = reordered.indices.begin() + expected.offsets[i];
    const auto last = reordered.indices.begin() + expected.offsets[i + 1];
    std::stable_partition(first, last, [&](std::uint32_t j) { return s.H[j] <= s.H[i]; });
  }
  // list entries where the two orders differ (a larger neighbour sorted before a smaller index)
  std::size_t split = 0;
  for (std::size_t k = 0; k < expected.indices.size(); ++k)
    split += reordered.indices[k] != expected.indices[k];
  EXPECT_GT(split, 1000u) << "the cloud should mix sizes within lists";
  for (int threads : {1, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    NeighborSearch symmetric;
    NeighborList list;
    // twice: the second build reuses the first one's rooms and capacity
    for (int pass = 0; pass < 2; ++pass) {
      symmetric.buildSymmetric(grid, s.x, s.H, cells, maxH, list);
      ASSERT_EQ(list.offsets, expected.offsets) << threads << " thread(s), pass " << pass;
      ASSERT_EQ(list.indices, reordered.indices) << threads << " thread(s), pass " << pass;
    }
  }
  EXPECT_GT(expected.indices.size(), 4000u * 10);
}

TEST(NeighborSearchTest, Avx2CandidateTestGivesTheScalarLists) {
  // The AVX2 path tests 8 candidates at a time (runtime dispatch): every build must give the scalar path's
  // lists, bit for bit, including the pairs at |x_ij| = H_ij up to round-off of a lattice on the cell borders
  // and the last points of each source (read 8 at a time only where 8 exist).
  if (!neighborSimdAvailable())
    GTEST_SKIP() << "no AVX2 on this CPU: the scalar path is the only one";
  struct Restore {
    ~Restore() { setNeighborSimd(true); }
  } restore;
  const Aabb box(Vec3d(-0.2, 0.0, -0.1), Vec3d(0.3, 0.4, 0.2));
  const Real h = 0.03f;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c = randomCloud(3000, h, 0.0, 29, box);
  for (Real& H : c.H)
    H = u(rng) < 0.5 ? h : Real(h * (1.0 + 2.0 * u(rng)));
  const Vec3d origin = box.min() - Vec3d::Constant(double(h));
  for (int k = 0; k < 10 * 10 * 10; ++k) {
    const Vec3d step(k % 10 + 4, k / 10 % 10 + 4, k / 100 + 4);
    c.x.push_back((origin + 0.5 * double(h) * step).cast<Real>());
    c.H.push_back(h);
  }
  Cloud wall = randomCloud(1500, h, 0.0, 31, box);
  UniformGrid grid;
  grid.setup(box, h);
  std::vector<std::uint32_t> cells, wallCells;
  sortByCell(grid, c, cells);
  sortByCell(grid, wall, wallCells);
  const Real maxH = *std::max_element(c.H.begin(), c.H.end());
  const PointBounds wallBounds = pointBounds(wall.x.data(), wall.x.size());
  auto buildAll = [&](bool simd) {
    EXPECT_EQ(setNeighborSimd(simd), simd);
    NeighborSearch search;
    std::vector<NeighborList> lists(3);
    search.build(grid, c.x, c.H, {GridPoints{c.x.data(), c.H.data(), 0, &cells, 0}}, 0, maxH, lists[0]);
    search.buildSymmetric(grid, c.x, c.H, cells, maxH, lists[1]);
    // a uniform source twice (the second one's indices offset), once with its bounds given
    search.build(grid, c.x, c.H,
                 {GridPoints{wall.x.data(), nullptr, h, &wallCells, 0, &wallBounds},
                  GridPoints{wall.x.data(), nullptr, h, &wallCells, std::uint32_t(wall.x.size())}},
                 -1, maxH, lists[2]);
    return lists;
  };
  const std::vector<NeighborList> scalar = buildAll(false);
  const std::vector<NeighborList> simd = buildAll(true);
  for (std::size_t k = 0; k < scalar.size(); ++k) {
    EXPECT_EQ(simd[k].offsets, scalar[k].offsets) << "build " << k;
    EXPECT_EQ(simd[k].indices, scalar[k].indices) << "build " << k;
  }
  EXPECT_GT(scalar[0].indices.size(), 4000u * 10);
  EXPECT_GT(scalar[2].indices.size(), 4000u * 2);
}

TEST(NeighborSearchTest, WallClearanceBoundsTheDistanceAndLeavesTheListsAsTheyWere) {
  const Aabb box(Vec3d(0, 0, 0), Vec3d(0.6, 0.5, 0.4));
  const Real h = 0.04f;
  UniformGrid grid;
  grid.setup(box, h);
  const Real margin = Real(1e-4) * grid.cellSize();  // the search's
  // a floor and a side wall: thin random layers
  Cloud wall = randomCloud(3000, h, 0.0, 21, Aabb(Vec3d(0, 0, 0), Vec3d(0.6, 0.01, 0.4)));
  const Cloud side = randomCloud(1500, h, 0.0, 22, Aabb(Vec3d(0, 0, 0), Vec3d(0.01, 0.5, 0.4)));
  const std::size_t nFloor = wall.x.size();
  wall.x.insert(wall.x.end(), side.x.begin(), side.x.end());
  wall.H.insert(wall.H.end(), side.H.begin(), side.H.end());
  std::vector<std::uint32_t> cells, wallCells;
  // the floor alone, for the check below that the search consults the clearance
  std::vector<Vec3> floorOnly(wall.x.begin(), wall.x.begin() + std::ptrdiff_t(nFloor));
  sortByCell(grid, wall, wallCells);
  const PointBounds wallBounds = pointBounds(wall.x.data(), wall.x.size());

  // water with fine and coarse (3 h) particles, some of them right at the walls; and water of one size, whose
  // pair support with the walls is exactly one cell (the uniform modes)
  for (const double coarseShare : {0.3, 0.0}) {
    Cloud c = randomCloud(4000, h, coarseShare, 23, box);
    sortByCell(grid, c, cells);
    const Real maxH = *std::max_element(c.H.begin(), c.H.end());
    const Real reach = Real(0.5) * (maxH + h);
    CellClearance clearance;
    clearance.build(grid, wall.x.data(), wall.x.size(), reach);

    // the bound never exceeds the distance to the nearest wall point, and within the reach it is short of it
    // by no more than a cell's diagonal and two units (the bound is the distance from the cell's box, less a
    // unit of margin, rounded down)
    std::size_t skipped = 0;
    for (std::size_t i = 0; i < c.x.size(); ++i) {
      double nearest = 1e9;
      for (const Vec3& w : wall.x)
        nearest = std::min(nearest, double((c.x[i] - w).norm()));
      const double bound = clearance.lowerBound(c.x[i]);
      ASSERT_LE(bound, nearest + 1e-6) << "particle " << i;
      if (nearest < double(reach)) {
        EXPECT_GE(bound, nearest - std::sqrt(3.0) * double(h) - 2 * double(h) / 32 - 1e-6)
            << "particle " << i;
      }
      // as the search skips: the pair support with the walls and the search's margin
      skipped += bound >= double(pairSupport(c.H[i], h) + margin);
    }
    // most of the water is out of the walls' reach (the test would be idle otherwise)
    EXPECT_GT(skipped, c.x.size() / 2) << "coarse share " << coarseShare;
    // outside the grid: no bound
    EXPECT_EQ(clearance.lowerBound(Vec3(5, 5, 5)), Real(0));

    // the same lists, in the same order, with the clearance and without (and both as brute force finds them)
    NeighborSearch search;
    NeighborList with, without;
    search.build(grid, c.x, c.H,
                 {GridPoints{wall.x.data(), nullptr, h, &wallCells, 0, &wallBounds, &clearance}}, -1, maxH,
                 with);
    search.build(grid, c.x, c.H, {GridPoints{wall.x.data(), nullptr, h, &wallCells, 0, &wallBounds}}, -1,
                 maxH, without);
    EXPECT_EQ(with.offsets, without.offsets);
    EXPECT_EQ(with.indices, without.indices);
    for (std::size_t i = 0; i < c.x.size(); ++i) {
      std::set<std::uint32_t> expected;
      const Real hij = pairSupport(c.H[i], h);
      for (std::size_t j = 0; j < wall.x.size(); ++j) {
        if ((c.x[i] - wall.x[j]).squaredNorm() < hij * hij)
          expected.insert(std::uint32_t(j));
      }
      ASSERT_EQ(listOf(with, i), expected) << "particle " << i;
    }
    EXPECT_GT(with.indices.size(), 1000u);

    // the search does consult it: a clearance of the floor alone, given for floor and side wall, hides the
    // side wall from the water above the floor
    CellClearance floorClearance;
    floorClearance.build(grid, floorOnly.data(), floorOnly.size(), reach);
    NeighborList blind;
    search.build(grid, c.x, c.H,
                 {GridPoints{wall.x.data(), nullptr, h, &wallCells, 0, &wallBounds, &floorClearance}}, -1,
                 maxH, blind);
    EXPECT_LT(blind.indices.size(), with.indices.size());
  }
}

/// The neighbours of every entry of `l`, row by row, whatever its form.
std::vector<std::uint32_t> decoded(const NeighborList& l) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i + 1 < l.offsets.size(); ++i) {
    for (std::uint32_t k = l.offsets[i]; k < l.offsets[i + 1]; ++k)
      out.push_back(l.neighbor(i, k));
  }
  return out;
}

TEST(NeighborSearchTest, NarrowListsHoldTheWideListsEntriesInHalfTheBytes) {
  // two clouds of the same count, supports spread over [h, 3 h]: a sparse one, then a dense one whose
  // lists outgrow the rooms the sparse one left (the spill path)
  const Real h = 0.03f;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Aabb sparseBox(Vec3d(0, 0, 0), Vec3d(0.8, 0.5, 0.4));
  const Aabb denseBox(Vec3d(0, 0, 0), Vec3d(0.3, 0.25, 0.2));
  std::vector<Cloud> clouds;
  std::vector<UniformGrid> grids(2);
  std::vector<std::vector<std::uint32_t>> cells(2);
  for (int c = 0; c < 2; ++c) {
    Cloud cloud = randomCloud(6000, h, 0.0, unsigned(31 + c), c == 0 ? sparseBox : denseBox);
    for (Real& H : cloud.H)
      H = u(rng) < 0.5 ? h : Real(h * (1.0 + 2.0 * u(rng)));
    grids[std::size_t(c)].setup(c == 0 ? sparseBox : denseBox, h);
    sortByCell(grids[std::size_t(c)], cloud, cells[std::size_t(c)]);
    clouds.push_back(cloud);
  }
  for (const bool simd : {false, true}) {
    setNeighborSimd(simd);
    for (int threads : {1, 2}) {
      tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
      for (const bool symmetric : {false, true}) {
        NeighborSearch wideSearch, narrowSearch;
        NeighborList wide, narrow;
        for (std::size_t c = 0; c < 2; ++c) {
          const Cloud& s = clouds[c];
          const Real maxH = *std::max_element(s.H.begin(), s.H.end());
          const std::vector<GridPoints> src{GridPoints{s.x.data(), s.H.data(), 0, &cells[c], 0}};
          if (symmetric) {
            wideSearch.buildSymmetric(grids[c], s.x, s.H, cells[c], maxH, wide);
            narrowSearch.buildSymmetric(grids[c], s.x, s.H, cells[c], maxH, narrow, ListForm::kNarrow);
          } else {
            wideSearch.build(grids[c], s.x, s.H, src, 0, maxH, wide);
            narrowSearch.build(grids[c], s.x, s.H, src, 0, maxH, narrow, ListForm::kNarrow);
          }
          const std::string where = "simd " + std::to_string(simd) + ", " + std::to_string(threads) +
                                    " thread(s), symmetric " + std::to_string(symmetric) + ", cloud " +
                                    std::to_string(c);
          ASSERT_FALSE(wide.narrow) << where;
          ASSERT_TRUE(narrow.narrow) << where;
          EXPECT_TRUE(narrow.indices.empty()) << where;
          ASSERT_EQ(narrow.offsets, wide.offsets) << where;
          ASSERT_EQ(decoded(narrow), wide.indices) << where;
          ASSERT_EQ(narrow.entries(), wide.indices.size()) << where;
          // the entries' bytes halve: both forms hold the same number of entries, with the same slack
          EXPECT_EQ(narrow.deltas.capacity(), wide.indices.capacity()) << where;
          EXPECT_EQ(wide.memoryBytes() - narrow.memoryBytes(), wide.indices.capacity() * sizeof(std::int16_t))
              << where;
          EXPECT_GT(wide.indices.size(), 6000u * 10) << where;
        }
      }
    }
  }
  setNeighborSimd(true);
}

TEST(NeighborSearchTest, NarrowListsFallBackToWideWhereAnOffsetDoesNotFit) {
  // Point A in cell (1, 1, 1), `gap` points alone in cells 3, 5, 7, ... of its row of cells, and B in a row
  // above: sorted by cell, A is point 0 and B point gap + 1, neighbours gap + 1 apart in the order. Narrow
  // lists hold offsets within +-32,767. With equal supports B is 0.7 cells above A, and A's search finds
  // the offset +gap + 1. With B three times as large, 1.7 cells above, A's own search does not reach B: B's
  // finds A at -(gap + 1), and the symmetric build writes +(gap + 1) into A's list from it.
  const Real cell = 0.01f;
  for (const bool unequal : {false, true}) {
    for (const std::size_t gap : {std::size_t(32766), std::size_t(32767)}) {
      Cloud c;
      const auto at = [&](double cx, double cy) {
        return Vec3(Real(cx * cell), Real(cy * cell), Real(1.5 * cell));
      };
      c.x.push_back(at(1.5, 1.5));
      for (std::size_t k = 0; k < gap; ++k)
        c.x.push_back(at(3.5 + 2.0 * double(k), 1.5));
      c.x.push_back(at(1.5, unequal ? 3.2 : 2.2));
      c.H.assign(c.x.size(), cell);
      if (unequal)
        c.H.back() = 3 * cell;
      const Real maxH = c.H.back();
      UniformGrid grid;
      grid.setup(Aabb(Vec3d(0, 0, 0), Vec3d(double(cell) * (2.0 * double(gap) + 5.0), 5.0 * double(cell),
                                            3.0 * double(cell))),
                 cell);
      std::vector<std::uint32_t> cells;
      sortByCell(grid, c, cells);
      const std::uint32_t b = std::uint32_t(gap + 1);
      ASSERT_GT(c.x[b].y(), Real(2 * cell)) << "B sorts last";
      ASSERT_EQ(c.H[b], maxH);
      for (const bool simd : {false, true}) {
        setNeighborSimd(simd);
        for (const bool symmetric : {false, true}) {
          NeighborSearch search;
          NeighborList list;
          for (int pass = 0; pass < 2; ++pass) {
            if (symmetric)
              search.buildSymmetric(grid, c.x, c.H, cells, maxH, list, ListForm::kNarrow);
            else
              search.build(grid, c.x, c.H, {GridPoints{c.x.data(), c.H.data(), 0, &cells, 0}}, 0, maxH, list,
                           ListForm::kNarrow);
            const std::string where = "gap " + std::to_string(gap) + ", unequal " + std::to_string(unequal) +
                                      ", simd " + std::to_string(simd) + ", symmetric " +
                                      std::to_string(symmetric) + ", pass " + std::to_string(pass);
            EXPECT_EQ(list.narrow, gap < 32767) << where;
            // the other form's entries are released
            EXPECT_EQ(list.narrow ? list.indices.capacity() : list.deltas.capacity(), 0u) << where;
            ASSERT_EQ(list.entries(), 2u) << where;
            ASSERT_EQ(list.count(0), 1u) << where;
            EXPECT_EQ(list.neighbor(0, list.offsets[0]), b) << where;
            ASSERT_EQ(list.count(b), 1u) << where;
            EXPECT_EQ(list.neighbor(b, list.offsets[b]), 0u) << where;
          }
        }
      }
    }
  }
  setNeighborSimd(true);
}
