// Surface tension (forces/surface_tension.hpp), measured against the physics it claims: a cube of water in
// zero gravity pulls itself into a sphere (both models), and a resting droplet holds the Laplace pressure
// 2 sigma / R (the continuum surface force, the default, whose curvature is checked first).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <drench/sph/fluid_solver.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.001;  // m: 1 mm particles, below water's capillary length of 2.7 mm
constexpr Scalar kSigma = 0.072;    // N/m, water against air
constexpr Scalar kPi = 3.14159265358979323846;

/// A fluid without gravity or walls; WCSPH at speed of sound `c` (its pressure is the Tait pressure, a
/// physical pressure with the outside at 0), XSPH viscosity `viscosity` to let oscillations die out.
FluidSolver make_fluid(PressureSolverKind solver, Scalar viscosity, const SurfaceTensionSettings* tension,
                       Scalar c = 2.0) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = solver;
  settings.viscosity.coefficient = viscosity;
  return FluidSolver(settings, Vec3::Zero(), BoundaryParticles{}, {}, viscosity > 0.0, c, tension);
}

/// Fills the lattice points of `spacing` inside the ball of `radius` (m) around the origin.
void add_ball(FluidSolver& fluid, Scalar radius) {
  const int n = static_cast<int>(std::ceil(radius / kSpacing));
  const Scalar mass = fluid.particle_mass();
  std::uint32_t id = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const Vec3 x = kSpacing * Vec3(i, j, k);
        if (x.norm() <= radius) fluid.particles().add(x, Vec3::Zero(), mass, id++);
      }
}

/// Fills a cube of side particles on the lattice, centred at the origin.
void add_cube(FluidSolver& fluid, int side) {
  const Scalar mass = fluid.particle_mass();
  std::uint32_t id = 0;
  const Scalar offset = 0.5 * (side - 1);
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      for (int k = 0; k < side; ++k)
        fluid.particles().add(kSpacing * (Vec3(i, j, k) - Vec3::Constant(offset)), Vec3::Zero(), mass, id++);
}

/// pi^(1/3) (6 V)^(2/3) / A of the fluid's reconstructed surface (sec. 4's Zhu & Bridson field, no
/// obstacles): 1 for a sphere, 0.806 for a cube.
Scalar sphericity(const FluidSolver& fluid) {
  SurfaceSettings settings;
  settings.contact_aware = false;
  const SurfaceMesh mesh = reconstruct_surface(fluid.particles().positions, kSpacing, settings, {});
  Scalar volume = 0.0;
  Scalar area = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.positions[t[0]];
    const Vec3& b = mesh.positions[t[1]];
    const Vec3& c = mesh.positions[t[2]];
    volume += a.dot(b.cross(c)) / 6.0;
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return std::cbrt(kPi) * std::pow(6.0 * std::abs(volume), 2.0 / 3.0) / area;
}

/// The largest distance of a particle from the fluid's centre of mass (unit: m).
Scalar farthest_from_centre(const FluidSolver& fluid) {
  const Vec3Array& x = fluid.particles().positions;
  Vec3 centre = Vec3::Zero();
  for (const Vec3& xi : x)
    centre += xi / static_cast<Scalar>(x.size());
  Scalar farthest = 0.0;
  for (const Vec3& xi : x)
    farthest = std::max(farthest, (xi - centre).norm());
  return farthest;
}

