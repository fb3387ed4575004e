#include <drench/scene/scene_loader.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/scene/effect_registry.hpp>
#include <drench/scene/simulation.hpp>
#include "../assertions.hpp"
#include "../temp_dir.hpp"

namespace drench {
namespace {

using drench::test::throws_containing;

using nlohmann::json;

SceneConfig parse(const std::string& text) {
  return parse_scene(json::parse(text), "x.json");
}

testing::AssertionResult scene_error(const std::string& text, const std::string& expected) {
  return throws_containing<SceneError>([&] { parse(text); }, expected);
}

testing::AssertionResult override_error(const std::string& text, const std::string& assignment,
                                        const std::string& expected) {
  json document = json::parse(text);
  return throws_containing<SceneError>([&] { apply_override(document, assignment); }, expected);
}

constexpr const char* kFullScene = R"({
  "gravity": [0, -9.8, 0.5],
  "fluid": {
    "rest_density": 998.2,
    "particle_spacing": 0.02,
    "pressure_solver": "wcsph",
    "wcsph": {"speed_of_sound": 30, "exponent": 7},
    "pcisph": {"eta": 0.01, "min_iterations": 2, "max_iterations": 50, "max_compression_per_iteration": 0.1,
               "max_relief_per_substep": 0.2, "precision": "double"},
    "viscosity": {"method": "artificial", "coefficient": 0.05},
    "cfl": 0.25,
    "sort_interval": 20,
    "substep_halvings": 6
  },
  "emitters": [
    {"type": "nozzle", "center": [0, 1, 0], "direction": [0, 0, -2], "radius": 0.03, "speed": 2.5,
     "start_time": 0.1, "max_particles": 5000},
    {"type": "box", "min": [0, 0, 0], "max": [0.5, 1, 0.5], "velocity": [1, 0, 0]}
  ],
  "boundaries": [
    {"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "open_top": true, "layers": 3},
    {"type": "plane", "point": [0, 0, 0], "normal": [0, 3, 0], "size": [2, 4], "layers": 1}
  ],
  "kill_regions": [
    {"type": "plane", "point": [0, -1, 0], "normal": [0, 0, 5]},
    {"type": "box", "min": [-5, -5, -5], "max": [5, 5, 5]}
  ],
  "time": {"dt": 0.002, "duration": 3, "frame_rate": 60},
  "effects": ["viscosity"]
})";

// ---------------------------------------------------------------------------------------------------------
// Valid scenes

TEST(SceneLoader, ParsesFullSceneIntoEveryMember) {
  const SceneConfig c = parse(kFullScene);
  EXPECT_EQ(c.source, "x.json");
  EXPECT_EQ(c.gravity, Vec3(0, -9.8, 0.5));
  EXPECT_DOUBLE_EQ(c.fluid.rest_density, 998.2);
  EXPECT_DOUBLE_EQ(c.fluid.particle_spacing, 0.02);
  EXPECT_EQ(c.fluid.pressure_solver, PressureSolverKind::WCSPH);
  ASSERT_TRUE(c.fluid.wcsph.speed_of_sound.has_value());
  EXPECT_DOUBLE_EQ(*c.fluid.wcsph.speed_of_sound, 30.0);
  EXPECT_DOUBLE_EQ(c.fluid.wcsph.exponent, 7.0);
  EXPECT_DOUBLE_EQ(c.fluid.pcisph.eta, 0.01);
  EXPECT_EQ(c.fluid.pcisph.min_iterations, 2);
  ASSERT_TRUE(c.fluid.pcisph.max_compression_per_iteration.has_value());
  EXPECT_DOUBLE_EQ(*c.fluid.pcisph.max_compression_per_iteration, 0.1);
  ASSERT_TRUE(c.fluid.pcisph.max_relief_per_substep.has_value());
  EXPECT_DOUBLE_EQ(*c.fluid.pcisph.max_relief_per_substep, 0.2);
  EXPECT_EQ(c.fluid.pcisph.max_iterations, 50);
  EXPECT_EQ(c.fluid.pcisph.precision, IterationPrecision::DOUBLE);
  EXPECT_EQ(c.fluid.viscosity.method, ViscosityKind::ARTIFICIAL);
  EXPECT_DOUBLE_EQ(c.fluid.viscosity.coefficient, 0.05);
  EXPECT_DOUBLE_EQ(c.fluid.cfl, 0.25);
  EXPECT_EQ(c.fluid.sort_interval, 20);
  EXPECT_EQ(c.fluid.substep_halvings, 6);

  ASSERT_EQ(c.emitters.size(), 2u);
  EXPECT_EQ(c.emitters[0].kind, EmitterSettings::Kind::NOZZLE);
  EXPECT_EQ(c.emitters[0].nozzle.center, Vec3(0, 1, 0));
  EXPECT_EQ(c.emitters[0].nozzle.direction, Vec3(0, 0, -1));
  EXPECT_DOUBLE_EQ(c.emitters[0].nozzle.radius, 0.03);
  EXPECT_DOUBLE_EQ(c.emitters[0].nozzle.speed, 2.5);
  EXPECT_DOUBLE_EQ(c.emitters[0].nozzle.start_time, 0.1);
  EXPECT_EQ(c.emitters[0].nozzle.max_particles, 5000);
  EXPECT_EQ(c.emitters[1].kind, EmitterSettings::Kind::BOX);
  EXPECT_EQ(c.emitters[1].box.min, Vec3(0, 0, 0));
  EXPECT_EQ(c.emitters[1].box.max, Vec3(0.5, 1, 0.5));
  EXPECT_EQ(c.emitters[1].box.velocity, Vec3(1, 0, 0));

  ASSERT_EQ(c.boundaries.size(), 2u);
  EXPECT_EQ(c.boundaries[0].kind, BoundarySettings::Kind::BOX);
  EXPECT_EQ(c.boundaries[0].min, Vec3(-1, 0, -1));
  EXPECT_EQ(c.boundaries[0].max, Vec3(1, 2, 1));
  EXPECT_TRUE(c.boundaries[0].open_top);
  EXPECT_EQ(c.boundaries[0].layers, 3);
  EXPECT_EQ(c.boundaries[1].kind, BoundarySettings::Kind::PLANE);
  EXPECT_EQ(c.boundaries[1].normal, Vec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(c.boundaries[1].size[0], 2.0);
  EXPECT_DOUBLE_EQ(c.boundaries[1].size[1], 4.0);
  EXPECT_EQ(c.boundaries[1].layers, 1);

  ASSERT_EQ(c.kill_regions.size(), 2u);
  EXPECT_EQ(c.kill_regions[0].kind, KillRegionSettings::Kind::PLANE);
  EXPECT_EQ(c.kill_regions[0].point, Vec3(0, -1, 0));
  EXPECT_EQ(c.kill_regions[0].normal, Vec3(0, 0, 1));
  EXPECT_EQ(c.kill_regions[1].kind, KillRegionSettings::Kind::BOX);
  EXPECT_EQ(c.kill_regions[1].min, Vec3(-5, -5, -5));
  EXPECT_EQ(c.kill_regions[1].max, Vec3(5, 5, 5));

  EXPECT_DOUBLE_EQ(c.time.dt, 0.002);
  EXPECT_DOUBLE_EQ(c.time.duration, 3.0);
  EXPECT_DOUBLE_EQ(c.time.frame_rate, 60.0);
  EXPECT_EQ(c.effects, std::vector<std::string>{"viscosity"});
  EXPECT_TRUE(c.has_effect("viscosity"));
}

TEST(SceneLoader, EmptyObjectTakesStructDefaults) {
  const SceneConfig c = parse("{}");
  const SceneConfig d;
  EXPECT_EQ(c.gravity, d.gravity);
  EXPECT_EQ(c.fluid.rest_density, d.fluid.rest_density);
  EXPECT_EQ(c.fluid.particle_spacing, d.fluid.particle_spacing);
  EXPECT_EQ(c.fluid.pressure_solver, d.fluid.pressure_solver);
  EXPECT_FALSE(c.fluid.wcsph.speed_of_sound.has_value());
  EXPECT_EQ(c.fluid.pcisph.max_iterations, d.fluid.pcisph.max_iterations);
  EXPECT_EQ(c.fluid.viscosity.method, d.fluid.viscosity.method);
  EXPECT_EQ(c.fluid.cfl, d.fluid.cfl);
  EXPECT_EQ(c.fluid.sort_interval, d.fluid.sort_interval);
  EXPECT_EQ(c.fluid.substep_halvings, d.fluid.substep_halvings);
  EXPECT_TRUE(c.emitters.empty());
  EXPECT_TRUE(c.boundaries.empty());
  EXPECT_TRUE(c.kill_regions.empty());
  EXPECT_EQ(c.time.dt, d.time.dt);
  EXPECT_EQ(c.time.duration, d.time.duration);
  EXPECT_EQ(c.time.frame_rate, d.time.frame_rate);
  EXPECT_TRUE(c.effects.empty());
  EXPECT_FALSE(c.has_effect("viscosity"));
}

TEST(SceneLoader, AbsentKeysInsideAnElementTakeDefaults) {
  const SceneConfig c = parse(R"({"emitters": [{"type": "nozzle", "speed": 3}], "fluid": {"cfl": 1}})");
  const NozzleEmitterSettings d;
  EXPECT_EQ(c.emitters[0].nozzle.direction, d.direction);
  EXPECT_EQ(c.emitters[0].nozzle.radius, d.radius);
  EXPECT_EQ(c.emitters[0].nozzle.max_particles, d.max_particles);
  EXPECT_DOUBLE_EQ(c.emitters[0].nozzle.speed, 3.0);
  EXPECT_DOUBLE_EQ(c.fluid.cfl, 1.0);
  EXPECT_EQ(c.fluid.pcisph.eta, PcisphSettings{}.eta);
  EXPECT_EQ(c.fluid.pcisph.precision, IterationPrecision::SINGLE);
}

TEST(SceneLoader, NormalisesNozzleDirection) {
  const SceneConfig c = parse(R"({"emitters": [{"type": "nozzle", "direction": [3, 4, 0]}]})");
  EXPECT_NEAR(c.emitters[0].nozzle.direction.x(), 0.6, 1e-15);
  EXPECT_NEAR(c.emitters[0].nozzle.direction.y(), 0.8, 1e-15);
  EXPECT_EQ(c.emitters[0].nozzle.direction.z(), 0.0);
}

TEST(SceneLoader, NormalisesTinyDirectionWithoutUnderflow) {
  const SceneConfig c = parse(R"({"emitters": [{"type": "nozzle", "direction": [0, 1e-200, 0]}]})");
  EXPECT_NEAR(c.emitters[0].nozzle.direction.y(), 1.0, 1e-15);
}

TEST(SceneLoader, NullSpeedOfSoundMeansAuto) {
  EXPECT_FALSE(parse(R"({"fluid": {"wcsph": {"speed_of_sound": null}}})").fluid.wcsph.speed_of_sound);
}

TEST(SceneLoader, NullMaxCompressionPerIterationMeansNoLimit) {
  EXPECT_EQ(parse("{}").fluid.pcisph.max_compression_per_iteration, 0.05);
  EXPECT_FALSE(parse(R"({"fluid": {"pcisph": {"max_compression_per_iteration": null}}})")
                   .fluid.pcisph.max_compression_per_iteration);
}

TEST(SceneLoader, RejectsZeroMaxCompressionPerIteration) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"max_compression_per_iteration": 0}}})",
                          "fluid.pcisph.max_compression_per_iteration must be > 0, got 0 (x.json)"));
}

