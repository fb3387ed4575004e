// The observables of a run against a reference on hand-made frame sets whose differences are known: a cloth
// shifted by 1 mm, a block of particles moved by one mass-grid cell, a surge front moved by 0.1 m, water on
// and past a flat cloth; and one clear error per way two runs cannot be compared.

#include <drench/compare/run_comparison.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/io/ply_writer.hpp>
#include <drench/scene/run_frames.hpp>
#include <drench/scene/scene_loader.hpp>
#include "../assertions.hpp"
#include "../temp_dir.hpp"

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.005;                                 // m
constexpr Scalar kMass = 1000.0 * kSpacing * kSpacing * kSpacing;  // kg: 0.125 g
// Frames hold float32 coordinates: about 3e-8 m of rounding at 0.5 m, far below every difference tested.
constexpr double kRounding = 1e-6;  // m

/// A frame set in `dir`/`name`: frame n has particles[n] and, when `cloths` is not empty, the cloth at
/// cloths[n] over `triangles`. Frame n is at n / 10 s.
RunFrames write_frames(const test::TempDir& dir, const std::string& name,
                       const std::vector<Vec3Array>& particles, const std::vector<Vec3Array>& cloths = {},
                       const std::vector<Triangle>& triangles = {}) {
  RunFrames run;
  run.dir = (dir.path() / name).string();
  run.particle_mass = kMass;
  run.particle_spacing = kSpacing;
  for (std::size_t n = 0; n < particles.size(); ++n) {
    char file[32];
    std::snprintf(file, sizeof file, "fluid_%04zu.ply", n);
    run.fluid_files.push_back(dir.write(name + "/" + file, points_to_ply("test", particles[n], {})));
    if (!cloths.empty()) {
      std::snprintf(file, sizeof file, "cloth_%04zu.ply", n);
      run.cloth_files.push_back(dir.write(name + "/" + file, mesh_to_ply("test", cloths[n], triangles)));
    }
    run.times.push_back(0.1 * static_cast<double>(n));
  }
  return run;
}

/// An n x n patch of nodes over [-0.1, 0.1]^2 at height y (m), its centre node at y + centre_drop, and its
/// triangles (two per cell).
Vec3Array patch(int n, Scalar y, Scalar centre_drop = 0) {
  Vec3Array nodes;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k)
      nodes.emplace_back(-0.1 + 0.2 * i / (n - 1), y + (i == n / 2 && k == n / 2 ? centre_drop : 0.0),
                         -0.1 + 0.2 * k / (n - 1));
  return nodes;
}
std::vector<Triangle> patch_triangles(int n) {
  std::vector<Triangle> triangles;
  for (Index i = 0; i + 1 < static_cast<Index>(n); ++i) {
    for (Index k = 0; k + 1 < static_cast<Index>(n); ++k) {
      const Index a = i * n + k, b = a + 1, c = a + n, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  }
  return triangles;
}

Vec3Array shifted(Vec3Array points, const Vec3& by) {
  for (Vec3& p : points)
    p += by;
  return points;
}

/// 2 x 2 x 2 particles at spacing 0.01 m from `corner` + 0.005 m: all inside one 2-cm cell when `corner` is
/// a cell's corner.
Vec3Array block(const Vec3& corner) {
  Vec3Array points;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        points.push_back(corner + Vec3(0.005 + 0.01 * i, 0.005 + 0.01 * j, 0.005 + 0.01 * k));
  return points;
}

const ObservableError& observable(const RunComparison& c, const std::string& name) {
  for (const ObservableError& e : c.observables)
    if (e.name == name) return e;
  throw std::runtime_error("no observable " + name);
}

// Every node 1 mm higher in every frame: RMS and largest distance 1 mm, and the centre's sag, measured from
// each run's own frame 0, unchanged. The reference sags 0.1 m, so the relative error is 1%.
TEST(RunComparison, ClothShiftedByOneMillimetreIsOneMillimetreRmsAndLargest) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  const std::vector<Vec3Array> reference_cloth = {patch(5, 0.0), patch(5, 0.0, -0.1)};
  const std::vector<Vec3Array> run_cloth = {shifted(reference_cloth[0], Vec3(0, 0.001, 0)),
                                            shifted(reference_cloth[1], Vec3(0, 0.001, 0))};
  const std::vector<Vec3Array> water = {block(Vec3(0, 0.02, 0)), block(Vec3(0, 0.02, 0))};
  const RunFrames reference = write_frames(dir, "reference", water, reference_cloth, triangles);
  const RunFrames run = write_frames(dir, "run", water, run_cloth, triangles);
  const RunComparison c = compare_runs(run, reference, {});
  EXPECT_EQ(c.frames, 2u);
  EXPECT_NEAR(observable(c, "cloth_rms_m").largest, 0.001, kRounding);
  EXPECT_NEAR(observable(c, "cloth_max_m").largest, 0.001, kRounding);
  EXPECT_NEAR(observable(c, "cloth_sag_m").largest, 0.0, kRounding);
  EXPECT_NEAR(observable(c, "cloth_rms_m").normaliser, 0.1, kRounding) << "the reference's largest sag";
  EXPECT_NEAR(observable(c, "cloth_rms_m").relative, 0.01, 1e-4);
  EXPECT_NEAR(observable(c, "mass_l1_kg").largest, 0.0, 1e-12) << "the same water in both";
  EXPECT_TRUE(c.worst == "cloth_rms_m" || c.worst == "cloth_max_m")
      << c.worst << ": RMS and largest are equal";
  EXPECT_NEAR(c.worst_relative, 0.01, 1e-4);
  EXPECT_NEAR(c.reference_series[0][1], 0.1, kRounding) << "the centre sag over time (m)";
}

