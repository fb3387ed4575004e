#pragma once
/// A static triangle mesh: what an OBJ file (io/obj_reader.hpp) or a built-in obstacle
/// (coupling/static_obstacles.hpp) gives.

#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// M vertices and F triangles.
struct TriangleMesh {
  Vec3Array positions;              ///< M vertices (unit: m)
  std::vector<Triangle> triangles;  ///< F, indices < M
};

}  // namespace drench