// The scenes shipped in demos/scenes/ obey the loader's rules (README and docs/scenes.md point users at
// them).
TEST(SceneLoader, EveryDemoSceneLoads) {
  const std::filesystem::path dir = std::filesystem::path(DRENCH_SOURCE_DIR) / "demos" / "scenes";
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    EXPECT_NO_THROW(load_scene_file(entry.path().string(), {})) << entry.path();
  }
  EXPECT_GE(scenes, 6) << "dam_break, hydrostatic_tank, jet_on_cloth, no_slip, free_slip, leak_comparison";
}

TEST(SceneLoader, NullMaxReliefPerSubstepMeansNoLimit) {
  EXPECT_EQ(parse("{}").fluid.pcisph.max_relief_per_substep, 0.05);
  EXPECT_FALSE(parse(R"({"fluid": {"pcisph": {"max_relief_per_substep": null}}})")
                   .fluid.pcisph.max_relief_per_substep);
}

TEST(SceneLoader, RejectsNegativeMaxReliefPerSubstep) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"max_relief_per_substep": -0.1}}})",
                          "fluid.pcisph.max_relief_per_substep must be > 0, got -0.1 (x.json)"));
}

TEST(SceneLoader, ReadsWcsphMaxCompressionNullMeaningNoLimit) {
  EXPECT_EQ(parse("{}").fluid.wcsph.max_compression, 0.05);
  EXPECT_EQ(parse(R"({"fluid": {"wcsph": {"max_compression": 0.1}}})").fluid.wcsph.max_compression, 0.1);
  EXPECT_FALSE(parse(R"({"fluid": {"wcsph": {"max_compression": null}}})").fluid.wcsph.max_compression);
  EXPECT_TRUE(scene_error(R"({"fluid": {"wcsph": {"max_compression": 0}}})",
                          "fluid.wcsph.max_compression must be > 0, got 0 (x.json)"));
}

TEST(SceneLoader, AcceptsZeroMaxParticlesAndZeroFrameRate) {
  const SceneConfig c =
      parse(R"({"emitters": [{"type": "nozzle", "max_particles": 0}], "time": {"frame_rate": 0}})");
  EXPECT_EQ(c.emitters[0].nozzle.max_particles, 0);
  EXPECT_EQ(c.time.frame_rate, 0.0);
}

TEST(SceneLoader, AcceptsDtEqualToDuration) {
  EXPECT_EQ(parse(R"({"time": {"dt": 0.5, "duration": 0.5}})").time.dt, 0.5);
}

TEST(SceneLoader, AcceptsMaxParticlesBeyond32Bits) {
  EXPECT_EQ(parse(R"({"emitters": [{"type": "nozzle", "max_particles": 5000000000}]})")
                .emitters[0]
                .nozzle.max_particles,
            5000000000);
}

// ---------------------------------------------------------------------------------------------------------
// Document-level errors

TEST(SceneLoader, RejectsNonObjectTopLevel) {
  EXPECT_TRUE(scene_error("[1, 2]", "the scene must be an object, got [1,2] (x.json)"));
}

TEST(SceneLoader, RejectsUnknownTopLevelKeyListingKnownKeys) {
  EXPECT_TRUE(scene_error(R"({"gravty": [0, 0, 0]})",
                          "gravty is not a known key (x.json); known: gravity, fluid, emitters, boundaries, "
                          "kill_regions, time, cloth, obstacles, coupling, surface, wetting, effects"));
}

TEST(SceneLoader, RejectsMisspeltFluidKeyListingKnownKeys) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"visocsity": {}}})",
                  "fluid.visocsity is not a known key (x.json); known: rest_density, particle_spacing, "
                  "pressure_solver, wcsph, pcisph, dfsph, pbf, viscosity, cfl, max_speed, sort_interval, "
                  "substep_halvings"));
}

TEST(SceneLoader, RejectsNonFiniteNumberInDocumentBuiltInCode) {
  json document = {{"time", {{"dt", std::numeric_limits<double>::infinity()}}}};
  EXPECT_TRUE(throws_containing<SceneError>([&] { parse_scene(document, "code"); },
                                            "time.dt must be finite, got inf (code)"));
}

TEST(SceneLoader, RejectsNanInDocumentBuiltInCode) {
  json document = {{"fluid", {{"cfl", std::nan("")}}}};
  EXPECT_TRUE(throws_containing<SceneError>([&] { parse_scene(document, "code"); },
                                            "fluid.cfl must be finite, got nan"));
}

// ---------------------------------------------------------------------------------------------------------
// gravity

TEST(SceneLoader, RejectsGravityWithTwoComponents) {
  EXPECT_TRUE(scene_error(R"({"gravity": [0, -9.81]})",
                          "gravity must be an array of 3 numbers, got [0,-9.81] (x.json)"));
}

TEST(SceneLoader, RejectsGravityComponentThatIsNotANumberNamingIndex) {
  EXPECT_TRUE(
      scene_error(R"({"gravity": [0, "down", 0]})", "gravity[1] must be a number, got \"down\" (x.json)"));
}

// ---------------------------------------------------------------------------------------------------------
// fluid

TEST(SceneLoader, RejectsFluidThatIsNotAnObject) {
  EXPECT_TRUE(scene_error(R"({"fluid": 3})", "fluid must be an object, got 3 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeParticleSpacingNamingPathAndValue) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"particle_spacing": -0.01}})",
                          "fluid.particle_spacing must be > 0, got -0.01 (x.json)"));
}

TEST(SceneLoader, RejectsZeroRestDensity) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"rest_density": 0}})", "fluid.rest_density must be > 0, got 0 (x.json)"));
}

TEST(SceneLoader, RejectsUnknownPressureSolverListingChoices) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pressure_solver": "iisph"}})",
                          "fluid.pressure_solver must be one of \"pcisph\", \"wcsph\", \"dfsph\", \"pbf\", "
                          "got \"iisph\" (x.json)"));
}

TEST(SceneLoader, RejectsUnknownPcisphPrecisionListingChoices) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"pcisph": {"precision": "half"}}})",
                  "fluid.pcisph.precision must be one of \"single\", \"double\", got \"half\" (x.json)"));
}