// A 1 cm cube of water (1000 particles) in zero gravity, with water's sigma: its capillary time
// sqrt(rho R^3 / sigma) is 57 ms; within 50 ms it is a sphere with every pressure solver and either model
// (sphericity of the reconstructed surface above 0.95; the cube's is 0.868 there), all of it: no particle
// farther from the centre than 1.25 times the sphere's radius R = 6.2 mm (the cube's corners are at 1.26 R).
// Without surface tension it stays a cube (PBF's own artificial pressure once scattered a free cube without
// it, so PBF is checked with it only). Steps of 0.5 ms: the capillary limit sqrt(rho spacing^3 / (2 pi
// sigma)) is 1.5 ms, and PCISPH blew the cube apart at 1 ms (sphericity 0.25) where the other solvers held.
// The cube rings as it rounds (its l = 4 Rayleigh mode, period 43 ms, overshoots to an octahedron whose six
// tips are 2 x 2 particles): the continuum force alone let PCISPH's tips pinch off and fly away (24
// particles at 0.11 m/s, sphericity 0.943 at 50 ms), which its cohesion share (SurfaceTensionCsf) stops.
TEST(SurfaceTension, CubeOfWaterInZeroGravityBecomesASphere) {
  for (const PressureSolverKind solver : {PressureSolverKind::DFSPH, PressureSolverKind::PCISPH,
                                          PressureSolverKind::WCSPH, PressureSolverKind::PBF}) {
    for (const int model :
         {-1, static_cast<int>(SurfaceTensionModel::AKINCI), static_cast<int>(SurfaceTensionModel::CSF)}) {
      const bool with_tension = model >= 0;
      const SurfaceTensionSettings tension{kSigma, static_cast<SurfaceTensionModel>(std::max(model, 0))};
      // WCSPH at 10 m/s: Akinci's cohesion pulls the bulk together by about 420 Pa, which its compression
      // limit (5%) must hold (58 c^2 Pa).
      FluidSolver fluid = make_fluid(solver, 0.1, with_tension ? &tension : nullptr, 10.0);
      add_cube(fluid, 10);
      const Scalar initial = sphericity(fluid);
      for (int step = 1; step <= 100; ++step)
        ASSERT_TRUE(fluid.step(0.0005).ok()) << pressure_solver_name(solver) << " step " << step;
      const Scalar final_sphericity = sphericity(fluid);
      const Scalar radius = std::cbrt(3.0 * fluid.particles().size() / (4.0 * kPi)) * kSpacing;
      const Scalar farthest = farthest_from_centre(fluid);
      const char* name = !with_tension                               ? "without"
                         : tension.model == SurfaceTensionModel::CSF ? "csf"
                                                                     : "akinci";
      std::printf("[ measured ] %s %s: sphericity %.4f at 0 s, %.4f at 0.05 s; farthest particle %.2f R\n",
                  pressure_solver_name(solver), name, initial, final_sphericity, farthest / radius);
      if (with_tension) {
        EXPECT_GT(final_sphericity, 0.95) << pressure_solver_name(solver) << " " << name;
        EXPECT_LT(farthest, 1.25 * radius) << pressure_solver_name(solver) << " " << name;
      } else if (solver != PressureSolverKind::PBF) {
        EXPECT_LT(final_sphericity, 0.9) << pressure_solver_name(solver);
      }
    }
  }
}

// The continuum surface force's curvature on droplets cut from the particle lattice (the Laplace test's
// starting shapes), weighted by |g| as the force is: within 15% of 2 / R at R = 4.5, 8.5 and 12.5 spacings,
// R the radius of the droplet's volume (N spacing^3). Plain colour-gradient normals read 5-7 / R here.
TEST(SurfaceTension, CsfCurvatureOfALatticeDropletIsTwoOverR) {
  for (const Scalar radius_in_spacings : {4.5, 8.5, 12.5}) {
    const SurfaceTensionSettings tension{kSigma, SurfaceTensionModel::CSF};
    FluidSolver fluid = make_fluid(PressureSolverKind::WCSPH, 0.0, &tension, 10.0);
    add_ball(fluid, radius_in_spacings * kSpacing);
    ASSERT_TRUE(fluid.step(1e-7).ok());
    const auto* csf = dynamic_cast<const SurfaceTensionCsf*>(fluid.surface_tension());
    ASSERT_NE(csf, nullptr);
    const std::size_t n = fluid.particles().size();
    const Scalar radius = std::cbrt(3.0 * n / (4.0 * kPi)) * kSpacing;
    Scalar weighted = 0.0;
    Scalar weights = 0.0;
    Scalar lowest = 1e9;
    Scalar highest = -1e9;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& g = csf->colour_gradients()[i];
      const Scalar kappa = csf->curvatures()[i];
      if (kappa == 0.0) continue;
      weighted += g.norm() * kappa;
      weights += g.norm();
      lowest = std::min(lowest, kappa);
      highest = std::max(highest, kappa);
    }
    const Scalar mean = weighted / weights;
    std::printf("[ measured ] R %.4f m: kappa R / 2 %.3f (|g|-weighted), %.3f to %.3f\n", radius,
                0.5 * mean * radius, 0.5 * lowest * radius, 0.5 * highest * radius);
    EXPECT_NEAR(mean, 2.0 / radius, 0.15 * 2.0 / radius) << "R " << radius;
  }
}

