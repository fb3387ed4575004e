#pragma once
/// Binary little-endian PLY files, which ParaView, Blender and Houdini open directly. The writer knows
/// arrays, not simulation objects: callers name the per-vertex properties they want written
/// (scene/frame_files.hpp writes the fluid's particles and the cloth this way).

#include <cstdint>
#include <string>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// One per-vertex property of a PLY `vertex` element: `count` values, written as float32 from
/// `values[i * stride]` (unit: whatever the caller's array holds), or as uint32 from `ids[i]`. The arrays are
/// borrowed and must outlive the call that writes them.
struct PlyProperty {
  enum class Type { FLOAT32, UINT32 };
  std::string name;
  Type type = Type::FLOAT32;
  std::size_t count = 0;
  const Scalar* values = nullptr;
  std::size_t stride = 1;
  const std::uint32_t* ids = nullptr;

  /// A float32 property from one value per vertex.
  static PlyProperty scalar(std::string name, const ScalarArray& values);
  /// A float32 property from component `axis` (0, 1 or 2) of one vector per vertex.
  static PlyProperty component(std::string name, const Vec3Array& vectors, int axis);
  /// A uint32 property (particle ids).
  static PlyProperty uint32(std::string name, const std::vector<std::uint32_t>& values);
};

/// A PLY point cloud: one `vertex` per entry of `positions` (N, unit: m) with float x y z, then `properties`
/// in their order. `description` goes into the header's comment ("drench <version> <description>, SI
/// units"). Values are rounded to float32, which keeps files small and is read by every viewer.
/// @throws std::invalid_argument when a property does not have N values (the message names it).
std::string points_to_ply(const std::string& description, const Vec3Array& positions,
                          const std::vector<PlyProperty>& properties);

/// points_to_ply written atomically to `path`. @throws IoError, std::invalid_argument
void write_points_ply(const std::string& path, const std::string& description, const Vec3Array& positions,
                      const std::vector<PlyProperty>& properties);

/// A PLY triangle surface at `positions` (M nodes, unit: m): `vertex` with float x y z and nx ny nz
/// (area-weighted vertex normals, unit length), then `properties` (M values each), and `face` with a
/// uchar-counted list of int indices, one per entry of `triangles` (F, node indices < M).
/// @throws std::invalid_argument when a property does not have M values.
std::string mesh_to_ply(const std::string& description, const Vec3Array& positions,
                        const std::vector<Triangle>& triangles,
                        const std::vector<PlyProperty>& properties = {});

/// mesh_to_ply written atomically to `path`. @throws IoError, std::invalid_argument
void write_mesh_ply(const std::string& path, const std::string& description, const Vec3Array& positions,
                    const std::vector<Triangle>& triangles, const std::vector<PlyProperty>& properties = {});

}  // namespace drench