TEST(SceneLoader, RejectsPressureSolverThatIsNotAString) {
  EXPECT_TRUE(scene_error(
      R"({"fluid": {"pressure_solver": 1}})",
      "fluid.pressure_solver must be one of \"pcisph\", \"wcsph\", \"dfsph\", \"pbf\", got 1 (x.json)"));
}

TEST(SceneLoader, ReadsDfsphWithItsSettings) {
  const SceneConfig c = parse(R"({"fluid": {"pressure_solver": "dfsph", "dfsph": {"eta": 0.001,
      "eta_divergence": 0.2, "min_iterations": 3, "max_iterations": 50, "max_divergence_iterations": 40}}})");
  EXPECT_EQ(c.fluid.pressure_solver, PressureSolverKind::DFSPH);
  EXPECT_DOUBLE_EQ(c.fluid.dfsph.eta, 0.001);
  EXPECT_DOUBLE_EQ(c.fluid.dfsph.eta_divergence, 0.2);
  EXPECT_EQ(c.fluid.dfsph.min_iterations, 3);
  EXPECT_EQ(c.fluid.dfsph.max_iterations, 50);
  EXPECT_EQ(c.fluid.dfsph.max_divergence_iterations, 40);
}

TEST(SceneLoader, DfsphDefaultsAndNullUnsetsTheReliefLimit) {
  const DfsphSettings d = parse(R"({"fluid": {"pressure_solver": "dfsph"}})").fluid.dfsph;
  EXPECT_DOUBLE_EQ(d.eta, 0.0005);
  EXPECT_DOUBLE_EQ(d.eta_divergence, 0.4);
  EXPECT_EQ(d.min_iterations, 2);
  EXPECT_EQ(d.max_iterations, 100);
  EXPECT_EQ(d.max_divergence_iterations, 100);
  EXPECT_EQ(d.max_relief_per_substep, 0.05);
  EXPECT_FALSE(d.warm_start);
  EXPECT_TRUE(parse(R"({"fluid": {"dfsph": {"warm_start": true}}})").fluid.dfsph.warm_start);
  EXPECT_EQ(d.precision, IterationPrecision::SINGLE);
  EXPECT_EQ(parse(R"({"fluid": {"dfsph": {"precision": "double"}}})").fluid.dfsph.precision,
            IterationPrecision::DOUBLE);
  EXPECT_FALSE(
      parse(R"({"fluid": {"dfsph": {"max_relief_per_substep": null}}})").fluid.dfsph.max_relief_per_substep);
}

TEST(SceneLoader, ReadsPbfWithItsSettingsAndDefaults) {
  const PbfSettings d = parse(R"({"fluid": {"pressure_solver": "pbf"}})").fluid.pbf;
  EXPECT_EQ(d.substeps, 4);
  EXPECT_EQ(d.iterations, 4);
  EXPECT_DOUBLE_EQ(d.relaxation, 1e-6);
  EXPECT_DOUBLE_EQ(d.scorr_k, 0.1);
  EXPECT_EQ(d.scorr_n, 4);
  EXPECT_DOUBLE_EQ(d.scorr_dq, 0.2);
  EXPECT_EQ(d.max_compression_per_iteration, 0.05);
  EXPECT_EQ(d.scorr_substep, 1.0 / 240.0);
  EXPECT_FALSE(parse(R"({"fluid": {"pbf": {"max_compression_per_iteration": null}}})")
                   .fluid.pbf.max_compression_per_iteration);
  EXPECT_FALSE(parse(R"({"fluid": {"pbf": {"scorr_substep": null}}})").fluid.pbf.scorr_substep);
  EXPECT_EQ(parse(R"({"fluid": {"pbf": {"scorr_substep": 0.001}}})").fluid.pbf.scorr_substep, 0.001);
  EXPECT_EQ(d.precision, IterationPrecision::SINGLE);
  EXPECT_EQ(parse(R"({"fluid": {"pbf": {"precision": "double"}}})").fluid.pbf.precision,
            IterationPrecision::DOUBLE);
  EXPECT_EQ(parse(R"({"fluid": {"pbf": {"precision": "single"}}})").fluid.pbf.precision,
            IterationPrecision::SINGLE);
  const SceneConfig c = parse(R"({"fluid": {"pressure_solver": "pbf", "pbf": {"substeps": 2, "iterations": 6,
      "relaxation": 0.5, "scorr_k": 0, "scorr_n": 2, "scorr_dq": 0.3}}})");
  EXPECT_EQ(c.fluid.pressure_solver, PressureSolverKind::PBF);
  EXPECT_EQ(c.fluid.pbf.substeps, 2);
  EXPECT_EQ(c.fluid.pbf.iterations, 6);
  EXPECT_DOUBLE_EQ(c.fluid.pbf.relaxation, 0.5);
  EXPECT_DOUBLE_EQ(c.fluid.pbf.scorr_k, 0.0);
  EXPECT_EQ(c.fluid.pbf.scorr_n, 2);
  EXPECT_DOUBLE_EQ(c.fluid.pbf.scorr_dq, 0.3);
}

TEST(SceneLoader, RejectsBadPbfSettingsNamingTheKey) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"substeps": 0}}})",
                          "fluid.pbf.substeps must be in [1, 1000], got 0 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"iterations": 2.5}}})", "fluid.pbf.iterations"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"relaxation": -1}}})",
                          "fluid.pbf.relaxation must be >= 0, got -1 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"scorr_dq": 1}}})",
                          "fluid.pbf.scorr_dq must be in (0, 1), got 1 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"sub_steps": 2}}})",
                          "fluid.pbf.sub_steps is not a known key (x.json); known: substeps, iterations, "
                          "relaxation, scorr_k, scorr_n, scorr_dq, max_compression_per_iteration, "
                          "scorr_substep, precision"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"precision": "half"}}})", "fluid.pbf.precision"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"max_compression_per_iteration": 0}}})",
                          "fluid.pbf.max_compression_per_iteration must be > 0, got 0 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"pbf": {"scorr_substep": -0.004}}})",
                          "fluid.pbf.scorr_substep must be > 0, got -0.004 (x.json)"));
}

TEST(SceneLoader, RejectsBadDfsphSettingsNamingTheKey) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"dfsph": {"eta": 0}}})",
                          "fluid.dfsph.eta must be in (0, 1), got 0 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"dfsph": {"eta_divergence": -1}}})",
                          "fluid.dfsph.eta_divergence must be > 0, got -1 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"dfsph": {"max_divergence_iterations": 0}}})",
                          "fluid.dfsph.max_divergence_iterations must be in [1, 1000], got 0 (x.json)"));
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"dfsph": {"min_iterations": 5, "max_iterations": 4}}})",
                  "fluid.dfsph.max_iterations must be >= fluid.dfsph.min_iterations = 5, got 4 (x.json)"));
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"dfsph": {"eta_div": 0.1}}})",
                  "fluid.dfsph.eta_div is not a known key (x.json); known: eta, eta_divergence, "
                  "min_iterations, max_iterations, max_divergence_iterations, max_relief_per_substep, "
                  "warm_start, precision"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"dfsph": {"max_relief_per_substep": 0}}})",
                          "fluid.dfsph.max_relief_per_substep must be > 0, got 0 (x.json)"));
}

TEST(SceneLoader, ReadsAdaptiveTimeStepAndRejectsBadBounds) {
  const SceneConfig c = parse(R"({"time": {"dt": 0.01, "adaptive": true, "dt_min": 0.001}})");
  EXPECT_TRUE(c.time.adaptive);
  EXPECT_DOUBLE_EQ(c.time.dt_min, 0.001);
  EXPECT_FALSE(parse("{}").time.adaptive);
  EXPECT_TRUE(scene_error(R"({"time": {"dt_min": 0}})", "time.dt_min must be > 0, got 0 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"time": {"dt": 0.001, "dt_min": 0.01}})",
                          "time.dt must be >= time.dt_min = 0.01, got 0.001 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"time": {"dt_min": 0.01}})",
                          "time.dt_min must be <= time.dt = 0.005, got 0.01 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"time": {"adaptive": 1}})", "time.adaptive"));
}

TEST(SceneLoader, RejectsZeroSpeedOfSound) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"wcsph": {"speed_of_sound": 0}}})",
                          "fluid.wcsph.speed_of_sound must be in (0, 2000], got 0 (x.json)"));
}

TEST(SceneLoader, RejectsTaitExponentBelowOne) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"wcsph": {"exponent": 0.5}}})",
                          "fluid.wcsph.exponent must be >= 1, got 0.5 (x.json)"));
}

TEST(SceneLoader, RejectsUnknownWcsphKey) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"wcsph": {"gamma": 7}}})",
                          "fluid.wcsph.gamma is not a known key (x.json); known: speed_of_sound, exponent"));
}

TEST(SceneLoader, RejectsPcisphEtaOfOne) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"eta": 1}}})",
                          "fluid.pcisph.eta must be in (0, 1), got 1 (x.json)"));
}

