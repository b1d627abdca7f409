#include "sim/neighbor_search.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace fp::sim {

namespace {
constexpr std::size_t kChunk = 512;  // query points per parallel task; fixed so lists are deterministic
}

void UniformGrid::setup(const Aabb& domain, Real cellSize, std::size_t maxCells) {
  if (!(cellSize > 0))
    throw InputError("grid cell size must be positive");
  m_cellSize = cellSize;
  m_invCellSize = Real(1) / cellSize;
  m_origin = (domain.min().array() - double(cellSize)).cast<Real>();
  const Vec3d extent = domain.sizes().array() + 2.0 * double(cellSize);
  double cells = 1.0;
  for (int d = 0; d < 3; ++d) {
    m_dims[d] = std::max(1, int(std::ceil(extent[d] / double(cellSize))));
    cells *= m_dims[d];
  }
  if (cells > double(maxCells)) {
    std::ostringstream s;
    s << "neighbour grid of " << m_dims.x() << " x " << m_dims.y() << " x " << m_dims.z()
      << " cells is too large: shrink the domain or enlarge the particle radius";
    throw InputError(s.str());
  }
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

void UniformGrid::sort(const Vec3* x, std::size_t n, std::vector<std::uint32_t>& order,
                       std::vector<std::uint32_t>& cellStart) {
  const std::size_t nc = cellCount();
  m_cellOf.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        const Eigen::Vector3i c = cellCoord(x[i]);
                        m_cellOf[i] = linear(c.x(), c.y(), c.z());
                      }
                    });
  cellStart.assign(nc + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    ++cellStart[m_cellOf[i] + 1];
  for (std::size_t c = 0; c < nc; ++c)
    cellStart[c + 1] += cellStart[c];
  order.resize(n);
  // scatter using cellStart[c] as a cursor, then shift back; stable in the original index
  for (std::size_t i = 0; i < n; ++i)
    order[cellStart[m_cellOf[i]]++] = std::uint32_t(i);
  for (std::size_t c = nc; c > 0; --c)
    cellStart[c] = cellStart[c - 1];
  cellStart[0] = 0;
}

namespace {

/// Distance from coordinate `p` to the slab [lo, lo + cell) along one axis, shrunk by a margin so that
/// points the cell index rounded into a neighbouring cell are never pruned.
inline Real slabDistance(Real p, Real lo, Real cell, Real margin) {
  const Real d = std::max(lo - p, p - (lo + cell)) - margin;
  return d > Real(0) ? d : Real(0);
}

/// floor(f) for the cell bounds of a row; anything below zero (NaN included) gives -1, which the caller
/// clamps like any cell left of the grid (std::floor is a library call on baseline x86-64)
inline int floorCell(Real f) {
  return f >= Real(0) ? int(std::min(f, Real(1 << 30))) : -1;
}

}  // namespace

