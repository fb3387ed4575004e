#include <drench/scene/frame_files.hpp>

#include <drench/io/ply_writer.hpp>

namespace drench {

bool frame_number(const std::string& name, const std::string& prefix, std::string& digits) {
  const std::string suffix = ".ply";
  if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  // 18 digits cannot overflow an int64; the writer's %04lld never makes more.
  return digits.size() <= 18 && digits.find_first_not_of("0123456789") == std::string::npos;
}

namespace {

std::vector<PlyProperty> particle_properties(const ParticleSet& particles) {
  return {PlyProperty::component("vx", particles.velocities, 0),
          PlyProperty::component("vy", particles.velocities, 1),
          PlyProperty::component("vz", particles.velocities, 2),
          PlyProperty::scalar("density", particles.densities),
          PlyProperty::scalar("pressure", particles.pressures),
          PlyProperty::uint32("id", particles.ids)};
}

}  // namespace

Vec3Array positions_as_saved(const Vec3Array& positions) {
  Vec3Array saved(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    saved[i] = positions[i].cast<float>().cast<Scalar>();
  return saved;
}

std::string particles_to_ply(const ParticleSet& particles) {
  return points_to_ply("fluid particles", particles.positions, particle_properties(particles));
}

void write_particles_ply(const std::string& path, const ParticleSet& particles) {
  write_points_ply(path, "fluid particles", particles.positions, particle_properties(particles));
}

void write_cloth_ply(const std::string& path, const ClothMesh& mesh) {
  write_mesh_ply(path, "cloth mesh", mesh.positions_t1, mesh.triangles);
}

void write_cloth_ply(const std::string& path, const ClothMesh& mesh, const ScalarArray& wetness) {
  write_mesh_ply(path, "cloth mesh", mesh.positions_t1, mesh.triangles,
                 {PlyProperty::scalar("wetness", wetness)});
}

void write_obstacles_ply(const std::string& path, const std::vector<TriangleMesh>& obstacles) {
  TriangleMesh all;
  for (const TriangleMesh& obstacle : obstacles) {
    const auto first = static_cast<Index>(all.positions.size());
    all.positions.insert(all.positions.end(), obstacle.positions.begin(), obstacle.positions.end());
    for (const Triangle& t : obstacle.triangles)
      all.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  }
  write_mesh_ply(path, "static obstacles", all.positions, all.triangles);
}

void write_surface_ply(const std::string& path, const SurfaceMesh& mesh) {
  write_mesh_ply(path, "fluid surface", mesh.positions, mesh.triangles);
}

}  // namespace drench