TEST(SceneLoader, RejectsZeroPcisphEta) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"eta": 0}}})",
                          "fluid.pcisph.eta must be in (0, 1), got 0 (x.json)"));
}

TEST(SceneLoader, RejectsZeroMinIterations) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"min_iterations": 0}}})",
                          "fluid.pcisph.min_iterations must be in [1, 1000], got 0 (x.json)"));
}

TEST(SceneLoader, RejectsMaxIterationsBelowMinIterations) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"pcisph": {"min_iterations": 5, "max_iterations": 4}}})",
                  "fluid.pcisph.max_iterations must be >= fluid.pcisph.min_iterations = 5, got 4 (x.json)"));
}

TEST(SceneLoader, RejectsMinIterationsAboveDefaultMaxOnTheKeyGiven) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"pcisph": {"min_iterations": 200}}})",
                  "fluid.pcisph.min_iterations must be <= fluid.pcisph.max_iterations = 100, got 200"));
}

TEST(SceneLoader, RejectsFractionalIterationCount) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"pcisph": {"max_iterations": 10.0}}})",
                          "fluid.pcisph.max_iterations must be an integer, got 10.0 (x.json)"));
}

TEST(SceneLoader, RejectsUnknownViscosityMethod) {
  EXPECT_TRUE(scene_error(
      R"({"fluid": {"viscosity": {"method": "laminar"}}})",
      "fluid.viscosity.method must be one of \"xsph\", \"artificial\", got \"laminar\" (x.json)"));
}

TEST(SceneLoader, ReadsTheSurfaceTensionModel) {
  EXPECT_EQ(parse(R"({})").surface_tension.model, SurfaceTensionModel::CSF);
  const SceneConfig c =
      parse(R"({"effects": ["surface_tension"], "surface_tension": {"sigma": 0.05, "model": "csf"}})");
  EXPECT_EQ(c.surface_tension.model, SurfaceTensionModel::CSF);
  EXPECT_DOUBLE_EQ(c.surface_tension.sigma, 0.05);
  EXPECT_EQ(parse(R"({"effects": ["surface_tension"], "surface_tension": {"model": "akinci"}})")
                .surface_tension.model,
            SurfaceTensionModel::AKINCI);
}

TEST(SceneLoader, RejectsUnknownSurfaceTensionModel) {
  EXPECT_TRUE(
      scene_error(R"({"effects": ["surface_tension"], "surface_tension": {"model": "becker"}})",
                  "surface_tension.model must be one of \"csf\", \"akinci\", got \"becker\" (x.json)"));
}

TEST(SceneLoader, RejectsNegativeViscosityCoefficient) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"viscosity": {"coefficient": -0.1}}})",
                          "fluid.viscosity.coefficient must be >= 0, got -0.1 (x.json)"));
}

TEST(SceneLoader, RejectsZeroCfl) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"cfl": 0}})", "fluid.cfl must be in (0, 1], got 0 (x.json)"));
}

TEST(SceneLoader, RejectsCflAboveOne) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"cfl": 1.5}})", "fluid.cfl must be in (0, 1], got 1.5 (x.json)"));
}

TEST(SceneLoader, MaxSpeedDefaultsTo1000AndNullMeansNoLimit) {
  EXPECT_EQ(parse("{}").fluid.max_speed, 1000.0);
  EXPECT_EQ(parse(R"({"fluid": {"max_speed": 50}})").fluid.max_speed, 50.0);
  EXPECT_FALSE(parse(R"({"fluid": {"max_speed": null}})").fluid.max_speed);
  EXPECT_TRUE(scene_error(R"({"fluid": {"max_speed": 0}})", "fluid.max_speed must be > 0, got 0 (x.json)"));
}

// An emitter at the limit would stop the run at its first particle: a load error naming the emitter's key.
TEST(SceneLoader, RejectsAnEmitterAtOrOverMaxSpeedNamingIt) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"max_speed": 50}, "emitters": [{"type": "nozzle", "speed": 49},
                                                               {"type": "nozzle", "speed": 50}]})",
                          "emitters[1].speed must be slower than fluid.max_speed (50 m/s), got 50 (x.json)"));
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"max_speed": 50}, "emitters": [{"type": "box", "velocity": [30, -40, 1]}]})",
                  "emitters[0].velocity must be slower than fluid.max_speed (50 m/s), got [30,-40,1]"));
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"max_speed": 0.5}, "emitters": [{"type": "nozzle"}]})",
                  "emitters[0].speed must be slower than fluid.max_speed (0.5 m/s), as its default is"));
  EXPECT_NO_THROW(
      parse(R"({"fluid": {"max_speed": null}, "emitters": [{"type": "nozzle", "speed": 5000}]})"));
}

TEST(SceneLoader, RejectsZeroSortInterval) {
  EXPECT_TRUE(
      scene_error(R"({"fluid": {"sort_interval": 0}})", "fluid.sort_interval must be >= 1, got 0 (x.json)"));
}

TEST(SceneLoader, RejectsSubstepHalvingsOutsideZeroToTwenty) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"substep_halvings": -1}})",
                          "fluid.substep_halvings must be in [0, 20], got -1 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"substep_halvings": 21}})",
                          "fluid.substep_halvings must be in [0, 20], got 21 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"fluid": {"substep_halvings": 1.5}})",
                          "fluid.substep_halvings must be an integer, got 1.5 (x.json)"));
}

TEST(SceneLoader, RejectsSortIntervalBeyondIntRange) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"sort_interval": 3000000000}})",
                          "fluid.sort_interval must be <= 2147483647, got 3000000000 (x.json)"));
}

TEST(SceneLoader, RejectsSortIntervalGivenAsString) {
  EXPECT_TRUE(scene_error(R"({"fluid": {"sort_interval": "10"}})",
                          "fluid.sort_interval must be an integer, got \"10\" (x.json)"));
}

// ---------------------------------------------------------------------------------------------------------
// emitters

TEST(SceneLoader, RejectsEmittersThatIsNotAnArray) {
  EXPECT_TRUE(
      scene_error(R"({"emitters": {"type": "box"}})", "emitters must be an array, got {\"type\":\"box\"}"));
}

TEST(SceneLoader, RejectsEmitterThatIsNotAnObject) {
  EXPECT_TRUE(
      scene_error(R"({"emitters": ["nozzle"]})", "emitters[0] must be an object, got \"nozzle\" (x.json)"));
}

TEST(SceneLoader, RejectsEmitterWithoutType) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"speed": 1}]})",
                          "emitters[0].type is missing; must be one of \"nozzle\", \"box\" (x.json)"));
}

TEST(SceneLoader, RejectsUnknownEmitterTypeNamingIndexAndChoices) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "box"}, {"type": "jet"}]})",
                          "emitters[1].type must be one of \"nozzle\", \"box\", got \"jet\" (x.json)"));
}

TEST(SceneLoader, RejectsNozzleKeyOnBoxEmitter) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "box", "radius": 0.1}]})",
                          "emitters[0].radius is not a known key (x.json); known: type, min, max, velocity"));
}

TEST(SceneLoader, RejectsBoxKeyOnNozzleEmitter) {
  EXPECT_TRUE(
      scene_error(R"({"emitters": [{"type": "nozzle", "velocity": [0, 0, 0]}]})",
                  "emitters[0].velocity is not a known key (x.json); known: type, center, direction"));
}

TEST(SceneLoader, RejectsZeroNozzleDirection) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "direction": [0, 0, 0]}]})",
                          "emitters[0].direction must be non-zero, got [0,0,0] (x.json)"));
}

TEST(SceneLoader, RejectsZeroNozzleRadius) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "radius": 0}]})",
                          "emitters[0].radius must be in (0, 10000000], got 0 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeNozzleSpeed) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "speed": -1}]})",
                          "emitters[0].speed must be > 0, got -1 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeNozzleStartTime) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "start_time": -0.5}]})",
                          "emitters[0].start_time must be >= 0, got -0.5 (x.json)"));
}

TEST(SceneLoader, RejectsFractionalMaxParticles) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "max_particles": 1.5}]})",
                          "emitters[0].max_particles must be an integer, got 1.5 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeMaxParticles) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "max_particles": -1}]})",
                          "emitters[0].max_particles must be >= 0, got -1 (x.json)"));
}

TEST(SceneLoader, RejectsMaxParticlesBeyondInt64) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "nozzle", "max_particles": 18446744073709551615}]})",
                          "emitters[0].max_particles must be <= 9223372036854775807"));
}

TEST(SceneLoader, RejectsBoxEmitterWithMaxNotAboveMinOnEveryAxis) {
  EXPECT_TRUE(
      scene_error(R"({"emitters": [{"type": "box", "min": [0, 0, 0], "max": [1, 0, 1]}]})",
                  "emitters[0].max must be > emitters[0].min = [0.0,0.0,0.0] on every axis, got [1,0,1] "
                  "(x.json)"));
}

