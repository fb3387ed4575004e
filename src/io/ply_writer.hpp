#pragma once
/// Binary little-endian PLY files, which ParaView, Blender and Houdini open directly.

#include <string>

#include "sph/particle_set.hpp"

namespace drench {

/// Serialises particles as a PLY point cloud: one `vertex` element per particle with float properties
/// x y z (unit: m), vx vy vz (unit: m/s), density (unit: kg/m^3), pressure (unit: Pa) and uint id.
/// Values are rounded to float32, which keeps files small and is read by every viewer.
std::string particles_to_ply(const ParticleSet& particles);

/// particles_to_ply written atomically to `path`. @throws IoError
void write_particles_ply(const std::string& path, const ParticleSet& particles);

}  // namespace drench
