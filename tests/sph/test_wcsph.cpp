// WCSPH's max_compression (a drench addition to Becker & Teschner 2007): a particle compressed beyond the
// limit pushes as one compressed that much, so a particle stacked onto another (as the cloth coupling stacks
// them) is pushed off at a speed of the flow's order rather than the sound's; below it the Tait equation is
// untouched.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <drench/sph/fluid_solver.hpp>

#include "stacked_block.hpp"

namespace drench {
namespace {

constexpr double kSpacing = 0.01;       // m
constexpr double kSpeedOfSound = 10.0;  // m/s
constexpr double kLimit = 0.05;         // max_compression (fraction of rest density)

struct Stacked {
  double compression_start = 0.0;  // the stacked particle's density above rest (fraction), before any motion
  double compression_end = 0.0;    // the same at the end
  double fastest = 0.0;            // the fastest particle seen at the end of any step (unit: m/s)
  std::vector<double> densities;   // every particle's density before any motion (unit: kg/m^3)
  std::vector<double> pressures;   // and its pressure (unit: Pa)
};

/// A resting 8 x 8 x 8 block without gravity and one more particle 0.1 spacing from the one nearest its
/// centre, as the coupling stacks them; 10 ms of WCSPH in 1 ms steps (CFL sub-steps inside).
Stacked relax(std::optional<double> max_compression) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = PressureSolverKind::WCSPH;
  settings.wcsph.max_compression = max_compression;
  FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, kSpeedOfSound);
  const std::uint32_t id = testing::stack_in_block(fluid, kSpacing);
  const auto compression = [&] { return testing::compression_of(fluid, id); };
  const ParticleSet& p = fluid.particles();
  Stacked s;
  EXPECT_TRUE(fluid.step(1e-12).ok());  // densities and pressures of the initial state; nothing moves
  s.compression_start = compression();
  s.densities = p.densities;
  s.pressures = p.pressures;
  for (int step = 0; step < 10; ++step) {
    EXPECT_TRUE(fluid.step(1e-3).ok());
    for (const Vec3& v : p.velocities)
      s.fastest = std::max(s.fastest, v.norm());
  }
  EXPECT_TRUE(fluid.step(1e-12).ok());  // densities at the end
  s.compression_end = compression();
  return s;
}

TEST(Wcsph, CompressionBeyondTheLimitPushesAsTheLimit) {
  const Stacked limited = relax(kLimit);
  const Stacked published = relax(std::nullopt);
  ASSERT_GT(limited.compression_start, 0.2)
      << "the test needs a particle far beyond the flow's own compression";
  ASSERT_EQ(limited.densities, published.densities);
  const double rho0 = FluidSettings{}.rest_density;
  const double stiffness = rho0 * kSpeedOfSound * kSpeedOfSound / 7.0;  // B of the Tait equation
  const double cap = stiffness * (std::pow(1.0 + kLimit, 7.0) - 1.0);
  int capped = 0;
  for (std::size_t i = 0; i < limited.densities.size(); ++i) {
    if (limited.densities[i] <= (1.0 + kLimit) * rho0) {
      // Below the limit, the published pressure to the bit.
      ASSERT_EQ(limited.pressures[i], published.pressures[i]) << "particle " << i;
    } else {
      ++capped;
      EXPECT_NEAR(limited.pressures[i], cap, 1e-9 * cap) << "particle " << i;
      EXPECT_GT(published.pressures[i], limited.pressures[i]) << "particle " << i;
    }
  }
  EXPECT_GE(capped, 2) << "the stacked particle and the one under it";
  ::testing::Test::RecordProperty("capped_particles", capped);
}

TEST(Wcsph, AStackedParticleIsPushedOffAtTheFlowsSpeedNotTheSounds) {
  const Stacked limited = relax(kLimit);
  const Stacked published = relax(std::nullopt);
  // As published, the 20%+ compression is released at a good fraction of the speed of sound (10 m/s);
  // with the limit the push is that of a 5% compression, and the particle still gets off its neighbour.
  EXPECT_GT(published.fastest, 0.1 * kSpeedOfSound);
  EXPECT_LT(limited.fastest, 0.5 * published.fastest);
  EXPECT_LT(limited.compression_end, 0.5 * limited.compression_start);
  ::testing::Test::RecordProperty("compression_start", std::to_string(limited.compression_start));
  ::testing::Test::RecordProperty("compression_end_limited", std::to_string(limited.compression_end));
  ::testing::Test::RecordProperty("compression_end_published", std::to_string(published.compression_end));
  ::testing::Test::RecordProperty("fastest_limited_mps", std::to_string(limited.fastest));
  ::testing::Test::RecordProperty("fastest_published_mps", std::to_string(published.fastest));
}

}  // namespace
}  // namespace drench