TEST(SceneLoader, RejectsBoxEmitterMinAboveDefaultMaxOnTheKeyGiven) {
  EXPECT_TRUE(
      scene_error(R"({"emitters": [{"type": "box", "min": [2, 2, 2]}]})",
                  "emitters[0].min must be < emitters[0].max = [1.0,1.0,1.0] on every axis, got [2,2,2]"));
}

TEST(SceneLoader, RejectsBoxEmitterVelocityOfWrongLength) {
  EXPECT_TRUE(scene_error(R"({"emitters": [{"type": "box", "velocity": [1, 0, 0, 0]}]})",
                          "emitters[0].velocity must be an array of 3 numbers, got [1,0,0,0] (x.json)"));
}

// ---------------------------------------------------------------------------------------------------------
// boundaries

TEST(SceneLoader, RejectsUnknownBoundaryType) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "sphere"}]})",
                          "boundaries[0].type must be one of \"box\", \"plane\", got \"sphere\" (x.json)"));
}

TEST(SceneLoader, RejectsBoundaryWithoutType) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"layers": 2}]})",
                          "boundaries[0].type is missing; must be one of \"box\", \"plane\" (x.json)"));
}

TEST(SceneLoader, RejectsBoundaryBoxWithMaxNotAboveMin) {
  EXPECT_TRUE(scene_error(
      R"({"boundaries": [{"type": "box", "min": [0, 0, 0], "max": [1, 1, -1]}]})",
      "boundaries[0].max must be > boundaries[0].min = [0.0,0.0,0.0] on every axis, got [1,1,-1]"));
}

TEST(SceneLoader, RejectsZeroBoundaryLayers) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "box", "layers": 0}]})",
                          "boundaries[0].layers must be >= 1, got 0 (x.json)"));
}

TEST(SceneLoader, RejectsOpenTopThatIsNotABoolean) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "box", "open_top": "yes"}]})",
                          "boundaries[0].open_top must be true or false, got \"yes\" (x.json)"));
}

TEST(SceneLoader, RejectsPlaneKeyOnBoundaryBox) {
  EXPECT_TRUE(scene_error(
      R"({"boundaries": [{"type": "box", "normal": [0, 1, 0]}]})",
      "boundaries[0].normal is not a known key (x.json); known: type, min, max, open_top, layers"));
}

TEST(SceneLoader, RejectsZeroBoundaryPlaneNormal) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "plane", "normal": [0, 0, 0]}]})",
                          "boundaries[0].normal must be non-zero, got [0,0,0] (x.json)"));
}

TEST(SceneLoader, RejectsBoundaryPlaneSizeWithOneEntry) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "plane", "size": [1]}]})",
                          "boundaries[0].size must be an array of 2 numbers, got [1] (x.json)"));
}

TEST(SceneLoader, RejectsZeroBoundaryPlaneSizeNamingIndex) {
  EXPECT_TRUE(scene_error(R"({"boundaries": [{"type": "plane", "size": [1, 0]}]})",
                          "boundaries[0].size[1] must be in (0, 10000000], got 0 (x.json)"));
}

// ---------------------------------------------------------------------------------------------------------
// kill_regions

TEST(SceneLoader, RejectsUnknownKillRegionType) {
  EXPECT_TRUE(scene_error(R"({"kill_regions": [{"type": "sphere"}]})",
                          "kill_regions[0].type must be one of \"plane\", \"box\", got \"sphere\" (x.json)"));
}

TEST(SceneLoader, RejectsZeroKillPlaneNormal) {
  EXPECT_TRUE(scene_error(R"({"kill_regions": [{"type": "plane", "normal": [0, 0, 0]}]})",
                          "kill_regions[0].normal must be non-zero, got [0,0,0] (x.json)"));
}

TEST(SceneLoader, RejectsBoxKeyOnKillPlane) {
  EXPECT_TRUE(scene_error(R"({"kill_regions": [{"type": "plane", "min": [0, 0, 0]}]})",
                          "kill_regions[0].min is not a known key (x.json); known: type, point, normal"));
}

TEST(SceneLoader, RejectsKillBoxWithMaxNotAboveMin) {
  EXPECT_TRUE(scene_error(R"({"kill_regions": [{"type": "box", "min": [0, 0, 0], "max": [0, 1, 1]}]})",
                          "kill_regions[0].max must be > kill_regions[0].min = [0.0,0.0,0.0] on every axis"));
}

// ---------------------------------------------------------------------------------------------------------
// time

TEST(SceneLoader, RejectsTimeStepGivenAsStringSayingNumberExpected) {
  EXPECT_TRUE(scene_error(R"({"time": {"dt": "fast"}})", "time.dt must be a number, got \"fast\" (x.json)"));
}

TEST(SceneLoader, RejectsZeroTimeStep) {
  EXPECT_TRUE(scene_error(R"({"time": {"dt": 0}})", "time.dt must be > 0, got 0 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeDuration) {
  EXPECT_TRUE(scene_error(R"({"time": {"duration": -1}})", "time.duration must be > 0, got -1 (x.json)"));
}

TEST(SceneLoader, RejectsNegativeFrameRate) {
  EXPECT_TRUE(
      scene_error(R"({"time": {"frame_rate": -30}})", "time.frame_rate must be >= 0, got -30 (x.json)"));
}

TEST(SceneLoader, RejectsTimeStepLongerThanDuration) {
  EXPECT_TRUE(scene_error(R"({"time": {"dt": 0.5, "duration": 0.1}})",
                          "time.duration must be >= time.dt = 0.5, got 0.1 (x.json)"));
}

TEST(SceneLoader, RejectsTimeStepLongerThanDefaultDurationOnTheKeyGiven) {
  EXPECT_TRUE(scene_error(R"({"time": {"dt": 2}})", "time.dt must be <= time.duration = 1, got 2 (x.json)"));
}

TEST(SceneLoader, RejectsUnknownTimeKey) {
  EXPECT_TRUE(scene_error(R"({"time": {"fps": 30}})",
                          "time.fps is not a known key (x.json); known: dt, duration, frame_rate"));
}

// ---------------------------------------------------------------------------------------------------------
// effects

TEST(SceneLoader, ReadsObstacles) {
  const SceneConfig c = parse(R"({"obstacles": [
      {"mesh": "v_plane", "center": [0, 0.1, 0], "angle_deg": 60, "size": 0.3, "width": 0.2, "triangle_size": 0.01},
      {"mesh": "/data/rock.obj", "center": [1, 2, 3], "scale": 0.5}],
      "effects": ["coupling"]})");
  ASSERT_EQ(c.obstacles.size(), 2u);
  EXPECT_EQ(c.obstacles[0].mesh, "v_plane");
  EXPECT_EQ(c.obstacles[0].center, Vec3(0, 0.1, 0));
  EXPECT_EQ(c.obstacles[0].angle_deg, 60.0);
  EXPECT_EQ(c.obstacles[0].size, 0.3);
  EXPECT_EQ(c.obstacles[0].width, 0.2);
  EXPECT_EQ(c.obstacles[0].triangle_size, 0.01);
  EXPECT_EQ(c.obstacles[1].mesh, "/data/rock.obj");
  EXPECT_EQ(c.obstacles[1].scale, 0.5);
  EXPECT_FALSE(c.cloth) << "obstacles alone may be coupled";
}

TEST(SceneLoader, RejectsObstacleKeysOfTheOtherKind) {
  EXPECT_TRUE(scene_error(R"({"obstacles": [{"mesh": "v_plane", "scale": 2}]})",
                          "obstacles[0].scale applies to an OBJ mesh only, got 2 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"obstacles": [{"mesh": "a.obj", "angle_deg": 45}]})",
                          "obstacles[0].angle_deg applies to \"mesh\": \"v_plane\" only, got 45 (x.json)"));
  EXPECT_TRUE(scene_error(R"({"obstacles": [{"center": [0, 0, 0]}]})", "obstacles[0].mesh is missing"));
  EXPECT_TRUE(scene_error(R"({"obstacles": [{"mesh": "v_plane", "angle_deg": 180}]})",
                          "obstacles[0].angle_deg must be in (0, 180), got 180 (x.json)"));
}

TEST(SceneFile, ObstacleObjIsFoundBesideTheSceneAndAMissingOneIsNamed) {
  const test::TempDir dir;
  const std::string file =
      dir.write("scene.json", R"({"obstacles": [{"mesh": "no_such_rock.obj"}], "effects": ["coupling"]})");
  const SceneConfig c = load_scene_file(file);
  const std::string expected = (std::filesystem::path(file).parent_path() / "no_such_rock.obj").string();
  EXPECT_EQ(c.obstacles[0].mesh, expected);
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { Simulation sim(c); }, "obstacles[0].mesh: OBJ file \"" + expected + "\" cannot be read"));
}

