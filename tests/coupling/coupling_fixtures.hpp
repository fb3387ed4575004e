#pragma once
/// Small meshes and particle sets for the coupling tests.

#include <random>
#include <vector>

#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench::test {

/// ClothMesh::grid, under the name the tests use.
inline ClothMesh grid_mesh(int n, double size, double y, double inverse_mass, double x0 = 0.0,
                           double z0 = 0.0) {
  return ClothMesh::grid(n, size, y, inverse_mass, x0, z0);
}

/// Particle arrays for a FluidView.
struct Particles {
  Vec3Array x0, x1, v;
  ScalarArray m;

  void add(const Vec3& start, const Vec3& velocity, double dt, double mass) {
    x0.push_back(start);
    x1.push_back(start + velocity * dt);
    v.push_back(velocity);
    m.push_back(mass);
  }
  FluidView view() { return FluidView{&x0, &x1, &v, &m}; }
};

/// Adds to `fluid`, at rest, the points of a cubic lattice of `spacing` (unit: m) within 3.5 spacings of
/// `centre` (unit: m): a droplet of 179 particles, ids from 0 (the fluid must be empty).
inline void add_droplet(FluidSolver& fluid, const Vec3& centre, double spacing) {
  std::uint32_t id = 0;
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j)
      for (int k = -3; k <= 3; ++k) {
        const Vec3 offset = spacing * Vec3(i, j, k);
        if (offset.norm() <= 3.5 * spacing)
          fluid.particles().add(centre + offset, Vec3::Zero(), fluid.particle_mass(), id++);
      }
}

}  // namespace drench::test
