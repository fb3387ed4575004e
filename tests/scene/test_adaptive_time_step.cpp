// time.adaptive (issue 29): each step is the fluid's CFL step within [dt_min, dt], frames and the end land on
// steps, and the fluid then never sub-steps.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <drench/scene/scene_loader.hpp>
#include <drench/scene/simulation.hpp>

namespace drench {
namespace {

SceneConfig adaptive_dam_break(const std::string& solver) {
  return load_scene_file(std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/dam_break.json",
                         {"fluid.particle_spacing=0.1", "fluid.pressure_solver=" + solver, "time.dt=0.02",
                          "time.duration=0.5", "time.adaptive=true", "time.dt_min=1e-4"});
}

TEST(AdaptiveTimeStep, StepsFollowTheCflLimitAndLandOnEveryFrame) {
  for (const std::string solver : {"wcsph", "pcisph", "dfsph"}) {
    SCOPED_TRACE(solver);
    const SceneConfig config = adaptive_dam_break(solver);
    Simulation sim(config);
    const Scalar frame = 1.0 / config.time.frame_rate;
    int frames_hit = 0;
    while (!sim.finished()) {
      const Scalar dt = sim.next_dt();
      const Scalar cfl = sim.fluid().cfl_step();
      // Never above the CFL step (or dt), never below dt_min unless cut to land on a frame or the end.
      ASSERT_LE(dt, std::min(cfl, config.time.dt) * (1 + 1e-12));
      ASSERT_TRUE(sim.step().ok());
      const Scalar k = std::round(sim.time() / frame);
      if (std::abs(sim.time() - k * frame) <= 1e-12) ++frames_hit;
    }
    const FluidStatistics& f = sim.fluid().statistics();
    std::printf("[ measured ] %s: %lld steps of %.3g to %.3g s, %d frames hit\n", solver.c_str(),
                static_cast<long long>(sim.steps_done()), sim.min_dt(), sim.max_dt(), frames_hit);
    EXPECT_EQ(f.max_substeps_per_step, 1) << "a step within the CFL limit needs no fluid sub-step";
    EXPECT_NEAR(sim.time(), config.time.duration, 1e-12);
    EXPECT_EQ(frames_hit, std::lround(config.time.duration * config.time.frame_rate));
    EXPECT_LT(sim.min_dt(), sim.max_dt()) << "the steps adapt";
    EXPECT_GE(sim.min_dt(), config.time.dt_min);
  }
}

}  // namespace
}  // namespace drench