TEST(SceneLoader, ReadsTheSurfaceSection) {
  const SceneConfig c = parse(
      R"({"effects": ["surface"], "surface": {"cell_size": 0.004, "contact_aware": false, "contact_offset": 0}})");
  EXPECT_EQ(c.surface.cell_size, 0.004);
  EXPECT_FALSE(c.surface.contact_aware);
  EXPECT_EQ(c.surface.contact_offset, 0.0);
  EXPECT_EQ(c.surface.field, SurfaceField::ZHU_BRIDSON);
  EXPECT_EQ(parse(R"({"effects": ["surface"], "surface": {"field": "density"}})").surface.field,
            SurfaceField::DENSITY);
  EXPECT_TRUE(scene_error(R"({"effects": ["surface"], "surface": {"field": "splashsurf"}})",
                          "surface.field must be one of \"zhu_bridson\", \"density\""));
}

TEST(SceneLoader, ReadsTheAnisotropicKernelsSettings) {
  const SceneConfig c =
      parse(R"({"effects": ["surface"], "surface": {"kernel": "anisotropic", "smoothing": 0.5,
      "max_anisotropy": 3, "anisotropy_scale": 8, "isolated_scale": 0.7, "min_neighbours": 10}})");
  EXPECT_EQ(c.surface.kernel, SurfaceKernel::ANISOTROPIC);
  EXPECT_EQ(c.surface.field, SurfaceField::DENSITY) << "Yu & Turk's kernels are the density field's";
  EXPECT_EQ(c.surface.smoothing, 0.5);
  EXPECT_EQ(c.surface.max_anisotropy, 3.0);
  EXPECT_EQ(c.surface.anisotropy_scale, 8.0);
  EXPECT_EQ(c.surface.isolated_scale, 0.7);
  EXPECT_EQ(c.surface.min_neighbours, 10);
  EXPECT_EQ(parse(R"({"effects": ["surface"]})").surface.kernel, SurfaceKernel::ISOTROPIC);
  EXPECT_TRUE(
      scene_error(R"({"effects": ["surface"], "surface": {"kernel": "anisotropic", "field": "zhu_bridson"}})",
                  "surface.field must be \"density\""));
  EXPECT_TRUE(scene_error(R"({"effects": ["surface"], "surface": {"smoothing": 1.5}})", "surface.smoothing"));
  EXPECT_TRUE(scene_error(R"({"effects": ["surface"], "surface": {"max_anisotropy": 0.5}})",
                          "surface.max_anisotropy"));
  EXPECT_TRUE(
      scene_error(R"({"effects": ["surface"], "surface": {"min_neighbours": 0}})", "surface.min_neighbours"));
}

TEST(SceneLoader, RejectsANegativeContactOffset) {
  EXPECT_TRUE(scene_error(R"({"effects": ["surface"], "surface": {"contact_offset": -0.001}})",
                          "surface.contact_offset"));
}

TEST(SceneLoader, RejectsANonPositiveSurfaceCellSize) {
  EXPECT_TRUE(scene_error(R"({"effects": ["surface"], "surface": {"cell_size": 0}})", "surface.cell_size"));
  EXPECT_TRUE(
      scene_error(R"({"effects": ["surface"], "surface": {"cell_size": -0.004}})", "surface.cell_size"));
}

TEST(SceneLoader, RejectsSurfaceSettingsWithoutTheSurfaceEffect) {
  EXPECT_TRUE(scene_error(R"({"surface": {"cell_size": 0.004}})", "effects does not list \"surface\""));
}

TEST(SceneLoader, ReadsTheWettingSectionAndChecksWhatItNeeds) {
  const std::string cloth = R"("cloth": {"mesh": "patch"}, )";
  const SceneConfig c =
      parse("{" + cloth +
            R"("effects": ["coupling", "wetting"], "wetting": {"max_saturation": 2, "absorption_rate": 5,
                "diffusion": 0.001, "gravity_flow": 0}})");
  EXPECT_EQ(c.wetting.max_saturation, 2.0);
  EXPECT_EQ(c.wetting.absorption_rate, 5.0);
  EXPECT_EQ(c.wetting.diffusion, 0.001);
  EXPECT_EQ(c.wetting.gravity_flow, 0.0);
  // The rates' upper bounds: the explicit spread's sub-steps grow with them (kMaxWettingDiffusion,
  // kMaxGravityFlow).
  for (const auto& [wetting, message] : std::vector<std::pair<std::string, std::string>>{
           {R"({"max_saturation": 0})", "wetting.max_saturation"},
           {R"({"diffusion": -1})", "wetting.diffusion"},
           {R"({"diffusion": 1e6})", "wetting.diffusion must be in [0, 1], got 1000000.0 (x.json)"},
           {R"({"gravity_flow": 1e9})", "wetting.gravity_flow must be in [0, 10], got 1000000000.0 (x.json)"},
           {R"({"porosity": 1})", "porosity is not a known key"}}) {
    EXPECT_TRUE(scene_error(
        "{" + cloth + R"("effects": ["coupling", "wetting"], "wetting": )" + wetting + "}", message))
        << wetting;
  }
  EXPECT_TRUE(
      scene_error("{" + cloth + R"("wetting": {"diffusion": 0.001}})", "effects does not list \"wetting\""));
  EXPECT_TRUE(scene_error(R"({"effects": ["wetting"]})", "effects[0] needs a cloth"));
  EXPECT_TRUE(scene_error("{" + cloth + R"("effects": ["wetting"]})", "needs the \"coupling\" effect"));
}

TEST(SceneLoader, RejectsUnknownEffectListingKnownEffects) {
  EXPECT_TRUE(
      scene_error(R"({"effects": ["viscosity", "magic"]})",
                  "effects[1] must be one of \"viscosity\", \"surface_tension\", \"coupling\", \"friction\", "
                  "\"adhesion\", \"leak_audit\", "
                  "\"surface\", \"wetting\", got "
                  "\"magic\" (x.json)"));
  // Every effect of the registry, also one added later, is named.
  for (const EffectEntry& effect : effect_registry())
    EXPECT_TRUE(scene_error(R"({"effects": ["magic"]})", "\"" + std::string(effect.name) + "\""));
}

TEST(SceneLoader, RejectsDuplicateEffectListingKnownEffects) {
  EXPECT_TRUE(scene_error(
      R"({"effects": ["viscosity", "viscosity"]})",
      "effects[1] repeats effects[0]; list each of \"viscosity\", \"surface_tension\", \"coupling\", "
      "\"friction\", \"adhesion\", "
      "\"leak_audit\", \"surface\", \"wetting\" at most once, got \"viscosity\""));
}

TEST(SceneLoader, RejectsEffectsGivenAsString) {
  EXPECT_TRUE(
      scene_error(R"({"effects": "viscosity"})", "effects must be an array, got \"viscosity\" (x.json)"));
}

TEST(SceneLoader, RejectsEffectThatIsNotAString) {
  EXPECT_TRUE(scene_error(R"({"effects": [1]})", "effects[0] must be a string, got 1 (x.json)"));
}

TEST(SceneLoader, ShortensHugeValuesInMessages) {
  const std::string long_name(200, 'a');
  EXPECT_TRUE(scene_error(R"({"effects": [")" + long_name + R"("]})",
                          "got \"" + std::string(76, 'a') + "... (x.json)"));
}

// ---------------------------------------------------------------------------------------------------------
// Overrides

TEST(SceneOverride, SetsNestedNumber) {
  json document = json::parse(kFullScene);
  apply_override(document, "time.dt=0.004");
  EXPECT_DOUBLE_EQ(parse_scene(document, "x.json").time.dt, 0.004);
}

TEST(SceneOverride, SetsArrayElementWithBrackets) {
  json document = json::parse(kFullScene);
  apply_override(document, "emitters[0].speed=5");
  EXPECT_DOUBLE_EQ(parse_scene(document, "x.json").emitters[0].nozzle.speed, 5.0);
}

TEST(SceneOverride, SetsArrayElementWithDottedIndex) {
  json document = json::parse(kFullScene);
  apply_override(document, "emitters.0.speed=5");
  EXPECT_DOUBLE_EQ(parse_scene(document, "x.json").emitters[0].nozzle.speed, 5.0);
}

TEST(SceneOverride, ReplacesWholeArrayElement) {
  json document = json::parse(kFullScene);
  apply_override(document, R"(emitters[1]={"type":"nozzle"})");
  EXPECT_EQ(parse_scene(document, "x.json").emitters[1].kind, EmitterSettings::Kind::NOZZLE);
}

TEST(SceneOverride, SetsArrayValueFromJson) {
  json document = json::parse("{}");
  apply_override(document, R"(effects=["viscosity"])");
  EXPECT_TRUE(parse_scene(document, "x.json").has_effect("viscosity"));
}

