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
  /// Bins every triangle of `obstacles` (borrowed; they must outlive this) into the cells its bounding box
  /// overlaps, on the finest of the levels of cells `cell` (unit: m, > 0), 2 `cell`, 4 `cell`, ... where
  /// that box spans at most two cells along each axis. One level would bin a game's ground quad of 200 m
  /// into 10^8 cells of 2 cm: five steps of the surface effect over it took 109 s and 8.7 GB.
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
  bool empty() const { return m_empty; }
  /// How many (cell, triangle) entries the levels hold: at most 8 a triangle.
  std::size_t entry_count() const;

 private:
  struct Box {
    Vec3 lo, hi;
  };
  using Bins = std::unordered_map<std::uint64_t, std::vector<std::pair<Index, Index>>>;
  /// The cell of x on a level of cells of size `size`.
  static Vec3i cell_of(const Vec3& x, Scalar size);
  static std::uint64_t key(const Vec3i& c);
  Scalar m_cell = 1.0;
  std::vector<std::vector<Box>> m_boxes;  // per obstacle, per triangle
  std::vector<Bins> m_levels;             // level k: cells of m_cell 2^k, empty where no triangle is
  bool m_empty = true;
};

}  // namespace drench
