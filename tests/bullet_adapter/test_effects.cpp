// Effects that cost nothing when off (issue 28), proved by counters, not timings: an effect the scene does
// not list is never built and never runs; the coupling costs one box test while no particle is within reach
// of the cloth, and until then the fluid is bit for bit that of a scene without the coupling; the settings of
// effects that are off change no frame.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_runner.hpp>
#include <drench/scene/simulation.hpp>
#include "../temp_dir.hpp"

namespace drench {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

/// Runs `scene` to its end as `drench run` does, into a fresh folder.
RunResult run(const SceneConfig& scene, const fs::path& dir) {
  Simulation simulation(scene, bullet::cloth_engine_factory());
  RunOptions options;
  options.out_dir = dir.string();
  options.progress = false;
  return run_scene(simulation, options);
}

/// Every frame file of a run (name -> bytes).
std::map<std::string, std::string> frames(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir / "frames")) {
    std::ifstream in(entry.path(), std::ios::binary);
    files[entry.path().filename().string()] = {std::istreambuf_iterator<char>(in),
                                               std::istreambuf_iterator<char>()};
  }
  return files;
}

/// The names of the files that differ between two runs' frames, or are in one only; empty when all agree.
std::string differing(const std::map<std::string, std::string>& a,
                      const std::map<std::string, std::string>& b) {
  std::string names;
  for (const auto& [name, bytes] : a) {
    const auto it = b.find(name);
    if (it == b.end() || it->second != bytes) names += name + " ";
  }
  for (const auto& [name, bytes] : b) {
    if (!a.count(name)) names += name + " ";
  }
  return names;
}

/// A jet of up to 300 particles from 3 cm above a 0.2 m cloth of 11 x 11 nodes pinned at its corners, 40
/// steps of 1 ms with a frame every 10 ms: the water reaches the cloth within 15 steps. Every known effect is
/// listed, friction with a coefficient of 0.3.
SceneConfig small_jet() {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0, 0.03, 0);
  jet.nozzle.radius = 0.01;
  jet.nozzle.speed = 2.0;
  jet.nozzle.max_particles = 300;
  c.emitters.push_back(jet);
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.2;
  cloth.nodes_x = cloth.nodes_z = 11;
  c.cloth = cloth;
  c.coupling.friction_coefficient = 0.3;
  c.time.dt = 0.001;
  c.time.duration = 0.04;
  c.time.frame_rate = 100;
  c.effects = known_effects();
  return c;
}

/// `scene` without `name`, and without the effects that need it, as the loader would insist.
SceneConfig without(SceneConfig scene, const std::string& name) {
  auto drop = [&](const std::string& effect) {
    scene.effects.erase(std::remove(scene.effects.begin(), scene.effects.end(), effect), scene.effects.end());
  };
  drop(name);
  if (name == "coupling") {
    drop("friction");
    drop("adhesion");
    drop("wetting");
  }
  if (!scene.has_effect("friction")) scene.coupling.friction_coefficient = 0.0;
  return scene;
}

class EffectOnOff : public testing::TestWithParam<std::string> {};

