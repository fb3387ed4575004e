#pragma once
/// Small meshes and particle sets for the coupling tests.

#include <random>
#include <vector>

#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>

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

}  // namespace drench::test
