#pragma once
/// Small meshes and particle sets for the coupling tests.

#include <random>
#include <vector>

#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/rigid_bodies.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench::test {

/// A rigid body's surface: the cube of side `side` (unit: m) with its lowest corner at `corner`, 8 nodes at
/// rest, 12 faces turned outward (counter-clockwise seen from outside).
inline RigidSurface cube_surface(std::uint64_t key, RigidMotion motion, const Vec3& corner, double side) {
  RigidSurface s;
  s.key = key;
  s.motion = motion;
  for (int i = 0; i < 8; ++i)
    s.positions_t0.push_back(corner + side * Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  const Index faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
  const Vec3 centre = corner + Vec3::Constant(0.5 * side);
  const Vec3Array& x = s.positions_t0;
  for (const auto& f : faces) {
    for (const Triangle t : {Triangle{f[0], f[1], f[2]}, Triangle{f[0], f[2], f[3]}}) {
      const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
      s.triangles.push_back(n.dot(x[t[0]] - centre) > 0.0 ? t : Triangle{t[0], t[2], t[1]});
    }
  }
  s.positions_t1 = s.positions_t0;
  s.velocities_t0.assign(8, Vec3::Zero());
  return s;
}

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