// With every effect on each one is built and runs; with one off, that one's constructor and passes ran zero
// times (and it skipped nothing), while the effects still listed ran.
TEST_P(EffectOnOff, IsNeverBuiltNorRunWhenOffAndRunsWhenOn) {
  const std::string& name = GetParam();
  static const EffectCounters all = [] {
    const TempDir all_dir("all");
    return run(small_jet(), all_dir.path()).effects;
  }();
  const TempDir off_dir("off");
  const SceneConfig off_scene = without(small_jet(), name);
  const RunResult off_run = run(off_scene, off_dir.path());
  const EffectCounters& off = off_run.effects;

  const EffectCounter& on = *all.find(name);
  EXPECT_EQ(on.constructed, 1u) << name;
  EXPECT_GT(on.passes, 0u) << name;

  const EffectCounter& c = *off.find(name);
  EXPECT_EQ(c.constructed, 0u) << name;
  EXPECT_EQ(c.passes, 0u) << name;
  EXPECT_EQ(c.skipped, 0u) << name;
  if (name == "coupling") {
    EXPECT_EQ(off.substep_obstacle.constructed, 0u);
    EXPECT_EQ(off.substep_obstacle.passes + off.substep_obstacle.skipped, 0u);
  }
  for (const std::string& other : off_scene.effects)
    EXPECT_GT(off.find(other)->passes, 0u) << other << " still listed without " << name;
  // summary.json lists what ran, and nothing of the effect that is off.
  const nlohmann::json& summary = off_run.summary;
  EXPECT_FALSE(summary["effect_passes"].contains(name));
  const nlohmann::json& ran = summary["effects_ran"];
  EXPECT_EQ(std::find(ran.begin(), ran.end(), name), ran.end());
  EXPECT_EQ(ran.size(), off_scene.effects.size());
  for (const std::string& other : off_scene.effects)
    EXPECT_EQ(summary["effect_passes"][other].get<std::uint64_t>(), off.find(other)->passes) << other;
}

INSTANTIATE_TEST_SUITE_P(Effects, EffectOnOff, testing::ValuesIn(known_effects()),
                         [](const testing::TestParamInfo<std::string>& param) { return param.param; });

// A jet released 20 cm above the cloth falls for about 80 steps before it is within reach. Until then every
// coupler step, fluid sub-step obstacle and leak audit is skipped after one box test, the wetting takes
// nothing, and the particles are bit for bit those of the same scene without "coupling", "leak_audit" and
// "wetting" (standing in for a build where the coupling does not exist). Once the water arrives the coupler
// runs on every step and finds contacts. Both coupling schemes.
TEST(Effects, CouplingIsSkippedUntilTheJetIsWithinReachAndChangesNothingBefore) {
  for (const CouplingScheme scheme : {CouplingScheme::CARRIED_WATER, CouplingScheme::IMPULSES}) {
    SCOPED_TRACE(scheme == CouplingScheme::CARRIED_WATER ? "carried_water" : "impulses");
    SceneConfig coupled = small_jet();
    coupled.emitters[0].nozzle.center.y() = 0.2;
    coupled.coupling.scheme = scheme;
    coupled.coupling.friction_coefficient = 0.0;
    coupled.time.duration = 0.2;
    coupled.effects = {"viscosity", "coupling", "leak_audit", "wetting"};
    SceneConfig alone = coupled;
    alone.effects = {"viscosity"};
    Simulation a(coupled, bullet::cloth_engine_factory());
    Simulation b(alone, bullet::cloth_engine_factory());

    std::int64_t arrival = 0;  // the first step whose coupler ran
    while (!a.finished()) {
      ASSERT_TRUE(a.step().ok());
      ASSERT_TRUE(b.step().ok());
      const EffectCounters counts = a.effect_counters();
      if (counts.coupling.passes > 0) {
        arrival = a.steps_done();
        break;
      }
      const auto steps = static_cast<std::uint64_t>(a.steps_done());
      ASSERT_EQ(counts.coupling.skipped, steps);
      ASSERT_EQ(counts.leak_audit.skipped, steps);
      ASSERT_EQ(counts.leak_audit.passes, 0u);
      ASSERT_EQ(counts.substep_obstacle.passes, 0u);
      ASSERT_EQ(counts.substep_obstacle.skipped, static_cast<std::uint64_t>(a.fluid().statistics().substeps));
      ASSERT_EQ(counts.wetting.passes, steps) << "the wetting runs on (on a dry cloth)";
      ASSERT_EQ(a.wetting_stats().particles_absorbed, 0u);
      ASSERT_EQ(a.particles().ids, b.particles().ids) << "step " << steps;
      ASSERT_EQ(a.particles().positions, b.particles().positions) << "step " << steps;
      ASSERT_EQ(a.particles().velocities, b.particles().velocities) << "step " << steps;
    }
    ASSERT_GT(arrival, 60) << "the jet needs about 80 steps to fall 20 cm";
    // It ended for a reason: the lowest particle is within two spacings of the cloth's highest node.
    double lowest = 1.0, highest_node = -1.0;
    for (const Vec3& x : a.particles().positions)
      lowest = std::min(lowest, x.y());
    for (const Vec3& x : a.cloth()->mesh().positions_t1)
      highest_node = std::max(highest_node, x.y());
    EXPECT_LT(lowest, highest_node + 2.0 * coupled.fluid.particle_spacing);

    for (int k = 0; k < 40 && !a.finished(); ++k)
      ASSERT_TRUE(a.step().ok());
    const EffectCounters counts = a.effect_counters();
    EXPECT_EQ(counts.coupling.skipped, static_cast<std::uint64_t>(arrival - 1))
        << "no particle within reach skipped once the water is on the cloth";
    EXPECT_EQ(counts.coupling.passes, static_cast<std::uint64_t>(a.steps_done() - arrival + 1));
    EXPECT_GT(counts.leak_audit.passes, 0u);
    EXPECT_GT(counts.substep_obstacle.passes, 0u);
    EXPECT_GT(a.coupling_stats().contacts, 0u);
    EXPECT_EQ(a.leak_stats().leaks, 0u);
  }
}

