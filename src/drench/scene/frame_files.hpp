#pragma once
/// The frame files of a run (docs/output.md): the fluid's particles, the cloth, the obstacles and the surface
/// as PLY, written through io/ply_writer.hpp, which knows arrays only.

#include <string>
#include <vector>

#include <drench/common/triangle_mesh.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/sph/particle_set.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace drench {

/// The NNNN of a frame file's name `<prefix>NNNN.ply` (e.g. prefix "fluid_"), in `digits`; false when `name`
/// is not such a name (a temporary file's included). At most 18 digits, so that std::stoll cannot overflow.
bool frame_number(const std::string& name, const std::string& prefix, std::string& digits);

/// `positions` as the frame files hold them, every coordinate rounded to float32 (the writer's precision):
/// exactly what io/ply_reader.hpp reads back. The run's surface is made from these, so that `drench
/// reconstruct` on the saved frames gives the same surface.
Vec3Array positions_as_saved(const Vec3Array& positions);

/// The particles as a PLY point cloud: one `vertex` per particle with float properties x y z (unit: m),
/// vx vy vz (unit: m/s), density (unit: kg/m^3), pressure (unit: Pa) and uint id.
std::string particles_to_ply(const ParticleSet& particles);

/// particles_to_ply written atomically to `path`. @throws IoError
void write_particles_ply(const std::string& path, const ParticleSet& particles);

/// The cloth where it is now (`positions_t1`, unit: m) as a PLY triangle surface with vertex normals.
/// @throws IoError
void write_cloth_ply(const std::string& path, const ClothMesh& mesh);
/// The same with a float vertex property `wetness` (M values in [0, 1]: water held over capacity, the
/// "wetting" effect).
void write_cloth_ply(const std::string& path, const ClothMesh& mesh, const ScalarArray& wetness);
/// The static obstacles, all in one PLY triangle surface with vertex normals (unit: m). @throws IoError
void write_obstacles_ply(const std::string& path, const std::vector<TriangleMesh>& obstacles);
/// The fluid's reconstructed surface (surface/surface_reconstruction.hpp) as a PLY triangle surface with
/// vertex normals (unit: m). @throws IoError
void write_surface_ply(const std::string& path, const SurfaceMesh& mesh);

}  // namespace drench
