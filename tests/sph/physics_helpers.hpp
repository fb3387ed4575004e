#pragma once
// Measurements shared by the physics tests.

#include <algorithm>
#include <string>
#include <vector>

#include <drench/scene/scene_loader.hpp>
#include <drench/scene/simulation.hpp>

namespace drench::testing {

/// A demo scene from demos/scenes with overrides, as `drench run --set` would load it.
inline SceneConfig demo_scene(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return load_scene_file(std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/" + name, overrides);
}

inline Scalar max_speed(const ParticleSet& p) {
  Scalar v = 0;
  for (const Vec3& u : p.velocities)
    v = std::max(v, u.norm());
  return v;
}

/// Kinetic plus gravitational potential energy (unit: J), potential zero at the origin.
inline Scalar total_energy(const ParticleSet& p, const Vec3& gravity) {
  Scalar e = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    e += p.masses[i] * (0.5 * p.velocities[i].squaredNorm() - gravity.dot(p.positions[i]));
  }
  return e;
}

inline bool all_finite(const ParticleSet& p) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p.positions[i].allFinite() || !p.velocities[i].allFinite()) return false;
  }
  return true;
}

/// Height of the free surface of a fluid resting on y = floor: the mean height of the top layer (the
/// `layer_count` highest particles) plus half a spacing, since each particle stands for a cube of fluid.
inline Scalar free_surface_height(const ParticleSet& p, std::size_t layer_count, Scalar spacing) {
  std::vector<Scalar> y;
  for (const Vec3& x : p.positions)
    y.push_back(x.y());
  std::sort(y.begin(), y.end(), std::greater<>());
  layer_count = std::min(layer_count, y.size());
  Scalar sum = 0;
  for (std::size_t k = 0; k < layer_count; ++k)
    sum += y[k];
  return sum / layer_count + 0.5 * spacing;
}

}  // namespace drench::testing
