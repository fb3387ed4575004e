// Adhesion (the coupler's adhere stage, coupler_stages.hpp): a droplet of water under a horizontal plate
// clings to it with adhesion and falls without, and the plate carries the droplet's weight; a droplet on a
// plate spreads over a cotton one and beads on a water-repellent one.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include <drench/coupling/coupler.hpp>
#include <drench/sph/fluid_solver.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.001;  // m
constexpr Scalar kSigma = 0.072;    // N/m, water
constexpr Scalar kDt = 0.0005;      // s
constexpr Scalar kPi = 3.14159265358979323846;
constexpr int kSteps = 400;  // 0.2 s: a free droplet falls 0.2 m in it

struct Hanging {
  Scalar centre_y = 0.0;         ///< the droplet's centre of mass at the end (unit: m)
  Scalar plate_impulse_y = 0.0;  ///< what the plate took over the second half (unit: N s)
  Scalar weight_impulse = 0.0;   ///< the droplet's weight times that time (unit: N s)
};

/// A half ball of water of radius 3 mm, flat side up, a particle spacing under a static plate at y = 0 (a
/// 2 cm grid, inverse mass 0), under gravity, with surface tension; the plate has the work of adhesion
/// `work` (N/m), or none when 0.
Hanging hang(Scalar work) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = PressureSolverKind::DFSPH;
  const SurfaceTensionSettings tension{kSigma};
  const Vec3 gravity(0.0, -9.81, 0.0);
  FluidSolver fluid(settings, gravity, BoundaryParticles{}, {}, true, 10.0, &tension);
  const Scalar radius = 3.0 * kSpacing;
  std::uint32_t id = 0;
  for (int i = -3; i <= 3; ++i)
    for (int j = 0; j <= 3; ++j)
      for (int k = -3; k <= 3; ++k) {
        const Vec3 offset = kSpacing * Vec3(i, -j, k);
        if (offset.norm() <= radius)
          fluid.particles().add(offset - Vec3(0.0, kSpacing, 0.0), Vec3::Zero(), fluid.particle_mass(), id++);
      }
  ClothMesh plate = ClothMesh::grid(21, 0.02, 0.0, 0.0, -0.01, -0.01);
  CouplingSettings coupling;
  coupling.cloth_thickness = 0.5 * kSpacing;
  Coupler coupler(coupling, false);
  if (work > 0.0) {
    AdhesionSettings adhesion;
    adhesion.work.assign(plate.triangle_count(), work);
    adhesion.range = 2.0 * kSpacing;
    adhesion.rest_density = settings.rest_density;
    coupler.set_adhesion(adhesion);
  }
  Hanging result;
  Scalar mass = 0.0;
  for (const Scalar m : fluid.particles().masses)
    mass += m;
  for (int step = 1; step <= kSteps; ++step) {
    EXPECT_TRUE(fluid.step(kDt).ok()) << step;
    ParticleSet& p = fluid.particles();
    const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses, nullptr};
    CouplingStepStats stats;
    coupler.step(view, plate, kDt, stats);
    if (step > kSteps / 2) {
      for (const Vec3& j : coupler.node_impulses())
        result.plate_impulse_y += j.y();
      result.weight_impulse += mass * gravity.y() * kDt;
    }
  }
  for (const Vec3& x : fluid.particles().positions)
    result.centre_y += x.y() / static_cast<Scalar>(fluid.particles().size());
  return result;
}

TEST(Adhesion, DropletClingsUnderAPlateWithAdhesionAndFallsWithout) {
  // Water on a face it wets fully: Dupre's sigma (1 + cos 0) = 0.144 N/m.
  const Hanging wet = hang(2.0 * kSigma);
  const Hanging dry = hang(0.0);
  std::printf(
      "[ measured ] centre after 0.2 s: %.4f m with adhesion, %.4f m without; plate took %.3g N s, "
      "weight %.3g N s over the last 0.1 s\n",
      wet.centre_y, dry.centre_y, wet.plate_impulse_y, wet.weight_impulse);
  // Hanging: its centre stays within its own radius (3 mm) of where it started (-2.2 mm).
  EXPECT_GT(wet.centre_y, -0.0052);
  // Fallen: free fall takes it 0.196 m down in 0.2 s; half of that is far from the plate's reach (2 mm).
  EXPECT_LT(dry.centre_y, -0.09);
  // What holds the droplet, the plate takes: its weight over the time, within 20% (the droplet still
  // wobbles).
  EXPECT_NEAR(wet.plate_impulse_y, wet.weight_impulse, 0.2 * std::abs(wet.weight_impulse));
}