/// The default jet-on-cloth scene, its nozzle lowered to 5 cm so that the water lands within the run's 40
/// steps, a frame every 4 ms.
SceneConfig default_scene() {
  return load_scene_file(std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/jet_on_cloth.json",
                         {"emitters[0].center=[0,0.05,0]", "emitters[0].max_particles=1500",
                          "time.duration=0.04", "time.frame_rate=250"});
}

// The wetting and surface settings are read only by their effects: the default scene with them set and the
// effects off writes the same frames, byte for byte, as without them. With "surface" on the fluid and cloth
// frames stay the same (it only reads them); with "wetting" on the fluid frames change (it takes water), so
// the comparison sees a difference where there is one.
TEST(Effects, SettingsOfEffectsThatAreOffChangeNoFrame) {
  const SceneConfig absent = default_scene();
  ASSERT_FALSE(absent.has_effect("wetting"));
  ASSERT_FALSE(absent.has_effect("surface"));
  SceneConfig present = absent;
  present.wetting.absorption_rate = 1000.0;
  present.wetting.max_saturation = 20.0;
  present.wetting.diffusion = 0.01;
  present.surface.cell_size = 0.003;
  present.surface.contact_aware = false;

  const TempDir absent_dir("absent"), present_dir("present"), surface_dir("surface"), wet_dir("wet");
  const RunResult reference = run(absent, absent_dir.path());
  ASSERT_TRUE(reference.status.ok());
  ASSERT_GT(reference.summary["contacts"].get<std::uint64_t>(), 0u) << "the water reached the cloth";
  const auto expected = frames(absent_dir.path());
  ASSERT_EQ(expected.size(), 2u * 11u);  // fluid and cloth, frames 0 to 10
  run(present, present_dir.path());
  EXPECT_EQ(differing(frames(present_dir.path()), expected), "");

  SceneConfig surface = present;
  surface.effects.push_back("surface");
  run(surface, surface_dir.path());
  auto with_surface = frames(surface_dir.path());
  std::size_t surfaces = 0;
  for (auto it = with_surface.begin(); it != with_surface.end();) {
    const bool is_surface = it->first.rfind("surface_", 0) == 0;
    surfaces += is_surface;
    it = is_surface ? with_surface.erase(it) : std::next(it);
  }
  EXPECT_EQ(surfaces, 11u);
  EXPECT_EQ(differing(with_surface, expected), "");

  SceneConfig wet = present;
  wet.effects.push_back("wetting");
  run(wet, wet_dir.path());
  const auto wet_frames = frames(wet_dir.path());
  bool fluid_differs = false;
  for (const auto& [name, bytes] : wet_frames) {
    if (name.rfind("fluid_", 0) == 0 && expected.count(name) && expected.at(name) != bytes)
      fluid_differs = true;
  }
  EXPECT_TRUE(fluid_differs) << "the wetting took no water: the comparison above proves nothing";
}

}  // namespace
}  // namespace drench
