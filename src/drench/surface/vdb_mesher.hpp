#pragma once
/// The sparse grid of the surface's scalar field and its marching cubes, on OpenVDB (a FloatGrid and
/// tools::volumeToMesh, the library Houdini and Blender mesh with). OpenVDB is linked privately: no OpenVDB
/// type appears here.

#include <memory>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

class VdbNodeGrid {
 public:
  /// Nodes at integer multiples of `cell` (unit: m); a node never given a value holds `outside`.
  /// @throws Error naming the cell size when OpenVDB refuses the transform (a cell too small to invert);
  ///         every method turns OpenVDB's exceptions into drench::Error the same way.
  VdbNodeGrid(Scalar cell, float outside);
  ~VdbNodeGrid();
  VdbNodeGrid(const VdbNodeGrid&) = delete;
  VdbNodeGrid& operator=(const VdbNodeGrid&) = delete;

  /// Activates every node within `reach` nodes (a cube) of a node next to some particle: the nodes whose
  /// value some particle can change, so the work follows the fluid, not its bounding box.
  /// @throws Error naming the particle when its node index exceeds 2^30 (OpenVDB coordinates are int32)
  void activate_around(const Vec3Array& particles, int reach);
  /// Activates the nodes of the boxes [lo[i], hi[i]] (node indices, inclusive, within 2^30 + 64 of 0: see
  /// check_range; `lo` and `hi` the same length): each the box of an anisotropic kernel's support, which
  /// for a flattened kernel holds far fewer nodes than the cube of its longest axis. Sets the bits of
  /// OpenVDB's leaves directly, 64 nodes a word.
  void activate_boxes(const std::vector<Vec3i>& lo, const std::vector<Vec3i>& hi);
  /// Throws the error activate_around throws for a point whose node is beyond the grid's int32
  /// coordinates (|x| / cell > 2^30), naming its index in `points`.
  void check_range(const Vec3Array& points) const;
  /// The active nodes' integer coordinates, in the grid's fixed traversal order.
  std::vector<Vec3i> active_nodes() const;
  /// Sets the value of each node (same length as `nodes`).
  void set_values(const std::vector<Vec3i>& nodes, const std::vector<float>& values);
  /// Marching cubes at the zero level: vertices (unit: m) and triangles wound counter-clockwise seen from
  /// the positive side (outside the fluid).
  void mesh(Vec3Array& positions, std::vector<Triangle>& triangles) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace drench
