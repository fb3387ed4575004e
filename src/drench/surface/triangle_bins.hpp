#pragma once
/// The triangles of the cloth and obstacles binned in cubic cells, for the surface's queries: which
/// triangles can a grid node's kernel reach (sec. 4, Fig. 2), which can a surface triangle meet.

#include <unordered_map>
#include <utility>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace drench {

class TriangleBins {
 public:
  TriangleBins() = default;
  /// Bins every triangle of `obstacles` (borrowed; they must outlive this) into the cells of size `cell`
  /// (unit: m, > 0) its bounding box overlaps.
  TriangleBins(const std::vector<SurfaceObstacle>& obstacles, Scalar cell);
  /// (obstacle, triangle) pairs whose bounding box overlaps the box [lo, hi], sorted, each once; `out` is
  /// replaced.
  void collect_box(const Vec3& lo, const Vec3& hi, std::vector<std::pair<Index, Index>>& out) const;
  /// The same for the cube of half-width `reach` around x.
  void collect_near(const Vec3& x, Scalar reach, std::vector<std::pair<Index, Index>>& out) const {
    collect_box(x - Vec3::Constant(reach), x + Vec3::Constant(reach), out);
  }
  /// The pairs of `candidates` (a collect_box answer for a box containing [lo, hi]) whose bounding box
  /// overlaps [lo, hi], in their order: the same list collect_box(lo, hi) gives, without the hash lookups
  /// and the sort. `out` is replaced.
  void filter_box(const std::vector<std::pair<Index, Index>>& candidates, const Vec3& lo, const Vec3& hi,
                  std::vector<std::pair<Index, Index>>& out) const;
  bool empty() const { return m_bins.empty(); }

 private:
  struct Box {
    Vec3 lo, hi;
  };
  Vec3i cell_of(const Vec3& x) const;
  static std::uint64_t key(const Vec3i& c);
  Scalar m_cell = 1.0;
  std::vector<std::vector<Box>> m_boxes;  // per obstacle, per triangle
  std::unordered_map<std::uint64_t, std::vector<std::pair<Index, Index>>> m_bins;
};

}  // namespace drench