void NeighborSearch::build(const UniformGrid& grid, const std::vector<Vec3>& qx, const std::vector<Real>& qH,
                           const std::vector<GridPoints>& sources, int selfSource, Real maxH,
                           NeighborList& out) {
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
  // buffer, and only then are the lists gathered into a new array.
  out.chunkCounts.resize(nChunks, 0);
  std::vector<std::size_t> roomStart(nChunks + 1, 0);
  std::vector<std::uint8_t> overflowed(nChunks, 0);
  std::vector<std::vector<std::uint32_t>> spills(nChunks);
  // The largest support in each cell of every source with per-point supports (0 where empty): a fine
  // particle then skips the cells of the coarsest reach that hold only fine particles. The lists come out
  // the same, in the same order.
  // every source's bounding box, widened by the margin (an empty source gets an empty box)
  std::vector<Eigen::AlignedBox<Real, 3>> bounds(sources.size());
  for (std::size_t s = 0; s < sources.size(); ++s) {
    const std::size_t count = sources[s].cellStart->empty() ? 0 : sources[s].cellStart->back();
    const Vec3* sx = sources[s].x;
    using Box = Eigen::AlignedBox<Real, 3>;
    Box box = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, 4096), Box(),
        [&](const tbb::blocked_range<std::size_t>& r, Box acc) {
          for (std::size_t j = r.begin(); j < r.end(); ++j)
            acc.extend(sx[j]);
          return acc;
        },
        [](Box a, const Box& b) { return a.extend(b); });
    if (!box.isEmpty()) {
      box.min().array() -= margin;
      box.max().array() += margin;
    }
    bounds[s] = box;
  }
  m_cellMaxH.resize(sources.size());
  for (std::size_t s = 0; s < sources.size(); ++s) {
    if (!sources[s].H)
      continue;
    const std::uint32_t* start = sources[s].cellStart->data();
    const Real* sH = sources[s].H;
    std::vector<Real>& cellMax = m_cellMaxH[s];
    cellMax.resize(sources[s].cellStart->size() - 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cellMax.size(), 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t c = r.begin(); c < r.end(); ++c) {
                          Real h = 0;
                          for (std::uint32_t j = start[c]; j < start[c + 1]; ++j)
                            h = std::max(h, sH[j]);
                          cellMax[c] = h;
                        }
                      });
  }
  auto searchChunk = [&](std::size_t chunk) {
    const std::size_t room = roomStart[chunk + 1] - roomStart[chunk];
    std::uint32_t* dst = out.indices.data() + roomStart[chunk];
    std::size_t count = 0;
    std::vector<std::uint32_t>* spill = nullptr;
    auto emit = [&](std::uint32_t j) {
      if (count < room) {
        dst[count] = j;
      } else {
        if (!spill)
          spill = &spills[chunk];
        spill->push_back(j);
      }
      ++count;
    };
    const std::size_t i0 = chunk * kChunk;
    const std::size_t i1 = std::min(n, i0 + kChunk);
    for (std::size_t i = i0; i < i1; ++i) {
      const Vec3 xi = qx[i];
      const Real Hi = qH[i];
      const Eigen::Vector3i c = grid.cellCoord(xi);
      for (int s = 0; s < int(sources.size()); ++s) {
        const GridPoints& src = sources[s];
        const Vec3* sx = src.x;
        const std::uint32_t* start = src.cellStart->data();
        const std::uint32_t skip =
            s == selfSource ? std::uint32_t(i) : std::numeric_limits<std::uint32_t>::max();
        const std::uint32_t offset = src.indexOffset;
        // the largest pair support this particle can have with this source
        const Real hMax = Real(0.5) * (Hi + (src.H ? maxH : src.uniformH));
        const Real hMax2 = hMax * hMax;
        // a source wholly out of reach (the hand, far from most of the water) costs no row at all
        if ((xi - xi.cwiseMax(bounds[std::size_t(s)].min()).cwiseMin(bounds[std::size_t(s)].max()))
                .squaredNorm() >= hMax2)
          continue;
        const int reach = std::max(1, int(std::ceil(hMax * invCell)));
        const int x0 = std::max(0, c.x() - reach), x1 = std::min(dims.x() - 1, c.x() + reach);
        const int y0 = std::max(0, c.y() - reach), y1 = std::min(dims.y() - 1, c.y() + reach);
        const int z0 = std::max(0, c.z() - reach), z1 = std::min(dims.z() - 1, c.z() + reach);
        for (int cz = z0; cz <= z1; ++cz) {
          const Real dz = slabDistance(xi.z(), origin.z() + Real(cz) * cell, cell, margin);
          for (int cy = y0; cy <= y1; ++cy) {
            const Real dy = slabDistance(xi.y(), origin.y() + Real(cy) * cell, cell, margin);
            const Real dyz2 = dy * dy + dz * dz;
            if (dyz2 >= hMax2)
              continue;
            // a row with no point in the whole reach (most rows of the walls) costs two loads
            const std::uint32_t rowBase = grid.linear(0, cy, cz);
            if (start[rowBase + std::uint32_t(x0)] == start[rowBase + std::uint32_t(x1) + 1])
              continue;
            // the cells of the row that the largest support reaches
            const Real w = std::sqrt(hMax2 - dyz2) + margin;
            const int rx0 = std::max(x0, floorCell((xi.x() - w - origin.x()) * invCell));
            const int rx1 = std::min(x1, floorCell((xi.x() + w - origin.x()) * invCell));
            if (rx0 > rx1)
              continue;
            if (!src.H) {
              // cells rx0..rx1 of one row are contiguous in the sorted arrays
              const std::uint32_t b = start[rowBase + std::uint32_t(rx0)];
              const std::uint32_t e = start[rowBase + std::uint32_t(rx1) + 1];
              for (std::uint32_t j = b; j < e; ++j) {
                if (j != skip && (xi - sx[j]).squaredNorm() < hMax2)
                  emit(j + offset);
              }
              continue;
            }
            // Trim the row's ends to the cells whose own largest support reaches i: a fine particle's row is
            // sized for the coarsest support, and most cells hold only fine particles. (Cells inside the
            // trimmed range are scanned whole; empty cells have no points to scan.)
            const Real* cellMax = m_cellMaxH[std::size_t(s)].data() + rowBase;
            auto reaches = [&](int cx) {
              const Real hc = Real(0.5) * (Hi + cellMax[cx]);
              const Real dx = slabDistance(xi.x(), origin.x() + Real(cx) * cell, cell, margin);
              return dx * dx + dyz2 < hc * hc;
            };
            int cx0 = rx0;
            int cx1 = rx1;
            while (cx0 <= cx1 && !reaches(cx0))
              ++cx0;
            while (cx1 > cx0 && !reaches(cx1))
              --cx1;
            if (cx0 > cx1)
              continue;
            // cells cx0..cx1 of one row are contiguous in the sorted arrays
            const std::uint32_t b = start[rowBase + std::uint32_t(cx0)];
            const std::uint32_t e = start[rowBase + std::uint32_t(cx1) + 1];
            const Real* sH = src.H;
            for (std::uint32_t j = b; j < e; ++j) {
              const Real h = Real(0.5) * (Hi + sH[j]);
              if (j != skip && (xi - sx[j]).squaredNorm() < h * h)
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
    // last build's count with a sixteenth of slack (a chunk that outgrows it spills, see above); a chunk
    // never seen gets a guess
    const std::size_t last = out.chunkCounts[chunk];
    const std::size_t room = last > 0 ? last + last / 16 + 64 : 32 * kChunk;
    roomStart[chunk + 1] = roomStart[chunk] + room;
  }
  const std::size_t total = roomStart[nChunks];
  if (out.indices.capacity() < total)
    out.indices.reserve(total + total / 16);
  out.indices.resize(total);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nChunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& cr) {
                      for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk)
                        searchChunk(chunk);
                    });
  std::vector<std::size_t> listStart(nChunks + 1, 0);
  for (std::size_t chunk = 0; chunk < nChunks; ++chunk)
    listStart[chunk + 1] = listStart[chunk] + out.chunkCounts[chunk];
  if (std::find(overflowed.begin(), overflowed.end(), std::uint8_t(1)) == overflowed.end()) {
    // close up the rooms in place (each moves left, so in chunk order nothing is overwritten before it
    // is moved)
    for (std::size_t chunk = 0; chunk < nChunks; ++chunk) {
      if (listStart[chunk] != roomStart[chunk] && out.chunkCounts[chunk] > 0) {
        std::memmove(out.indices.data() + listStart[chunk], out.indices.data() + roomStart[chunk],
                     out.chunkCounts[chunk] * sizeof(std::uint32_t));
      }
    }
    out.indices.resize(listStart[nChunks]);
  } else {
    // some chunk outgrew its room (lists grew, or adaptivity moved coarse particles into it): gather into
    // a new array
    std::vector<std::uint32_t> merged(listStart[nChunks]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nChunks, 1),
                      [&](const tbb::blocked_range<std::size_t>& cr) {
                        for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
                          const std::size_t room = roomStart[chunk + 1] - roomStart[chunk];
                          const std::size_t inRoom = std::min<std::size_t>(room, out.chunkCounts[chunk]);
                          const auto from = out.indices.begin() + std::ptrdiff_t(roomStart[chunk]);
                          const auto to = std::copy(from, from + std::ptrdiff_t(inRoom),
                                                    merged.begin() + std::ptrdiff_t(listStart[chunk]));
                          std::copy(spills[chunk].begin(), spills[chunk].end(), to);
                        }
                      });
    out.indices.swap(merged);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nChunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& cr) {
                      for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
                        const std::uint32_t base = std::uint32_t(listStart[chunk]);
                        const std::size_t i1 = std::min(n, (chunk + 1) * kChunk);
                        for (std::size_t i = chunk * kChunk; i < i1; ++i)
                          out.offsets[i + 1] += base;
                      }
                    });
}

}  // namespace fp::sim
