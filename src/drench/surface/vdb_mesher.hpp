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
  /// The same with a reach per particle (N entries, >= 0, in nodes): a kernel's own reach, so that a small
  /// kernel does not activate the nodes only the longest one can change.
  void activate_around(const Vec3Array& particles, const std::vector<int>& reaches);
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
