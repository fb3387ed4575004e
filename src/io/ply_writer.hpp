#pragma once
/// Binary little-endian PLY files, which ParaView, Blender and Houdini open directly.

#include <string>

#include "coupling/cloth_mesh.hpp"
#include "sph/particle_set.hpp"

namespace drench {

/// Serialises particles as a PLY point cloud: one `vertex` element per particle with float properties
/// x y z (unit: m), vx vy vz (unit: m/s), density (unit: kg/m^3), pressure (unit: Pa) and uint id.
/// Values are rounded to float32, which keeps files small and is read by every viewer.
std::string particles_to_ply(const ParticleSet& particles);

/// particles_to_ply written atomically to `path`. @throws IoError
void write_particles_ply(const std::string& path, const ParticleSet& particles);

/// Serialises a triangle mesh at `positions` (M nodes, unit: m) as a PLY surface: `vertex` with float x y z
/// and nx ny nz (area-weighted vertex normals, unit length), `face` with a uchar-counted list of int indices.
std::string mesh_to_ply(const Vec3Array& positions, const std::vector<Triangle>& triangles);

/// mesh_to_ply written atomically to `path`. @throws IoError
void write_mesh_ply(const std::string& path, const Vec3Array& positions,
                    const std::vector<Triangle>& triangles);

}  // namespace drench
