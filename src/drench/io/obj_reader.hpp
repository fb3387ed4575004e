#pragma once
/// Triangle meshes from Wavefront OBJ files, for a cloth (bullet_adapter/) and for static obstacles
/// (coupling/static_obstacles.hpp).

#include <cstdint>
#include <string>

#include <drench/common/triangle_mesh.hpp>

namespace drench {

/// Largest OBJ file read (unit: bytes): 1 GiB, some 20 million triangles, far beyond a cloth or obstacle the
/// coupling can step.
inline constexpr std::uint64_t kMaxObjFileBytes = std::uint64_t{1} << 30;

/// Reads an OBJ file with tinyobjloader, polygons triangulated (quads along a diagonal, larger polygons as
/// fans), every object of the file in one mesh; materials are not read. Vertices that no face uses are
/// dropped; the others keep their order. Lines and points are ignored. The text is checked first for what
/// tinyobjloader 2.0rc10 accepts silently: a coordinate such as "nan" (read as 0), a face of fewer than 3
/// vertices (dropped), and a face index that does not fit 32 bits (wrapped: 4294967299 became vertex 3).
/// @param key  the scene key the file came from, first in every message (e.g. "cloth.mesh")
/// @throws SceneError naming the key and the file (and the line where there is one): it is not a regular
///         file or is larger than kMaxObjFileBytes (checked before it is opened), it cannot be read or
///         parsed, a coordinate is not a finite number, a face has fewer than 3 vertices or is not a triangle
///         after triangulation, an index is not an integer, is 0, overflows 32 bits or is out of range (with
///         the line and the index as written), a face repeats a vertex or has zero area, no faces.
TriangleMesh load_obj_mesh(const std::string& path, const std::string& key = "cloth.mesh");

}  // namespace drench