// One node alone moved by 3 mm out of 25: the largest distance is 3 mm, the RMS 3 mm / sqrt(25) = 0.6 mm.
TEST(RunComparison, OneNodeMovedGivesItsDistanceAsLargestAndItsShareAsRms) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  const std::vector<Vec3Array> reference_cloth = {patch(5, 0.0), patch(5, 0.0, -0.1)};
  std::vector<Vec3Array> run_cloth = reference_cloth;
  run_cloth[1][3].z() += 0.003;
  const std::vector<Vec3Array> water = {block(Vec3(0, 0.02, 0)), block(Vec3(0, 0.02, 0))};
  const RunComparison c = compare_runs(write_frames(dir, "run", water, run_cloth, triangles),
                                       write_frames(dir, "reference", water, reference_cloth, triangles), {});
  EXPECT_NEAR(observable(c, "cloth_max_m").largest, 0.003, kRounding);
  EXPECT_NEAR(observable(c, "cloth_rms_m").largest, 0.0006, kRounding);
  EXPECT_NEAR(observable(c, "cloth_rms_m").per_frame[0], 0.0, kRounding);
}

// Two blocks of 8 particles, one moved by one 2-cm cell (the default: four 5-mm spacings) in x: its 8
// particles leave one cell and fill another, L1 = 2 x 8 x 0.125 g = 2 g, over 16 particles' 2 g of water:
// relative error 1. Moved by half a cell, half of its particles change cell: 1 g.
TEST(RunComparison, BlockMovedByOneCellGivesTheL1MassDifferenceByHand) {
  const test::TempDir dir;
  const Vec3Array still = block(Vec3(0.1, 0.0, 0.0));
  auto frame = [&](const Vec3& moved_by) {
    Vec3Array points = still;
    for (const Vec3& p : shifted(block(Vec3(0.0, 0.0, 0.0)), moved_by))
      points.push_back(p);
    return points;
  };
  const RunFrames reference = write_frames(dir, "reference", {frame(Vec3::Zero()), frame(Vec3::Zero())});
  const RunComparison whole =
      compare_runs(write_frames(dir, "whole", {frame(Vec3::Zero()), frame(Vec3(0.02, 0, 0))}), reference, {});
  EXPECT_NEAR(observable(whole, "mass_l1_kg").per_frame[0], 0.0, 1e-12);
  EXPECT_NEAR(observable(whole, "mass_l1_kg").largest, 2 * 8 * kMass, 1e-12);
  EXPECT_NEAR(observable(whole, "mass_l1_kg").normaliser, 16 * kMass, 1e-12);
  EXPECT_NEAR(whole.worst_relative, 1.0, 1e-9);
  const RunComparison half =
      compare_runs(write_frames(dir, "half", {frame(Vec3::Zero()), frame(Vec3(0.01, 0, 0))}), reference, {});
  EXPECT_NEAR(observable(half, "mass_l1_kg").largest, 2 * 4 * kMass, 1e-12);
  // With 4-cm cells the half-cell move stays in the cell (x from 0.015 to 0.025, 0.005 to 0.015).
  ComparisonSettings coarse;
  coarse.cell_size = 0.04;
  const RunComparison coarse_half = compare_runs(
      write_frames(dir, "half4", {frame(Vec3::Zero()), frame(Vec3(0.01, 0, 0))}), reference, coarse);
  EXPECT_NEAR(observable(coarse_half, "mass_l1_kg").largest, 0.0, 1e-12);
}