struct Resting {
  Scalar contact_radius = 0.0;  ///< of the water touching the plate (unit: m)
  Scalar touching = 0.0;        ///< fraction of the particles within 1.5 spacings of the plate
  Scalar contact_angle = 0.0;   ///< of the spherical cap of the droplet's volume and height (unit: degree)
  Scalar lowest = 0.0;          ///< the lowest particle's height over the plate (unit: m)
  Scalar volume_radius = 0.0;   ///< R0, the radius of the ball of the droplet's volume, N spacing^3 (m)
};

/// A ball of water of radius 3.5 mm (179 particles) let down a particle spacing above a static plate at
/// y = 0 (6 cm wide, inverse mass 0), with water's surface tension, left to settle for 0.2 s (the capillary
/// time sqrt(rho R^3 / sigma) is 24 ms); the plate has the work of adhesion `work` (N/m). Gravity is a tenth
/// of the earth's: the Bond number rho g R^2 / sigma is then 0.17, a 1.1 mm droplet's on the earth, so the
/// droplet's shape is its contact angle's and not a puddle's (at 9.81 m/s^2, 1.7, the droplet without
/// adhesion flattened to a contact radius of 0.97 R0). Free slip.
/// What it measures: the contact radius, sqrt(2) times the RMS distance from the droplet's vertical axis of
/// the particles within 1.5 spacings of the plate (the radius of a uniform disc of that RMS); and the
/// contact angle theta of the spherical cap of the droplet's volume V and height H (its top particle plus
/// half a spacing): V = pi H^2 (3 Rc - H) / 3 gives the cap's sphere radius Rc, cos theta = 1 - H / Rc.
Resting rest(Scalar work) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = PressureSolverKind::DFSPH;
  const SurfaceTensionSettings tension{kSigma};
  FluidSolver fluid(settings, Vec3(0.0, -0.981, 0.0), BoundaryParticles{}, {}, true, 10.0, &tension);
  test::add_droplet(fluid, Vec3(0.0, 4.0 * kSpacing, 0.0), kSpacing);
  // Wider than the droplet's spread on cotton (about 1 cm).
  ClothMesh plate = ClothMesh::grid(41, 0.06, 0.0, 0.0, -0.03, -0.03);
  CouplingSettings coupling;
  coupling.cloth_thickness = 0.5 * kSpacing;
  Coupler coupler(coupling, false);
  AdhesionSettings adhesion;
  adhesion.work.assign(plate.triangle_count(), work);
  adhesion.range = 2.0 * kSpacing;
  adhesion.rest_density = settings.rest_density;
  coupler.set_adhesion(adhesion);
  for (int step = 1; step <= kSteps; ++step) {
    EXPECT_TRUE(fluid.step(kDt).ok()) << step;
    ParticleSet& p = fluid.particles();
    const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses, nullptr};
    CouplingStepStats stats;
    EXPECT_EQ(coupler.step(view, plate, kDt, stats), COUPLING_OK) << step;
  }
  const Vec3Array& x = fluid.particles().positions;
  const Scalar n = static_cast<Scalar>(x.size());
  Vec3 centre = Vec3::Zero();
  for (const Vec3& xi : x)
    centre += xi / n;
  Resting result;
  result.lowest = x.front().y();
  Scalar top = x.front().y();
  Scalar sum_r2 = 0.0;
  int touching = 0;
  for (const Vec3& xi : x) {
    result.lowest = std::min(result.lowest, xi.y());
    top = std::max(top, xi.y());
    if (xi.y() > 1.5 * kSpacing) continue;
    ++touching;
    sum_r2 += std::pow(xi.x() - centre.x(), 2) + std::pow(xi.z() - centre.z(), 2);
  }
  result.touching = touching / n;
  result.contact_radius = touching > 0 ? std::sqrt(2.0 * sum_r2 / touching) : 0.0;
  const Scalar volume = n * kSpacing * kSpacing * kSpacing;
  result.volume_radius = std::cbrt(3.0 * volume / (4.0 * kPi));
  const Scalar height = top + 0.5 * kSpacing;
  const Scalar cap_radius = (3.0 * volume / (kPi * height * height) + height) / 3.0;
  result.contact_angle = std::acos(std::clamp(1.0 - height / cap_radius, -1.0, 1.0)) * 180.0 / kPi;
  return result;
}

