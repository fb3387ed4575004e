#include "io/ply_writer.hpp"

#include <cstdint>
#include <cstring>

#include "io/atomic_file.hpp"

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

}  // namespace

std::string particles_to_ply(const ParticleSet& particles) {
  const std::size_t n = particles.size();
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment drench " DRENCH_VERSION
                    " fluid particles, SI units\n"
                    "element vertex " +
                    std::to_string(n) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float vx\nproperty float vy\nproperty float vz\n"
                    "property float density\nproperty float pressure\nproperty uint id\nend_header\n";
  out.reserve(out.size() + n * 36);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(particles.positions[i][a]));
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(particles.velocities[i][a]));
    append_le(out, static_cast<float>(particles.densities[i]));
    append_le(out, static_cast<float>(particles.pressures[i]));
    append_le(out, static_cast<std::uint32_t>(particles.ids[i]));
  }
  return out;
}

void write_particles_ply(const std::string& path, const ParticleSet& particles) {
  write_file_atomic(path, particles_to_ply(particles));
}

std::string mesh_to_ply(const Vec3Array& positions, const std::vector<Triangle>& triangles) {
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
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment drench " DRENCH_VERSION
                    " cloth mesh, SI units\nelement vertex " +
                    std::to_string(positions.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float nx\nproperty float ny\nproperty float nz\nelement face " +
                    std::to_string(triangles.size()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + positions.size() * 24 + triangles.size() * 13);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(positions[i][a]));
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(normals[i][a]));
  }
  for (const Triangle& t : triangles) {
    append_le(out, static_cast<std::uint8_t>(3));
    for (Index v : t)
      append_le(out, static_cast<std::int32_t>(v));
  }
  return out;
}

void write_mesh_ply(const std::string& path, const Vec3Array& positions,
                    const std::vector<Triangle>& triangles) {
  write_file_atomic(path, mesh_to_ply(positions, triangles));
}

}  // namespace drench