// A dam break's water moved 0.1 m further in x: the front differs by 0.1 m; a gauge at x = 0.4475 sees the
// run's sheet (one particle) and a particle above it where the reference's column is empty: two particles'
// volume over the column's one-spacing square cross-section, 2 x 5 mm of water.
TEST(RunComparison, SurgeFrontMovedByATenthOfAMetreIsATenthOfAMetre) {
  const test::TempDir dir;
  Vec3Array start, surge;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      start.emplace_back(0.0025 + 0.005 * i, 0.0025 + 0.005 * j, 0.0);  // a 0.1 m column
  for (int i = 0; i < 80; ++i)
    surge.emplace_back(0.0025 + 0.005 * i, 0.0025, 0.0);  // a 0.4 m sheet one particle deep
  const RunFrames reference = write_frames(dir, "reference", {start, surge});
  Vec3Array further = shifted(surge, Vec3(0.1, 0, 0));
  further.emplace_back(0.4475, 0.1025, 0.0);  // one particle 0.1 m above the sheet at the gauge
  ComparisonSettings settings;
  settings.gauges_x = {0.4475};
  const RunComparison c = compare_runs(write_frames(dir, "run", {start, further}), reference, settings);
  EXPECT_NEAR(observable(c, "front_m").largest, 0.1, kRounding);
  EXPECT_NEAR(observable(c, "front_m").normaliser, 0.3, kRounding) << "the reference's front travels 0.3 m";
  EXPECT_NEAR(observable(c, "gauge_height_m").largest, 2 * kSpacing, kRounding)
      << "the reference's column at x = 0.4475 is empty (height 0); the run's holds two particles, each "
         "spacing^3 of water over a spacing x spacing cross-section (the reference's water is one particle "
         "deep in z)";
  EXPECT_TRUE(std::none_of(c.observables.begin(), c.observables.end(), [](const ObservableError& e) {
    return e.name == "cloth_rms_m";
  })) << "no cloth, no cloth observables";
}

// A gauge's height is the water's volume in its column over the cross-section: a column 2 cm wide, 2 cm deep
// and 10 cm high of 5-mm particles reads 10 cm; a droplet thrown 1 m above it adds one particle's volume,
// 0.125 cm^3 over 4 cm^2, 0.3 mm, where the highest particle would read 1 m more.
TEST(RunComparison, ALoneDropletAboveAGaugeBarelyChangesItsHeight) {
  const test::TempDir dir;
  Vec3Array column;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 4; ++k)
        column.emplace_back(0.0025 + 0.005 * i, 0.0025 + 0.005 * j, 0.0025 + 0.005 * k);
  Vec3Array splashed = column;
  splashed.emplace_back(0.0075, 1.1, 0.0075);
  ComparisonSettings settings;
  settings.gauges_x = {0.01};
  settings.gauge_width = 0.02;
  const RunFrames reference = write_frames(dir, "reference", {column, column});
  const RunComparison still = compare_runs(reference, reference, settings);
  EXPECT_NEAR(observable(still, "gauge_height_m").normaliser, 0.1, 1e-9)
      << "the reference's largest gauge height: its 10-cm column, the depth its frame 0's 2 cm";
  const RunComparison splash =
      compare_runs(write_frames(dir, "splash", {column, splashed}), reference, settings);
  const double droplet = kSpacing * kSpacing * kSpacing / (0.02 * 0.02);  // m: 0.3125 mm
  EXPECT_NEAR(observable(splash, "gauge_height_m").largest, droplet, 1e-9);
  EXPECT_LT(observable(splash, "gauge_height_m").relative, 0.005) << "under half a percent of the column";
}