/// Young-Dupre's contact angle for the work of adhesion W (N/m): cos theta = W / sigma - 1 (unit: degree).
Scalar young_dupre_angle(Scalar work) {
  return std::acos(work / kSigma - 1.0) * 180.0 / kPi;
}

/// The base radius of a spherical cap of volume 4/3 pi R0^3 meeting a plane at contact angle theta (degree),
/// in units of R0.
Scalar cap_base_radius(Scalar theta_degree) {
  const Scalar c = std::cos(theta_degree * kPi / 180.0);
  return std::sin(theta_degree * kPi / 180.0) * std::cbrt(4.0 / ((2.0 + c) * (1.0 - c) * (1.0 - c)));
}

// Young-Dupre: the work of adhesion W = sigma (1 + cos theta) sets the contact angle theta. On cotton (W =
// 2 sigma = 0.144 N/m, theta 0) water spreads; on a water-repellent fabric (W = 0.05 N/m, theta 108
// degrees) it beads, its cap base 1.06 R0 wide; without adhesion (theta 180) it is a ball on a point.
// Measured: water-repellent 104 degrees, contact radius 1.09 R0 (within 15 degrees and 15% of Young-Dupre's
// cap); cotton 56 degrees, 1.41 R0, wider than any cap of theta >= 90 degrees (1.26 R0): a film a few
// particles thick, thinner than which particles cannot spread, so theta 0 is out of reach; none 160
// degrees, 0.68 R0. The lowest particles sit at 0.36-0.49 mm, inside the cloth thickness (0.5 mm) where the
// elastic repulsion balances the pull.
TEST(Adhesion, DropletSpreadsOnCottonAndBeadsOnAWaterRepellentPlate) {
  const Resting cotton = rest(2.0 * kSigma);
  const Resting repellent = rest(0.05);
  const Resting none = rest(0.0);
  for (const auto& [name, r] :
       {std::pair{"cotton (0.144 N/m)", cotton}, std::pair{"water-repellent (0.05 N/m)", repellent},
        std::pair{"none (0 N/m)", none}})
    std::printf(
        "[ measured ] %s: contact angle %.0f degrees, contact radius %.2f mm (%.2f R0, R0 %.2f mm), %.0f%% "
        "of the water within 1.5 spacings of the plate, lowest particle %.2f mm over it\n",
        name, r.contact_angle, 1e3 * r.contact_radius, r.contact_radius / r.volume_radius,
        1e3 * r.volume_radius, 100.0 * r.touching, 1e3 * r.lowest);
  EXPECT_LT(cotton.contact_angle, 90.0);
  EXPECT_GT(cotton.contact_radius, cap_base_radius(90.0) * cotton.volume_radius);
  EXPECT_NEAR(repellent.contact_angle, young_dupre_angle(0.05), 15.0);
  EXPECT_NEAR(repellent.contact_radius, cap_base_radius(young_dupre_angle(0.05)) * repellent.volume_radius,
              0.15 * cap_base_radius(young_dupre_angle(0.05)) * repellent.volume_radius);
  EXPECT_GT(none.contact_angle, repellent.contact_angle);
  EXPECT_GT(repellent.contact_radius, none.contact_radius);
  EXPECT_GT(cotton.touching, repellent.touching);
  EXPECT_GT(repellent.touching, none.touching);
  // Held up by the plate: the pull presses the water into the thickness (0.5 mm) only as far as the elastic
  // repulsion (eq. 3-4) lets it, never through its inner half (with adhesion after repulsion, cotton's
  // lowest particles sat at 0.00 mm, on the face).
  for (const Resting& r : {cotton, repellent, none})
    EXPECT_GE(r.lowest, 0.5 * 0.5 * kSpacing);
}

}  // namespace
}  // namespace drench
