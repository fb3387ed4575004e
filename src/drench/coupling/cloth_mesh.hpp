#pragma once
/// What the coupling needs from a cloth engine (Huber et al. 2013 sec. 5): node positions at the start and
/// end of the step, inverse masses and triangles. Any engine (Bullet through bullet_adapter/, a static rigid
/// mesh, a test) fills one of these; the coupler corrects the end positions in place, and the engine takes
/// them back with velocity += (corrected - predicted) / dt.

#include <array>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// A triangle mesh moving linearly over one step. All arrays of nodes have M entries, `triangles` has F.
struct ClothMesh {
  Vec3Array positions_t0;  ///< M, node positions at the start of the step (unit: m)
  Vec3Array positions_t1;  ///< M, at the end of the step: predicted by the engine, corrected by coupling (m)
  ScalarArray
      inverse_masses;  ///< M, 1 / node mass (unit: 1/kg); 0 = pinned or static, never moved by coupling
  std::vector<Triangle> triangles;  ///< F, node indices < M

  std::size_t node_count() const { return positions_t0.size(); }
  std::size_t triangle_count() const { return triangles.size(); }

  /// A static rigid mesh: both positions equal, every inverse mass 0 (the paper's V-shaped plane).
  static ClothMesh rigid(const Vec3Array& positions, std::vector<Triangle> triangles);

  /// A square grid of n x n nodes (n >= 2) spanning [x0, x0 + size] x [z0, z0 + size] at height y (unit: m),
  /// 2 (n - 1)^2 triangles with normal +y, not moving, every node of inverse mass `inverse_mass` (1/kg).
  static ClothMesh grid(int n, double size, double y, double inverse_mass, double x0 = 0.0, double z0 = 0.0);

  /// Throws drench::Error naming the first problem: arrays of different lengths, an index out of range, a
  /// repeated index in a triangle, a negative or non-finite inverse mass, a non-finite position.
  void validate() const;
};

/// a == b, as std::vector's ==, in one comparison of the bytes (indices have no padding and compare as
/// bytes): std::vector's compares each triangle in a call of its own, which was most of a check that found
/// a mesh's triangles unchanged (the grid broad phase's, the leak audit's between steps; issue 41's profile).
/// @param a, b  triangle lists of any lengths
bool same_triangles(const std::vector<Triangle>& a, const std::vector<Triangle>& b);

}  // namespace drench