// On a flat cloth over [-0.1, 0.1]^2 at y = 0: 8 particles 1-2 cm above it are held; 8 at 5 cm are above
// the 2-cm band; 8 beside the cloth are not over it; 8 below its lowest node are past its edges.
TEST(RunComparison, WaterHeldAndPastTheEdgesAreCountedByTheirDefinitions) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  Vec3Array water = block(Vec3(-0.01, 0.0, -0.01));
  for (const Vec3Array& more :
       {block(Vec3(-0.05, 0.04, -0.05)), block(Vec3(0.2, 0.0, 0.0)), block(Vec3(0.0, -0.3, 0.0))})
    water.insert(water.end(), more.begin(), more.end());
  const std::vector<Vec3Array> cloth = {patch(5, 0.0), patch(5, 0.0)};
  const RunFrames reference = write_frames(dir, "reference", {water, water}, cloth, triangles);
  const RunComparison c = compare_runs(reference, reference, {});
  const auto index = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(c.series_names.begin(), c.series_names.end(), name) -
                                    c.series_names.begin());
  };
  EXPECT_NEAR(c.reference_series[index("held_kg")][1], 8 * kMass, 1e-12);
  EXPECT_NEAR(c.reference_series[index("past_edges_kg")][1], 8 * kMass, 1e-12);
  EXPECT_NEAR(c.reference_series[index("fluid_kg")][1], 32 * kMass, 1e-12);
  EXPECT_NEAR(c.worst_relative, 0.0, 1e-12) << "a run against itself";
}

// Water a kill region removed is in no frame, yet it left the scene: 8 particles killed in the run where the
// reference holds them on the cloth are 8 particles' more water past the edges, and in the mass grid they
// left a cell for the "killed" one (L1 = 2 x 8 particles). Killed in both runs, they are no difference.
TEST(RunComparison, WaterKilledCountsAsPastTheEdgesAndInTheMassDifference) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  const std::vector<Vec3Array> cloth = {patch(5, 0.0), patch(5, 0.0)};
  const Vec3Array held = block(Vec3(-0.01, 0.0, -0.01));
  const Vec3Array other = block(Vec3(0.04, 0.0, 0.04));
  Vec3Array both = held;
  both.insert(both.end(), other.begin(), other.end());
  RunFrames reference = write_frames(dir, "reference", {both, both}, cloth, triangles);
  reference.killed_kg = {0.0, 0.0};
  RunFrames run = write_frames(dir, "run", {both, other}, cloth, triangles);
  run.killed_kg = {0.0, 8 * kMass};
  const RunComparison c = compare_runs(run, reference, {});
  EXPECT_NEAR(observable(c, "past_edges_kg").largest, 8 * kMass, 1e-12);
  EXPECT_NEAR(observable(c, "held_kg").largest, 8 * kMass, 1e-12);
  EXPECT_NEAR(observable(c, "mass_l1_kg").largest, 2 * 8 * kMass, 1e-12);
  EXPECT_NEAR(observable(c, "mass_l1_kg").normaliser, 16 * kMass, 1e-12) << "the water in the reference";
  const auto killed = static_cast<std::size_t>(
      std::find(c.series_names.begin(), c.series_names.end(), "killed_kg") - c.series_names.begin());
  ASSERT_LT(killed, c.series_names.size());
  EXPECT_NEAR(c.run_series[killed][1], 8 * kMass, 1e-12);

  // The same 8 killed in the reference as well: nothing differs, and the reference's water is the frame's
  // plus the killed.
  RunFrames killed_too = write_frames(dir, "killed_too", {both, other}, cloth, triangles);
  killed_too.killed_kg = {0.0, 8 * kMass};
  const RunComparison same = compare_runs(run, killed_too, {});
  EXPECT_NEAR(same.worst_relative, 0.0, 1e-12);
  EXPECT_NEAR(observable(same, "mass_l1_kg").normaliser, 16 * kMass, 1e-12);

  run.killed_kg = {0.0};
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(run, reference, {}); },
                                               {run.dir, "killed water", "1 frames", "has 2"}));
}

