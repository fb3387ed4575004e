// The viewer's simulation side (render/live_simulation.hpp), without a window: paused it steps only when
// asked, once per request; running it stops at the scene's duration; a restart starts a new generation
// from step 0; the stepping thread uses drench's thread count; the surface worker refuses a
// second request while one is under way and hands back a mesh.

#include <drench/render/live_simulation.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/common/parallel.hpp>
#include <drench/scene/scene_loader.hpp>

namespace drench::render {
namespace {

using namespace std::chrono_literals;

/// The default demo, `duration` long (unit: s).
LiveSimulation::Factory jet_on_cloth(double duration) {
  const SceneConfig config = load_scene_file(DRENCH_SOURCE_DIR "/demos/scenes/jet_on_cloth.json",
                                             {"time.duration=" + std::to_string(duration)});
  return [config] { return std::make_unique<Simulation>(config, bullet::cloth_engine_factory()); };
}

/// Takes snapshots until `done` holds for one (true) or 60 s pass (false); `snapshot` is the last taken.
bool wait_for(LiveSimulation& live, Snapshot& snapshot, const std::function<bool(const Snapshot&)>& done) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (live.take_latest(snapshot) && done(snapshot)) return true;
    std::this_thread::sleep_for(1ms);
  }
  return false;
}

TEST(LiveSimulation, PausedStepsOnlyWhenAskedOncePerRequest) {
  LiveSimulation live(jet_on_cloth(0.05), true);
  Snapshot snapshot;
  ASSERT_TRUE(live.take_latest(snapshot));  // the initial state, published before the thread starts
  EXPECT_EQ(snapshot.steps, 0);
  EXPECT_EQ(snapshot.serial, 1u);
  EXPECT_FALSE(snapshot.cloth.triangles.empty());
  EXPECT_FALSE(live.take_latest(snapshot));  // nothing new while paused

  live.step_once();
  live.step_once();
  ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.steps == 2; }));
  std::this_thread::sleep_for(100ms);  // time for steps that should not come
  EXPECT_FALSE(live.take_latest(snapshot));
  EXPECT_EQ(live.total_steps(), 2);
  EXPECT_NEAR(snapshot.time, 0.002, 1e-12);
  EXPECT_EQ(snapshot.positions.size(), snapshot.velocities.size());
}

TEST(LiveSimulation, RunsToTheScenesDurationThenRestartsFromStepZero) {
  LiveSimulation live(jet_on_cloth(0.01), false);
  Snapshot snapshot;
  ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.finished; }));
  EXPECT_EQ(snapshot.steps, 10);
  EXPECT_GT(snapshot.positions.size(), 0u);  // the nozzle has emitted
  EXPECT_TRUE(snapshot.stopped.empty());
  live.step_once();  // ignored: running, and finished besides
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(live.total_steps(), 10);

  live.set_paused(true);
  live.restart();
  ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.generation == 1; }));
  EXPECT_EQ(snapshot.steps, 0);  // paused is kept: the new scene waits at its start
  EXPECT_EQ(snapshot.positions.size(), 0u);
  EXPECT_FALSE(snapshot.finished);
  live.set_paused(false);
  ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.finished; }));
  EXPECT_EQ(snapshot.generation, 1u);
  EXPECT_EQ(live.total_steps(), 20);
  EXPECT_GT(live.stepping_seconds(), 0.0);
  EXPECT_TRUE(live.error().empty());
}

TEST(LiveSimulation, StepsWithDrenchsThreadCount) {
  // `--threads 1` on a machine of more cores: the stepping thread must see 1, not the default.
  const int before = thread_count();
  set_thread_count(1);
  std::atomic<int> seen{0};
  const LiveSimulation::Factory jet = jet_on_cloth(0.01);
  {
    LiveSimulation live(
        [&] {
          seen = thread_count();
          return jet();
        },
        true);
    seen = 0;
    live.restart();  // the factory now runs on the stepping thread
    Snapshot snapshot;
    ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.generation == 1; }));
  }
  set_thread_count(before);
  EXPECT_EQ(seen, 1);
}

TEST(LiveSimulation, DestroyingItWhileRunningJoinsTheThread) {
  Snapshot snapshot;
  {
    LiveSimulation live(jet_on_cloth(10.0), false);
    ASSERT_TRUE(wait_for(live, snapshot, [](const Snapshot& s) { return s.steps >= 3; }));
  }  // would hang or crash here if the thread were left running
  EXPECT_GE(snapshot.steps, 3);
}

TEST(LiveSurface, RefusesASecondRequestWhileBusyAndHandsBackTheSurface) {
  Snapshot snapshot;
  snapshot.serial = 7;
  snapshot.generation = 2;
  for (int i = -4; i <= 4; ++i) {
    for (int j = -4; j <= 4; ++j) {
      for (int k = -4; k <= 4; ++k)
        snapshot.positions.push_back(0.005 * Vec3(i, j, k));
    }
  }
  SurfaceSettings settings;
  settings.cell_size = 0.004;
  LiveSurface surface(0.005, settings, TriangleMesh{});
  ASSERT_TRUE(surface.request(snapshot));
  EXPECT_FALSE(surface.request(snapshot));  // under way, or done and not yet taken

  TriangleMesh mesh;
  std::uint64_t serial = 0, generation = 0;
  std::string error;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!surface.take(mesh, serial, generation, error) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(1ms);
  EXPECT_TRUE(error.empty()) << error;
  EXPECT_EQ(serial, 7u);
  EXPECT_EQ(generation, 2u);
  ASSERT_FALSE(mesh.triangles.empty());
  // A closed surface around the 4 cm cube of particles: every vertex within a few cells of it.
  for (const Vec3& v : mesh.positions)
    EXPECT_LT(v.cwiseAbs().maxCoeff(), 0.02 + 3 * 0.004) << v.transpose();
  EXPECT_TRUE(surface.request(snapshot));  // free again once taken
}

}  // namespace
}  // namespace drench::render
