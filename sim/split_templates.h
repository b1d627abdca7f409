#pragma once
/// Split patterns for 1:n particle splitting (n = 2 .. 27), after Vacondio et al. 2013 and Winchenbach & Kolb
/// 2021: child offsets, in units of the parent's radius, chosen so that the n children of mass m/n (each with
/// the support of its own mass) reproduce the parent's kernel-weighted volume field W(x, H_o) as closely as
/// possible in the least-squares sense over the parent's support. Perfect cubes (8, 27) are the cubic lattice
/// of the children's own spacing, which reproduces a lattice of parents exactly; the other patterns are found
/// by a deterministic gradient descent from a Fibonacci-ball start (so 1:2 is a segment, 1:3 the triangle of
/// the paper's figure 1, 1:4 a tetrahedron).

#include <vector>

#include "sim/types.h"

namespace fp::sim {

/// The precomputed patterns; built once per process on first use (thread-safe).
class SplitTemplates {
 public:
  /// smallest and largest supported child counts
  static constexpr int kMinChildren = 2;
  static constexpr int kMaxChildren = 27;

  /// the shared instance
  static const SplitTemplates& get();

  /// child offsets of the 1:n pattern for a parent of radius 1 (support 4), centred on the parent (their mean
  /// is zero); kMinChildren <= n <= kMaxChildren
  const std::vector<Vec3d>& offsets(int n) const { return m_offsets[std::size_t(n)]; }
  /// least-squares mismatch of the pattern's volume field against the parent's, relative to the parent's own
  /// squared field (0 = perfect)
  double residual(int n) const { return m_residual[std::size_t(n)]; }

 private:
  SplitTemplates();
  std::vector<std::vector<Vec3d>> m_offsets;
  std::vector<double> m_residual;
};

}  // namespace fp::sim