// The continuum force's curvature is checked from 4.5 spacings up and its normals are smoothed over 4, so
// droplets smaller than a ball of 4 spacings (268 particles) take Akinci's pair forces instead: two droplets
// far apart, of 3 and 5 spacings, are told apart whole, and the small one's particles get no continuum
// curvature.
TEST(SurfaceTension, CsfLeavesDropletsBelowFourSpacingsToAkincisForces) {
  const SurfaceTensionSettings tension{kSigma, SurfaceTensionModel::CSF};
  FluidSolver fluid = make_fluid(PressureSolverKind::WCSPH, 0.0, &tension, 10.0);
  add_ball(fluid, 3.0 * kSpacing);
  const std::size_t small = fluid.particles().size();
  FluidSolver big = make_fluid(PressureSolverKind::WCSPH, 0.0, nullptr, 10.0);
  add_ball(big, 5.0 * kSpacing);
  for (std::size_t i = 0; i < big.particles().size(); ++i)
    fluid.particles().add(big.particles().positions[i] + Vec3(0.02, 0.0, 0.0), Vec3::Zero(),
                          fluid.particle_mass(), static_cast<std::uint32_t>(small + i));
  ASSERT_TRUE(fluid.step(1e-7).ok());
  const auto* csf = dynamic_cast<const SurfaceTensionCsf*>(fluid.surface_tension());
  ASSERT_NE(csf, nullptr);
  std::size_t small_unresolved = 0;
  std::size_t big_unresolved = 0;
  std::size_t small_curved = 0;
  for (std::size_t i = 0; i < fluid.particles().size(); ++i) {
    const bool in_small = fluid.particles().positions[i].x() < 0.01;
    (in_small ? small_unresolved : big_unresolved) += csf->unresolved()[i] ? 1 : 0;
    if (in_small && csf->curvatures()[i] != 0.0) ++small_curved;
  }
  std::printf("[ measured ] %zu and %zu particles: %zu and %zu in droplets too small\n", small,
              fluid.particles().size() - small, small_unresolved, big_unresolved);
  EXPECT_EQ(small_unresolved, small);
  EXPECT_EQ(big_unresolved, 0u);
  EXPECT_EQ(small_curved, 0u);
}

/// The virial pressure of the SPH pressure force's pairs at particle i (unit: Pa): (rho_i / 6) sum_j x_ij .
/// a_ij with a_ij = -m_j (p_i / rho_i^2 + p_j / rho_j^2) grad W_ij, from the solver's last densities and
/// pressures at the current positions (the fluid at rest barely moves in a sub-step). Equals p_i only where
/// sum_j V_j x_ij . grad W_ij is -3: on the cubic lattice the cubic spline gives -3.06.
Scalar pressure_force_virial(const FluidSolver& fluid, std::size_t i) {
  const ParticleSet& p = fluid.particles();
  const CubicSplineKernel& kernel = fluid.kernel();
  const Scalar support_sq = kernel.support_radius() * kernel.support_radius();
  const Scalar rho_i = p.densities[i];
  Scalar virial = 0.0;
  for (std::size_t j = 0; j < p.size(); ++j) {
    const Vec3 x_ij = p.positions[i] - p.positions[j];
    if (j == i || x_ij.squaredNorm() >= support_sq) continue;
    const Scalar rho_j = p.densities[j];
    const Scalar w = p.masses[j] * (p.pressures[i] / (rho_i * rho_i) + p.pressures[j] / (rho_j * rho_j));
    virial -= w * x_ij.dot(kernel.gradient(x_ij));
  }
  return rho_i * virial / 6.0;
}