// A run that stopped after two of three frames is measured against the whole reference's sag (0.1 m in its
// last frame), not the 1 cm of the frames it has: a short run's error is not inflated into a large one.
TEST(RunComparison, AShortRunIsNormalisedByTheWholeReference) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  const std::vector<Vec3Array> reference_cloth = {patch(5, 0.0), patch(5, 0.0, -0.01), patch(5, 0.0, -0.1)};
  const std::vector<Vec3Array> run_cloth = {shifted(reference_cloth[0], Vec3(0.001, 0, 0)),
                                            shifted(reference_cloth[1], Vec3(0.001, 0, 0))};
  const Vec3Array water = block(Vec3(0, 0.02, 0));
  ComparisonSettings allow;
  allow.allow_shorter = true;
  const RunComparison c =
      compare_runs(write_frames(dir, "run", {water, water}, run_cloth, triangles),
                   write_frames(dir, "reference", {water, water, water}, reference_cloth, triangles), allow);
  EXPECT_EQ(c.frames, 2u);
  EXPECT_NEAR(observable(c, "cloth_rms_m").normaliser, 0.1, kRounding);
  EXPECT_NEAR(observable(c, "cloth_rms_m").relative, 0.01, 1e-4);
  EXPECT_EQ(c.reference_series[0].size(), 3u) << "the reference's sag over all its frames";
}

TEST(RunComparison, RunsThatCannotBeComparedAreErrorsNamingTheFile) {
  const test::TempDir dir;
  const std::vector<Triangle> triangles = patch_triangles(5);
  const Vec3Array water = block(Vec3::Zero());
  const RunFrames reference =
      write_frames(dir, "reference", {water, water}, {patch(5, 0), patch(5, 0)}, triangles);
  const RunFrames shorter = write_frames(dir, "shorter", {water}, {patch(5, 0)}, triangles);
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(shorter, reference, {}); },
                                               {shorter.dir, "1 frames", reference.dir, "has 2"}));
  ComparisonSettings allow;
  allow.allow_shorter = true;
  EXPECT_EQ(compare_runs(shorter, reference, allow).frames, 1u) << "a run that stopped: its frames only";
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(reference, shorter, allow); },
                                               {"2 frames", "has 1"}))
      << "a run longer than its reference is never allowed";

  RunFrames late = write_frames(dir, "late", {water, water}, {patch(5, 0), patch(5, 0)}, triangles);
  late.times[1] = 0.1004;
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(late, reference, {}); },
                                               {late.fluid_files[1], "0.1004", "time.frame_rate"}));

  const RunFrames finer =
      write_frames(dir, "finer", {water, water}, {patch(6, 0), patch(6, 0)}, patch_triangles(6));
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(finer, reference, {}); },
                                               {finer.cloth_files[0], "36 cloth nodes", "25"}));
  const RunFrames dry = write_frames(dir, "dry", {water, water});
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(dry, reference, {}); },
                                               {dry.dir, "no cloth frames"}));
  RunFrames missing = write_frames(dir, "missing", {water, water}, {patch(5, 0), patch(5, 0)}, triangles);
  std::filesystem::remove(missing.fluid_files[1]);
  EXPECT_TRUE(test::throws_containing<IoError>([&] { compare_runs(missing, reference, {}); },
                                               {missing.fluid_files[1]}));
  ComparisonSettings bad;
  bad.cell_size = -0.02;
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { compare_runs(reference, reference, bad); },
                                                  {"cell_size", "must be 0", "-0.02"}));
  // A cell below the particle spacing holds at most one particle; 1e300 m is one cell for any scene.
  for (const double cell : {1e-12, 1e300}) {
    bad.cell_size = cell;
    EXPECT_TRUE(test::throws_containing<SceneError>([&] { check_comparison_settings(bad, reference); },
                                                    {"cell_size (drench sweep --cell-size)", "got"}));
  }
  bad = ComparisonSettings();
  bad.gauges_x = {0.5, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { check_comparison_settings(bad, reference); },
                                                  {"gauge x (drench sweep --gauge)", "got nan"}));
  bad.gauges_x = {1e300};
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { check_comparison_settings(bad, reference); },
                                                  {"--gauge", "got 1e+300"}));
}

