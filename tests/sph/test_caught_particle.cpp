// A particle caught inside a moving body's boundary shell, every pressure solver. A game's body moves
// centimetres per 1/60 s frame and its boundary is placed where the frame starts, so water can be found
// inside its shell (or squeezed between a body and the cloth): the shell's gradients cancel there, and with
// one fluid neighbour near the kernel's edge the solvers' denominators (DFSPH's eq. 11 factor, PBF's sum of
// constraint gradients) nearly vanish while the shell compresses the particle. The correction then grew as
// one over that neighbour's gradient and threw the pair apart: bench_game_frame's level sent DFSPH's
// particles to 3,100 m/s and PBF's to 111 m/s.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include <drench/sph/fluid_solver.hpp>

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.02;  // m
constexpr Scalar kDt = 0.005;      // s

/// Boundary points on the faces of a cube of side `side` centred at `centre`, one per spacing^2 patch at
/// the patch's centre, inset by 0.6 spacings as drench places a body's (coupling/rigid_boundary), with the
/// faces' outward normals: a body's shell as FluidSolver::set_moving_boundary takes it.
void cube_shell(const Vec3& centre, Scalar side, Vec3Array& points, ScalarArray& volumes,
                Vec3Array& normals) {
  const int cells = static_cast<int>(std::lround(side / kSpacing));
  for (int axis = 0; axis < 3; ++axis) {
    for (const Scalar sign : {-1.0, 1.0}) {
      Vec3 normal = Vec3::Zero();
      normal[axis] = sign;
      for (int a = 0; a < cells; ++a) {
        for (int b = 0; b < cells; ++b) {
          Vec3 p = centre + (0.5 * side - 0.6 * kSpacing) * normal;
          p[(axis + 1) % 3] += (a + 0.5) * kSpacing - 0.5 * side;
          p[(axis + 2) % 3] += (b + 0.5) * kSpacing - 0.5 * side;
          points.push_back(p);
          volumes.push_back(kSpacing * kSpacing * kSpacing);
          normals.push_back(normal);
        }
      }
    }
  }
}

class CaughtParticle : public testing::TestWithParam<PressureSolverKind> {};

TEST_P(CaughtParticle, DoesNotThrowItsNeighbour) {
  // One particle in a shell of 2 spacings, its neighbour outside at 1.5, 1.8 and 1.95 spacings. The caught
  // particle may leave the shell in the step (a spacing to a face, and PBF moves it out within its
  // sub-steps), but no particle may move two spacings, and the push may not grow as the neighbour nears the
  // kernel's edge. With the denominators' former floor (1e-6 of a filled lattice's) DFSPH threw the pair at
  // 1.68, 10.5 and 168 m/s; with PBF's denominator kept from the prediction the caught particle left at 39.
  const Vec3 centre = Vec3::Constant(0.1);
  Vec3Array points, normals;
  ScalarArray volumes;
  cube_shell(centre, 2 * kSpacing, points, volumes, normals);
  const Scalar bound = 2 * kSpacing / kDt;
  std::vector<Scalar> speeds;
  for (const Scalar distance : {1.5, 1.8, 1.95}) {
    FluidSettings settings;
    settings.particle_spacing = kSpacing;
    settings.pressure_solver = GetParam();
    FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0);
    const Scalar mass = settings.rest_density * kSpacing * kSpacing * kSpacing;
    fluid.particles().add(centre, Vec3::Zero(), mass, 0);
    fluid.particles().add(centre + Vec3(distance * kSpacing, 0, 0), Vec3::Zero(), mass, 1);
    fluid.set_moving_boundary(points, volumes, normals);
    ASSERT_TRUE(fluid.step(kDt).ok());
    speeds.push_back(fluid.max_speed());
    std::printf("[ measured ] %s, neighbour at %.2f spacings: fastest particle %.3g m/s (bound %.3g)\n",
                pressure_solver_name(GetParam()), distance, speeds.back(), bound);
    EXPECT_LT(speeds.back(), bound);
  }
  EXPECT_LE(speeds.back(), speeds.front());
}

INSTANTIATE_TEST_SUITE_P(EverySolver, CaughtParticle,
                         testing::Values(PressureSolverKind::WCSPH, PressureSolverKind::PCISPH,
                                         PressureSolverKind::DFSPH, PressureSolverKind::PBF),
                         [](const testing::TestParamInfo<PressureSolverKind>& param) {
                           return std::string(pressure_solver_name(param.param));
                         });

}  // namespace
}  // namespace drench
