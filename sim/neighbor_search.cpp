#include "sim/neighbor_search.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
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

void NeighborSearch::build(const UniformGrid& grid, const std::vector<Vec3>& qx, const std::vector<Real>& qH,
                           const std::vector<GridPoints>& sources, int selfSource, Real maxH,
                           NeighborList& out) {
  const std::size_t n = qx.size();
  const std::size_t nChunks = (n + kChunk - 1) / kChunk;
  if (m_chunks.size() < nChunks)
    m_chunks.resize(nChunks);
  out.offsets.resize(n + 1);
  out.offsets[0] = 0;
  const Eigen::Vector3i dims = grid.dims();
  const Real invCell = Real(1) / grid.cellSize();

  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, nChunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
        for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
          std::vector<std::uint32_t>& buf = m_chunks[chunk].indices;
          buf.clear();
          const std::size_t i0 = chunk * kChunk;
          const std::size_t i1 = std::min(n, i0 + kChunk);
          for (std::size_t i = i0; i < i1; ++i) {
            const Vec3 xi = qx[i];
            const Real Hi = qH[i];
            const std::size_t before = buf.size();
            const Eigen::Vector3i c = grid.cellCoord(xi);
            // reach in cells: the largest pair support this particle can have
            const int reach = std::max(1, int(std::ceil(Real(0.5) * (Hi + maxH) * invCell)));
            const int x0 = std::max(0, c.x() - reach), x1 = std::min(dims.x() - 1, c.x() + reach);
            const int y0 = std::max(0, c.y() - reach), y1 = std::min(dims.y() - 1, c.y() + reach);
            const int z0 = std::max(0, c.z() - reach), z1 = std::min(dims.z() - 1, c.z() + reach);
            for (int s = 0; s < int(sources.size()); ++s) {
              const GridPoints& src = sources[s];
              const Vec3* sx = src.x;
              const std::vector<std::uint32_t>& start = *src.cellStart;
              const bool skipSelf = s == selfSource;
              for (int cz = z0; cz <= z1; ++cz) {
                for (int cy = y0; cy <= y1; ++cy) {
                  // cells x0..x1 of one row are contiguous in the sorted arrays
                  const std::uint32_t b = start[grid.linear(x0, cy, cz)];
                  const std::uint32_t e = start[grid.linear(x1, cy, cz) + 1];
                  if (src.H) {
                    const Real* sH = src.H;
                    for (std::uint32_t j = b; j < e; ++j) {
                      if (skipSelf && j == i)
                        continue;
                      const Real h = Real(0.5) * (Hi + sH[j]);
                      if ((xi - sx[j]).squaredNorm() < h * h)
                        buf.push_back(j + src.indexOffset);
                    }
                  } else {
                    const Real h = Real(0.5) * (Hi + src.uniformH);
                    const Real h2 = h * h;
                    for (std::uint32_t j = b; j < e; ++j) {
                      if (skipSelf && j == i)
                        continue;
                      if ((xi - sx[j]).squaredNorm() < h2)
                        buf.push_back(j + src.indexOffset);
                    }
                  }
                }
              }
            }
            out.offsets[i + 1] = std::uint32_t(buf.size() - before);
          }
        }
      });
  for (std::size_t i = 0; i < n; ++i)
    out.offsets[i + 1] += out.offsets[i];
  out.indices.resize(out.offsets[n]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nChunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& cr) {
                      for (std::size_t chunk = cr.begin(); chunk < cr.end(); ++chunk) {
                        const std::vector<std::uint32_t>& buf = m_chunks[chunk].indices;
                        std::copy(buf.begin(), buf.end(), out.indices.begin() + out.offsets[chunk * kChunk]);
                      }
                    });
}

std::size_t NeighborSearch::memoryBytes() const {
  std::size_t bytes = 0;
  for (const Chunk& c : m_chunks)
    bytes += c.indices.capacity() * sizeof(std::uint32_t);
  return bytes;
}

}  // namespace fp::sim
