// PCISPH's max_relief_per_substep (a drench addition to Solenthaler & Pajarola 2009): a particle that enters
// a sub-step compressed far beyond what the fluid's own motion makes is relieved by at most that much of its
// compression in the sub-step; without the limit PCISPH undoes it all at once.

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>

#include <drench/scene/scene_config.hpp>
#include <drench/sph/fluid_solver.hpp>

#include "stacked_block.hpp"

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // m

struct Relief {
  double before = 0.0;   // fraction of rest density above rest, at the start of the sub-step
  double after = 0.0;    // the same after it
  double fastest = 0.0;  // the fastest particle after it (unit: m/s)
};

/// A resting 8 x 8 x 8 block without gravity, one more particle 0.1 spacing from an interior one
/// (as the coupling stacks them); one sub-step of 0.1 ms. Returns that particle's compression before and
/// after.
Relief relieve(std::optional<double> max_relief) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pcisph.max_relief_per_substep = max_relief;
  FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0);
  const std::uint32_t id = testing::stack_in_block(fluid, kSpacing);
  const auto compression = [&] { return testing::compression_of(fluid, id); };
  const ParticleSet& p = fluid.particles();
  Relief r;
  EXPECT_TRUE(fluid.step(1e-4).ok());  // one sub-step: nothing moves before it, so no CFL limit
  r.before = compression();
  for (const Vec3& v : p.velocities)
    r.fastest = std::max(r.fastest, v.norm());
  EXPECT_TRUE(fluid.step(1e-12).ok());  // densities at the start of this sub-step: after the first
  r.after = compression();
  return r;
}

TEST(Pcisph, ReliefPerSubstepIsLimited) {
  const Relief limited = relieve(0.05);
  const Relief published = relieve(std::nullopt);
  ASSERT_GT(limited.before, 0.2) << "the test needs a particle far beyond any sub-step's own compression";
  ASSERT_EQ(limited.before, published.before);
  // As published, PCISPH undoes nearly all of it in one sub-step (recorded as after_published).
  EXPECT_LT(published.after, 0.25 * published.before);
  // With the limit the particle is driven to 0.05 below its density; its neighbours, compressed by
  // it, relieve their own share and push it further (recorded as after_limited). It still relieves, by less
  // than half of what published PCISPH does, and the pressure throws nothing as fast.
  const double relief_limited = limited.before - limited.after;
  const double relief_published = published.before - published.after;
  EXPECT_GT(relief_limited, 0.05 - 0.01);
  EXPECT_LT(relief_limited, 0.5 * relief_published);
  EXPECT_LT(limited.fastest, 0.5 * published.fastest);
  ::testing::Test::RecordProperty("compression_before", std::to_string(limited.before));
  ::testing::Test::RecordProperty("after_limited", std::to_string(limited.after));
  ::testing::Test::RecordProperty("after_published", std::to_string(published.after));
  ::testing::Test::RecordProperty("fastest_limited_mps", std::to_string(limited.fastest));
  ::testing::Test::RecordProperty("fastest_published_mps", std::to_string(published.fastest));
}

}  // namespace
}  // namespace drench
