#pragma once
/// Small meshes and particle sets for the coupling tests.

#include <random>
#include <vector>

#include "coupling/cloth_mesh.hpp"
#include "coupling/coupler.hpp"

namespace drench::test {

/// A square grid of n x n nodes spanning [x0, x0 + size] x [z0, z0 + size] at height y, split into 2 (n-1)^2
/// triangles (normal +y). Every node has inverse mass `inverse_mass`.
inline ClothMesh grid_mesh(int n, double size, double y, double inverse_mass, double x0 = 0.0,
                           double z0 = 0.0) {
  ClothMesh mesh;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh.positions_t0.emplace_back(x0 + size * i / (n - 1), y, z0 + size * j / (n - 1));
    }
  }
  mesh.positions_t1 = mesh.positions_t0;
  mesh.inverse_masses.assign(mesh.positions_t0.size(), inverse_mass);
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const Index a = static_cast<Index>(j * n + i);
      const Index b = a + 1;
      const Index c = a + static_cast<Index>(n);
      const Index d = c + 1;
      mesh.triangles.push_back({a, c, b});
      mesh.triangles.push_back({b, c, d});
    }
  }
  return mesh;
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