TEST(SceneOverride, TakesInvalidJsonValueAsString) {
  json document = json::parse("{}");
  apply_override(document, "fluid.pressure_solver=wcsph");
  EXPECT_EQ(document["fluid"]["pressure_solver"], "wcsph");
  EXPECT_EQ(parse_scene(document, "x.json").fluid.pressure_solver, PressureSolverKind::WCSPH);
}

TEST(SceneOverride, CreatesMissingIntermediateObjects) {
  json document = json::parse("{}");
  apply_override(document, "fluid.pcisph.eta=0.02");
  EXPECT_DOUBLE_EQ(parse_scene(document, "x.json").fluid.pcisph.eta, 0.02);
}

TEST(SceneOverride, AddsNewKeyToExistingObject) {
  json document = json::parse(R"({"fluid": {"cfl": 0.3}})");
  apply_override(document, "fluid.sort_interval=4");
  const SceneConfig c = parse_scene(document, "x.json");
  EXPECT_DOUBLE_EQ(c.fluid.cfl, 0.3);
  EXPECT_EQ(c.fluid.sort_interval, 4);
}

TEST(SceneOverride, LaterAssignmentWins) {
  json document = json::parse("{}");
  apply_override(document, "time.dt=0.01");
  apply_override(document, "time.dt=0.02");
  EXPECT_DOUBLE_EQ(parse_scene(document, "x.json").time.dt, 0.02);
}

TEST(SceneOverride, ValueMayContainEqualsSign) {
  json document = json::parse("{}");
  apply_override(document, "note=a=b");
  EXPECT_EQ(document["note"], "a=b");
}

TEST(SceneOverride, NullResetsSpeedOfSoundToAuto) {
  json document = json::parse(kFullScene);
  apply_override(document, "fluid.wcsph.speed_of_sound=null");
  EXPECT_FALSE(parse_scene(document, "x.json").fluid.wcsph.speed_of_sound.has_value());
}

TEST(SceneOverride, RejectsAssignmentWithoutEquals) {
  EXPECT_TRUE(override_error("{}", "foo", "--set foo: expected json.path=value"));
}

TEST(SceneOverride, RejectsEmptyPath) {
  EXPECT_TRUE(override_error("{}", "=5", "--set =5: expected json.path=value"));
}

TEST(SceneOverride, RejectsMalformedPath) {
  EXPECT_TRUE(override_error("{}", "time..dt=1", "--set time..dt=1: malformed path \"time..dt\""));
}

TEST(SceneOverride, RejectsNonNumericBracketIndex) {
  EXPECT_TRUE(override_error(kFullScene, "emitters[x].speed=1", "--set emitters[x].speed=1: malformed path"));
}

TEST(SceneOverride, RejectsArrayIndexPastTheEnd) {
  EXPECT_TRUE(override_error(R"({"emitters": [{"type": "box"}]})", "emitters[3].speed=5",
                             "--set emitters[3].speed=5: emitters has 1 element(s)"));
}

TEST(SceneOverride, RejectsDottedIndexPastTheEnd) {
  EXPECT_TRUE(override_error(R"({"emitters": []})", "emitters.0.speed=5",
                             "--set emitters.0.speed=5: emitters has 0 element(s)"));
}

TEST(SceneOverride, RejectsIndexIntoMissingArray) {
  EXPECT_TRUE(
      override_error("{}", "emitters[0].speed=5",
                     "--set emitters[0].speed=5: emitters is missing; --set creates objects but not arrays"));
}

TEST(SceneOverride, RejectsIndexIntoObject) {
  EXPECT_TRUE(
      override_error(R"({"fluid": {}})", "fluid[0]=1", "--set fluid[0]=1: fluid is an object, not an array"));
}

TEST(SceneOverride, RejectsKeyIntoArray) {
  EXPECT_TRUE(
      override_error(kFullScene, "emitters.speed=1",
                     "--set emitters.speed=1: emitters is an array; expected an index, e.g. emitters[0]"));
}

TEST(SceneOverride, RejectsPathThroughNumber) {
  EXPECT_TRUE(override_error(R"({"time": {"dt": 0.004}})", "time.dt.x=1",
                             "--set time.dt.x=1: time.dt is not an object or array, got 0.004"));
}

TEST(SceneOverride, RejectsInvalidUtf8) {
  EXPECT_TRUE(override_error("{}", "note=\xff", "not valid UTF-8"));
}

TEST(SceneOverride, BadValueFailsWithSameValidationAsFile) {
  json document = json::parse(kFullScene);
  apply_override(document, "fluid.particle_spacing=-0.01");
  EXPECT_TRUE(throws_containing<SceneError>([&] { parse_scene(document, "x.json"); },
                                            "fluid.particle_spacing must be > 0, got -0.01 (x.json)"));
}

TEST(SceneOverride, MisspeltKeyIsReportedAsUnknown) {
  json document = json::parse("{}");
  apply_override(document, "fluid.visocsity=1");
  EXPECT_TRUE(
      throws_containing<SceneError>([&] { parse_scene(document, "x.json"); },
                                    "fluid.visocsity is not a known key (x.json); known: rest_density"));
}

// ---------------------------------------------------------------------------------------------------------
// Files

TEST(SceneFile, LoadsSceneFromFile) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", kFullScene);
  const SceneConfig c = load_scene_file(file);
  EXPECT_EQ(c.source, file);
  EXPECT_EQ(c.emitters.size(), 2u);
}

TEST(SceneFile, AppliesOverridesAndNamesThemInSource) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", kFullScene);
  const SceneConfig c = load_scene_file(file, {"time.dt=0.001", "emitters[0].speed=4"});
  EXPECT_DOUBLE_EQ(c.time.dt, 0.001);
  EXPECT_DOUBLE_EQ(c.emitters[0].nozzle.speed, 4.0);
  EXPECT_EQ(c.source, file + " with --set time.dt=0.001 --set emitters[0].speed=4");
}

TEST(SceneFile, RejectsBadOverrideValueNamingFileAndOverrides) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", kFullScene);
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { load_scene_file(file, {"fluid.particle_spacing=-1"}); },
      "fluid.particle_spacing must be > 0, got -1 (" + file + " with --set fluid.particle_spacing=-1)"));
}

TEST(SceneFile, RejectsOverflowingOverrideAsNonFinite) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", kFullScene);
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file, {"time.dt=1e999"}); },
                                            "time.dt must be finite, got inf (" + file + " with --set"));
}

TEST(SceneFile, RejectsOverridePastArrayEndNamingFile) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", R"({"emitters": [{"type": "box"}]})");
  EXPECT_TRUE(
      throws_containing<SceneError>([&] { load_scene_file(file, {"emitters[3].speed=5"}); },
                                    "--set emitters[3].speed=5: emitters has 1 element(s) (" + file + ")"));
}

TEST(SceneFile, MissingFileThrowsIoErrorNamingPath) {
  const std::string path = testing::TempDir() + "drench_no_such_scene.json";
  EXPECT_TRUE(throws_containing<IoError>([&] { load_scene_file(path); },
                                         path + ": cannot read scene file: No such file or directory"));
}

TEST(SceneFile, ClothObjPathBecomesAbsoluteBesideTheSceneAndAnOverridesBesideTheWorkingDirectory) {
  const test::TempDir dir;
  const std::string file = dir.write("sub/scene.json", R"({"cloth": {"mesh": "../meshes/flag.obj"}})");
  const nlohmann::json document = read_scene_document(file);
  EXPECT_EQ(document["cloth"]["mesh"], (dir.path() / "meshes" / "flag.obj").string());
  EXPECT_EQ(read_scene_document(file, {"cloth.mesh=flag.obj"})["cloth"]["mesh"],
            (std::filesystem::current_path() / "flag.obj").string());
  EXPECT_EQ(read_scene_document(file, {"cloth.mesh=patch"})["cloth"]["mesh"], "patch");
}

TEST(SceneFile, OverridePathDeeperThan64LevelsIsRefused) {
  std::string path = "a";
  for (int i = 0; i < 70; ++i)
    path += ".a";
  EXPECT_TRUE(override_error("{}", path + "=1", "path of 71 levels; JSON nested deeper than 64 levels"));
}

TEST(SceneFile, DirectoryThrowsIoErrorNamingPath) {
  const std::string path = testing::TempDir();
  EXPECT_TRUE(
      throws_containing<IoError>([&] { read_scene_document(path); }, path + ": cannot read scene file"));
}

TEST(SceneFile, MalformedJsonReportsLineAndColumn) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", "{\n  \"time\": {\"dt\": 0.1,}\n}\n");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file); },
                                            file + ": malformed JSON at line 2, column 22: syntax error"));
}

TEST(SceneFile, MalformedJsonPositionAgreesWithParser) {
  const std::string text = "{\n\"a\": [1,\n 2,,3]}";
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", text);
  std::string parser_position;
  json unused;
  try {
    unused = json::parse(text);
  } catch (const json::parse_error& e) {
    const std::string what = e.what();
    parser_position =
        what.substr(what.find("line "), what.find(':', what.find("line ")) - what.find("line "));
  }
  EXPECT_EQ(parser_position, "line 3, column 4");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file); },
                                            "malformed JSON at " + parser_position + ": "));
}

