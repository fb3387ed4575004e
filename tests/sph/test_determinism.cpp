// Two runs with the same thread count give bit-identical states (per-particle sums in neighbor-list order,
// reductions in index order).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <thread>

#include <drench/common/parallel.hpp>

#include "physics_helpers.hpp"

namespace drench {
namespace {

ParticleSet run_dam_break(int threads, int steps, const std::string& solver = "pcisph") {
  const int saved = thread_count();
  set_thread_count(threads);
  Simulation sim(testing::demo_scene("dam_break.json",
                                     {"fluid.particle_spacing=0.1", "fluid.pressure_solver=" + solver}));
  for (int s = 0; s < steps; ++s)
    sim.step();
  set_thread_count(saved);
  return sim.particles();
}

bool bitwise_equal(const ParticleSet& a, const ParticleSet& b) {
  if (a.size() != b.size() || a.ids != b.ids) return false;
  const std::size_t bytes = a.size() * sizeof(Vec3);
  return std::memcmp(a.positions.data(), b.positions.data(), bytes) == 0 &&
         std::memcmp(a.velocities.data(), b.velocities.data(), bytes) == 0 &&
         std::memcmp(a.pressures.data(), b.pressures.data(), a.size() * sizeof(Scalar)) == 0;
}

TEST(Determinism, TwoRunsWithTheSameThreadCountAreBitIdentical) {
  const int threads = std::max(2, static_cast<int>(std::thread::hardware_concurrency()));
  EXPECT_TRUE(bitwise_equal(run_dam_break(threads, 60), run_dam_break(threads, 60)));
}

TEST(Determinism, OneAndTwoThreadsGiveBitIdenticalStates) {
  EXPECT_TRUE(bitwise_equal(run_dam_break(1, 60), run_dam_break(2, 60)));
}

TEST(Determinism, DfsphGivesBitIdenticalStatesOnOneAndTwoThreads) {
  EXPECT_TRUE(bitwise_equal(run_dam_break(1, 60, "dfsph"), run_dam_break(2, 60, "dfsph")));
}

TEST(Determinism, PbfGivesBitIdenticalStatesOnRepeatedRunsAndOneAndTwoThreads) {
  const ParticleSet two = run_dam_break(2, 60, "pbf");
  EXPECT_TRUE(bitwise_equal(two, run_dam_break(2, 60, "pbf")));
  EXPECT_TRUE(bitwise_equal(run_dam_break(1, 60, "pbf"), two));
}

}  // namespace
}  // namespace drench