// A run folder as drench run writes it: scene.json and frames/; its frames' times follow the steps.
TEST(RunFrames, ReadsARunFolderAndNamesTheFirstMissingFrame) {
  const test::TempDir dir;
  dir.write("run/scene.json", R"({"fluid": {"particle_spacing": 0.005, "rest_density": 1000},
      "emitters": [{"type": "box", "min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}],
      "time": {"dt": 0.004, "duration": 0.1, "frame_rate": 60}})");
  const Vec3Array water = block(Vec3::Zero());
  for (const char* name : {"fluid_0000.ply", "fluid_0001.ply", "fluid_0002.ply"})
    dir.write(std::string("run/frames/") + name, points_to_ply("test", water, {}));
  const RunFrames run = read_run_frames((dir.path() / "run").string());
  ASSERT_EQ(run.fluid_files.size(), 3u);
  EXPECT_TRUE(run.cloth_files.empty());
  EXPECT_NEAR(run.particle_mass, kMass, 1e-15);
  // 1/60 s = 4.17 steps of 4 ms: frame 1 is written after step 5, at 20 ms; frame 2 (33.3 ms) at 36 ms.
  EXPECT_NEAR(run.times[1], 0.020, 1e-12);
  EXPECT_NEAR(run.times[2], 0.036, 1e-12);
  std::filesystem::remove(dir.path() / "run/frames/fluid_0001.ply");
  EXPECT_TRUE(test::throws_containing<IoError>([&] { read_run_frames((dir.path() / "run").string()); },
                                               {"fluid_0001.ply", "missing"}));
  EXPECT_TRUE(test::throws_containing<IoError>([&] { read_run_frames((dir.path() / "nothing").string()); },
                                               {"scene.json", "missing"}));
}

// With kill regions the water they removed by each frame comes from summary.json; without it the comparison
// cannot count that water, and says which file lacks it.
TEST(RunFrames, ReadsTheKilledWaterOfAKillRegionScene) {
  const test::TempDir dir;
  dir.write("run/scene.json", R"({"fluid": {"particle_spacing": 0.005, "rest_density": 1000},
      "emitters": [{"type": "box", "min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}],
      "kill_regions": [{"type": "plane", "point": [0, -0.5, 0], "normal": [0, 1, 0]}],
      "time": {"dt": 0.004, "duration": 0.1, "frame_rate": 50}})");
  const Vec3Array water = block(Vec3::Zero());
  for (const char* name : {"fluid_0000.ply", "fluid_0001.ply"})
    dir.write(std::string("run/frames/") + name, points_to_ply("test", water, {}));
  const std::string folder = (dir.path() / "run").string();
  EXPECT_TRUE(test::throws_containing<IoError>([&] { read_run_frames(folder); }, {"summary.json"}));
  dir.write("run/summary.json", R"({"status": "ok"})");
  EXPECT_TRUE(test::throws_containing<IoError>([&] { read_run_frames(folder); },
                                               {"summary.json", "killed_kg_by_frame", "missing"}));
  dir.write("run/summary.json", R"({"killed_kg_by_frame": [0.0, 0.001]})");
  const RunFrames run = read_run_frames(folder);
  ASSERT_EQ(run.killed_kg.size(), 2u);
  EXPECT_DOUBLE_EQ(run.killed_kg[1], 0.001);
}

// The reference's settings: dt / 8, eta / 10, the cloth's sub-steps x 4, the iterations in double; a key the
// scene does not write is added with its parent object, and a second key of that object keeps the first.
TEST(ReferenceOverrides, RefineTheSceneEffectiveValuesAndKeepTheRest) {
  const nlohmann::json scene = nlohmann::json::parse(R"({"fluid": {"particle_spacing": 0.005},
      "emitters": [{"type": "box", "min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}],
      "cloth": {"mesh": "patch", "substeps": 3},
      "time": {"dt": 0.004, "duration": 0.1, "frame_rate": 50}})");
  const std::vector<std::string> overrides = reference_overrides(scene, {});
  nlohmann::json document = scene;
  for (const std::string& assignment : overrides)
    apply_override(document, assignment);
  EXPECT_DOUBLE_EQ(document["time"]["dt"].get<double>(), 0.0005);
  EXPECT_DOUBLE_EQ(document["fluid"]["pcisph"]["eta"].get<double>(), 0.0001) << "the default 0.001 / 10";
  EXPECT_EQ(document["fluid"]["pcisph"]["precision"], "double");
  EXPECT_EQ(document["fluid"]["pbf"]["precision"], "double");
  EXPECT_DOUBLE_EQ(document["fluid"]["dfsph"]["eta"].get<double>(), 0.00005);
  EXPECT_EQ(document["cloth"]["substeps"], 12);
  EXPECT_DOUBLE_EQ(document["fluid"]["particle_spacing"].get<double>(), 0.005);
  ReferenceRefinement bad;
  bad.cloth_substeps_factor = 1.5;
  EXPECT_TRUE(
      test::throws_containing<SceneError>([&] { reference_overrides(scene, bad); }, {"whole number", "1.5"}));
}

}  // namespace
}  // namespace drench