TEST(SceneFile, EmptyFileIsMalformedAtLineOneColumnOne) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", "");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file); },
                                            file + ": malformed JSON at line 1, column 1: "));
}

TEST(SceneFile, NumberOverflowInFileIsMalformed) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", R"({"time": {"dt": 1e999}})");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file); },
                                            file + ": malformed JSON: number overflow"));
}

TEST(SceneFile, ReadDocumentAppliesOverridesWithoutValidating) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", R"({"time": {"dt": 0.01}})");
  const json document = read_scene_document(file, {"time.dt=-5", "fluid.bogus=1"});
  EXPECT_EQ(document["time"]["dt"], -5);
  EXPECT_EQ(document["fluid"]["bogus"], 1);
}

// ---------------------------------------------------------------------------------------------------------
// Canonical text and hashing

TEST(SceneHash, CanonicalTextSortsKeysWithoutSpaces) {
  const json document = json::parse(R"({"time": {"duration": 2, "dt": 0.5}, "effects": ["viscosity"]})");
  EXPECT_EQ(canonical_scene_text(document), R"({"effects":["viscosity"],"time":{"dt":0.5,"duration":2}})");
}

TEST(SceneHash, CanonicalTextIgnoresFormattingAndKeyOrder) {
  const json a = json::parse(R"({"b": 1, "a": [1, 2]})");
  const json b = json::parse("{\n  \"a\": [1,2],\n  \"b\": 1\n}");
  EXPECT_EQ(canonical_scene_text(a), canonical_scene_text(b));
}

TEST(SceneHash, Sha256OfAbcMatchesStandardVector) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(SceneHash, Sha256OfEmptyStringMatchesStandardVector) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(SceneLoader, ReadsClothAndCoupling) {
  const SceneConfig c = parse_scene(nlohmann::json::parse(R"({
    "cloth": {"center": [0, 0.5, 0], "size": [0.3, 0.4], "nodes": [21, 11], "area_density": 0.1,
              "pinned": "corner", "position_iterations": 8, "substeps": 3},
    "coupling": {"cloth_thickness": 0.002, "slip": "no_slip", "broad_phase": "grid", "continuous": false,
                 "scheme": "impulses"},
    "effects": ["coupling", "friction", "leak_audit"]})"),
                                    "x.json");
  ASSERT_TRUE(c.cloth.has_value());
  EXPECT_EQ(c.cloth->center, Vec3(0, 0.5, 0));
  EXPECT_EQ(c.cloth->size_x, 0.3);
  EXPECT_EQ(c.cloth->size_z, 0.4);
  EXPECT_EQ(c.cloth->nodes_x, 21);
  EXPECT_EQ(c.cloth->nodes_z, 11);
  EXPECT_EQ(c.cloth->pinned, "corner");
  EXPECT_EQ(c.cloth->position_iterations, 8);
  EXPECT_EQ(c.cloth->substeps, 3);
  EXPECT_EQ(c.coupling.cloth_thickness, 0.002);
  EXPECT_EQ(c.coupling.slip, SlipCondition::NO_SLIP);
  EXPECT_FALSE(c.coupling.continuous);
  EXPECT_EQ(c.coupling.scheme, CouplingScheme::IMPULSES);
  EXPECT_EQ(CouplingSettings().scheme, CouplingScheme::CARRIED_WATER);
}

TEST(SceneLoader, RejectsUnknownCouplingScheme) {
  EXPECT_TRUE(scene_error(R"({"cloth": {}, "coupling": {"scheme": "implicit"}})",
                          "coupling.scheme must be one of \"carried_water\", \"impulses\", got \"implicit\" "
                          "(x.json)"));
}

TEST(SceneLoader, RejectsCouplingWithoutCloth) {
  EXPECT_TRUE(scene_error(R"({"effects": ["coupling"]})",
                          "effects[0] needs a cloth or obstacles; the scene has no \"cloth\" and no "
                          "\"obstacles\", got \"coupling\" (x.json)"));
}

TEST(SceneLoader, RejectsFrictionSettingsWithoutTheFrictionEffect) {
  EXPECT_TRUE(scene_error(R"({"cloth": {}, "coupling": {"slip": "no_slip"}, "effects": ["coupling"]})",
                          "coupling.slip asks for tangential boundary conditions, but effects does not list "
                          "\"friction\", got \"no_slip\" (x.json)"));
}

TEST(SceneLoader, RejectsBadClothNodeCount) {
  EXPECT_TRUE(
      scene_error(R"({"cloth": {"nodes": [1, 5]}})", "cloth.nodes[0] must be in [2, 4096], got 1 (x.json)"));
}

TEST(SceneLoader, RejectsUnknownPinning) {
  EXPECT_TRUE(
      scene_error(R"({"cloth": {"pinned": "edges"}})",
                  "cloth.pinned must be one of \"corners\", \"corner\", \"none\", got \"edges\" (x.json)"));
}

// --- camera (drench render) ---

TEST(SceneLoader, ReadsTheCameraAndDefaultsItsFieldOfView) {
  const SceneConfig config = parse(R"({"camera": {"position": [0, 1, 2], "target": [0, 0, 0.5]}})");
  ASSERT_TRUE(config.camera);
  EXPECT_EQ(*config.camera->position, Vec3(0, 1, 2));
  EXPECT_EQ(*config.camera->target, Vec3(0, 0, 0.5));
  EXPECT_EQ(config.camera->fov_deg, 45.0);
  EXPECT_FALSE(parse("{}").camera);
  // A field of view alone keeps the framing automatic.
  const SceneConfig fov_only = parse(R"({"camera": {"fov_deg": 30}})");
  EXPECT_FALSE(fov_only.camera->position);
  EXPECT_EQ(fov_only.camera->fov_deg, 30.0);
}

TEST(SceneLoader, RejectsAnUnknownCameraKeyNamingThePath) {
  EXPECT_TRUE(scene_error(R"({"camera": {"positon": [0, 1, 2]}})",
                          "camera.positon is not a known key (x.json); known: position, target, fov_deg"));
}

TEST(SceneLoader, RejectsHalfACameraAndAFieldOfViewOutOfRange) {
  EXPECT_TRUE(scene_error(R"({"camera": {"position": [0, 1, 2]}})", "camera.target is missing"));
  EXPECT_TRUE(scene_error(R"({"camera": {"target": [0, 1, 2]}})", "camera.position is missing"));
  EXPECT_TRUE(scene_error(R"({"camera": {"position": [0, 1, 2], "target": [0, 1, 2]}})",
                          "camera.target must be at least 1e-6 m from camera.position"));
  EXPECT_TRUE(
      scene_error(R"({"camera": {"fov_deg": 180}})", "camera.fov_deg must be in [0.1, 179], got 180"));
  // Each drew a blank image.
  EXPECT_TRUE(scene_error(R"({"camera": {"fov_deg": 1e-300}})", "camera.fov_deg must be in [0.1, 179]"));
  EXPECT_TRUE(scene_error(R"({"camera": {"position": [1e300, 0, 0], "target": [0, 0, 0]}})",
                          "camera.position[0] must be in [-10000000, 10000000], got 1e+300"));
  EXPECT_TRUE(scene_error(R"({"camera": {"position": [1e-300, 0, 0], "target": [0, 0, 0]}})",
                          "camera.target must be at least 1e-6 m from camera.position"));
  EXPECT_TRUE(scene_error(R"({"camera": {"position": [0, 1]}})", "camera.position"));
}

TEST(SceneLoader, ParsesACameraGivenApartFromTheScene) {
  const CameraSettings camera = parse_camera(json::parse(R"({"position": [1, 2, 3], "target": [0, 0, 0],
                                                            "fov_deg": 60})"),
                                             "--camera");
  EXPECT_EQ(*camera.position, Vec3(1, 2, 3));
  EXPECT_EQ(camera.fov_deg, 60.0);
  EXPECT_TRUE(
      throws_containing<SceneError>([] { parse_camera(json::parse(R"({"up": [0, 1, 0]})"), "--camera"); },
                                    "camera.up is not a known key (--camera)"));
}

}  // namespace
}  // namespace drench

namespace drench {
namespace {

// A work of adhesion without the "adhesion" effect would be ignored: the loader names it.
TEST(SceneLoader, RejectsAdhesionWithoutTheEffect) {
  EXPECT_TRUE(scene_error(R"({"cloth": {"adhesion": 0.05}})",
                          "cloth.adhesion sets a work of adhesion, but effects does not list \"adhesion\""));
  EXPECT_TRUE(scene_error(R"({"obstacles": [{"mesh": "v_plane", "adhesion": 0.05}]})",
                          "obstacles[0].adhesion sets a work of adhesion"));
}

}  // namespace
}  // namespace drench
