#include <drench/io/ply_writer.hpp>

#include <cstring>
#include <stdexcept>

#include <drench/io/atomic_file.hpp>

namespace drench {

namespace {

static_assert(sizeof(float) == 4, "PLY float is 32-bit");

template <class T>
void append_le(std::string& out, T value) {
  // x86-64 and aarch64 are little-endian, as PLY's binary_little_endian asks.
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

std::string header_start(const std::string& description, std::size_t vertices) {
  return "ply\nformat binary_little_endian 1.0\ncomment drench " DRENCH_VERSION " " + description +
         ", SI units\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\n";
}

std::string property_lines(const std::vector<PlyProperty>& properties, std::size_t vertices) {
  std::string lines;
  for (const PlyProperty& property : properties) {
    if (property.count != vertices)
      throw std::invalid_argument("PLY property '" + property.name + "' has " +
                                  std::to_string(property.count) + " values for " + std::to_string(vertices) +
                                  " vertices");
    lines += (property.type == PlyProperty::Type::UINT32 ? "property uint " : "property float ") +
             property.name + "\n";
  }
  return lines;
}

void append_properties(std::string& out, const std::vector<PlyProperty>& properties, std::size_t i) {
  for (const PlyProperty& property : properties) {
    if (property.type == PlyProperty::Type::UINT32)
      append_le(out, property.ids[i]);
    else
      append_le(out, static_cast<float>(property.values[i * property.stride]));
  }
}

}  // namespace

PlyProperty PlyProperty::scalar(std::string name, const ScalarArray& values) {
  PlyProperty property;
  property.name = std::move(name);
  property.count = values.size();
  property.values = values.data();
  return property;
}

PlyProperty PlyProperty::component(std::string name, const Vec3Array& vectors, int axis) {
  PlyProperty property;
  property.name = std::move(name);
  property.count = vectors.size();
  property.values = vectors.empty() ? nullptr : coordinates(vectors) + axis;
  property.stride = 3;
  return property;
}

PlyProperty PlyProperty::uint32(std::string name, const std::vector<std::uint32_t>& values) {
  PlyProperty property;
  property.name = std::move(name);
  property.type = Type::UINT32;
  property.count = values.size();
  property.ids = values.data();
  return property;
}

std::string points_to_ply(const std::string& description, const Vec3Array& positions,
                          const std::vector<PlyProperty>& properties) {
  const std::size_t n = positions.size();
  std::string out = header_start(description, n) + property_lines(properties, n) + "end_header\n";
  out.reserve(out.size() + n * 4 * (3 + properties.size()));
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(positions[i][a]));
    append_properties(out, properties, i);
  }
  return out;
}

void write_points_ply(const std::string& path, const std::string& description, const Vec3Array& positions,
                      const std::vector<PlyProperty>& properties) {
  write_file_atomic(path, points_to_ply(description, positions, properties));
}

std::string mesh_to_ply(const std::string& description, const Vec3Array& positions,
                        const std::vector<Triangle>& triangles, const std::vector<PlyProperty>& properties) {
  Vec3Array normals(positions.size(), Vec3::Zero());
  for (const Triangle& t : triangles) {
    // The cross product's length is twice the area: summing it weights each face by its area.
    const Vec3 n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (Index v : t)
      normals[v] += n;
  }
  for (Vec3& n : normals) {
    const double length = n.norm();
    n = length > 0.0 ? Vec3(n / length) : Vec3::UnitY();
  }
  std::string out = header_start(description, positions.size()) +
                    "property float nx\nproperty float ny\nproperty float nz\n" +
                    property_lines(properties, positions.size()) + "element face " +
                    std::to_string(triangles.size()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + positions.size() * 4 * (6 + properties.size()) + triangles.size() * 13);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(positions[i][a]));
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(normals[i][a]));
    append_properties(out, properties, i);
  }
  for (const Triangle& t : triangles) {
    append_le(out, static_cast<std::uint8_t>(3));
    for (Index v : t)
      append_le(out, static_cast<std::int32_t>(v));
  }
  return out;
}

void write_mesh_ply(const std::string& path, const std::string& description, const Vec3Array& positions,
                    const std::vector<Triangle>& triangles, const std::vector<PlyProperty>& properties) {
  write_file_atomic(path, mesh_to_ply(description, positions, triangles, properties));
}

}  // namespace drench