// Inside a resting droplet the pressure should exceed the outside's (0) by 2 sigma / R (issue 43), here with
// the continuum surface force. The pressure measured is the mechanical one: the virial of every pair force
// (Irving & Kirkwood 1950, each pair shared by its two particles; the kinetic part is negligible at rest),
// (rho_i / 6) sum_j x_ij . a_ij over the SPH pressure force's pairs (WCSPH's Tait pressure is a physical one,
// 0 outside) and the surface tension's (for this model its cohesion's; the continuum force acts on the
// surface layer only), averaged over the particles within R / 2 of the centre, and over 0.05-0.1 s every 5
// ms: the small droplet still rings (26-36 Pa at single instants from 0.05 to 0.15 s without the cohesion).
// Measured: 35.2 Pa (34.3-35.8) at R = 4.5 mm (2 sigma / R 31.8) and 18.0 Pa (17.5-18.5) at 8.5 mm (17.0);
// without the cohesion 34.4 and 17.6 Pa. Akinci's model holds 94 and 73 Pa here: its pair forces' surface
// stress is not the surface energy its gamma is calibrated to (a flat slab's int (p_N - p_T) dz reads
// 0.003-0.152 N/m against 0.072), and its curvature term is no energy's gradient, so its droplets never rest
// (1-2 cm/s after 0.3 s).
TEST(SurfaceTension, RestingDropletHoldsTheLaplacePressure) {
  for (const Scalar radius_in_spacings : {4.5, 8.5}) {
    const SurfaceTensionSettings tension{kSigma, SurfaceTensionModel::CSF};
    FluidSolver fluid = make_fluid(PressureSolverKind::WCSPH, 0.1, &tension, 10.0);
    add_ball(fluid, radius_in_spacings * kSpacing);
    const std::size_t n = fluid.particles().size();
    const Scalar radius = std::cbrt(3.0 * n / (4.0 * kPi)) * kSpacing;
    Scalar sum = 0.0;
    Scalar lowest = 1e9;
    Scalar highest = -1e9;
    int samples = 0;
    for (int step = 1; step <= 100; ++step) {
      ASSERT_TRUE(fluid.step(0.001).ok()) << step;
      if (step < 50 || step % 5 != 0) continue;
      const ScalarArray& virial = fluid.surface_tension()->virial_pressures();
      Vec3 centre = Vec3::Zero();
      for (const Vec3& x : fluid.particles().positions)
        centre += x;
      centre /= static_cast<Scalar>(n);
      Scalar pressure = 0.0;
      int count = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if ((fluid.particles().positions[i] - centre).norm() < 0.5 * radius) {
          pressure += pressure_force_virial(fluid, i) + virial[i];
          ++count;
        }
      }
      pressure /= count;
      sum += pressure;
      lowest = std::min(lowest, pressure);
      highest = std::max(highest, pressure);
      ++samples;
    }
    const Scalar pressure = sum / samples;
    const Scalar laplace = 2.0 * kSigma / radius;
    std::printf("[ measured ] R %.4f m: inside %.2f Pa (%.1f to %.1f over %d samples), 2 sigma / R %.2f Pa\n",
                radius, pressure, lowest, highest, samples, laplace);
    EXPECT_NEAR(pressure, laplace, 0.15 * laplace) << "R " << radius;
  }
}

}  // namespace
}  // namespace drench
