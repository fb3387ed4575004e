// `drench reconstruct` (scene/reconstruct_run.hpp) on the output of a short run: the same surface files as
// the run's own `surface` effect, byte for byte; a plain reconstruction that crosses the obstacle where the
// contact-aware one does not; and bad input that is named and writes nothing.

#include <drench/scene/reconstruct_run.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>

#include <drench/common/error.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_runner.hpp>
#include <drench/scene/simulation.hpp>
#include "../temp_dir.hpp"

namespace drench {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::TempDir;

/// A block of 8 x 4 x 6 particles (1 cm) dropped into a static V (Fig. 8's obstacle), coupled so that it
/// stays out of it: by the last frames the fluid lies in the V, where a plain reconstruction crosses it.
/// 25 steps of 4 ms, a frame every 20 ms.
json drop_into_v(bool surface_effect) {
  json scene = json::parse(R"({
    "fluid": {"particle_spacing": 0.01},
    "emitters": [{"type": "box", "min": [-0.04, 0.05, -0.03], "max": [0.04, 0.09, 0.03]}],
    "obstacles": [{"mesh": "v_plane", "angle_deg": 90, "size": 0.1, "width": 0.1, "triangle_size": 0.01}],
    "coupling": {"cloth_thickness": 0.001},
    "time": {"dt": 0.004, "duration": 0.1, "frame_rate": 50},
    "effects": ["coupling"]
  })");
  if (surface_effect) {
    scene["effects"].push_back("surface");
    scene["surface"] = {{"cell_size", 0.004}};
  }
  return scene;
}

/// Simulates `scene` as `drench run` would, writing into `dir`; returns the summary.
json run(const json& scene, const fs::path& dir) {
  Simulation simulation(parse_scene(scene, "test scene"));
  RunOptions options;
  options.out_dir = dir.string();
  options.progress = false;
  options.scene_document = scene;
  return run_scene(simulation, options).summary;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Every file under `dir` (relative name -> contents).
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files[fs::relative(entry.path(), dir).string()] = read_file(entry.path());
  }
  return files;
}

/// The surface files of a run folder, moved out of it (name -> contents), so that what reconstruct writes
/// cannot be mistaken for what the run left.
std::map<std::string, std::string> take_surfaces(const fs::path& dir) {
  std::map<std::string, std::string> surfaces;
  for (const auto& entry : fs::directory_iterator(dir / "frames")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("surface_", 0) != 0) continue;
    surfaces[name] = read_file(entry.path());
    fs::remove(entry.path());
  }
  return surfaces;
}

ReconstructResult reconstruct(const fs::path& dir, const std::vector<std::string>& overrides = {}) {
  ReconstructOptions options;
  options.run_dir = dir.string();
  options.overrides = overrides;
  options.progress = false;
  return reconstruct_run(options);
}

/// Passes when reconstructing `dir` throws an `Exception` whose message contains `expected` and the folder
/// is left exactly as it was.
template <class Exception>
testing::AssertionResult fails_writing_nothing(const fs::path& dir, const std::vector<std::string>& overrides,
                                               const std::string& expected) {
  const auto before = snapshot(dir);
  try {
    reconstruct(dir, overrides);
    return testing::AssertionFailure() << "did not throw";
  } catch (const Exception& e) {
    const std::string message = e.what();
    if (message.find(expected) == std::string::npos)
      return testing::AssertionFailure()
             << "message \"" << message << "\" does not contain \"" << expected << "\"";
  } catch (const std::exception& e) {
    return testing::AssertionFailure() << "threw another exception type: " << e.what();
  }
  const auto after = snapshot(dir);
  if (after != before) {
    std::string changed;
    for (const auto& [name, bytes] : after) {
      const auto it = before.find(name);
      if (it == before.end() || it->second != bytes) changed += " " + name;
    }
    return testing::AssertionFailure() << "the folder changed:" << changed;
  }
  return testing::AssertionSuccess();
}

TEST(ReconstructRun, GivesTheRunsSurfaceFilesByteForByte) {
  const TempDir dir;
  const json scene = drop_into_v(true);
  const json summary = run(scene, dir.path());
  EXPECT_EQ(json::parse(read_file(dir.path() / "scene.json")), scene);
  const auto from_run = take_surfaces(dir.path());
  ASSERT_EQ(from_run.size(), 6u);  // frames 0 to 5
  ASSERT_GT(from_run.at("surface_0005.ply").size(), 1000u) << "the last frame has no surface to compare";

  const ReconstructResult result = reconstruct(dir.path());
  EXPECT_EQ(result.frames, 6);
  for (const auto& [name, bytes] : from_run) {
    ASSERT_TRUE(fs::exists(dir.path() / "frames" / name)) << name;
    EXPECT_TRUE(read_file(dir.path() / "frames" / name) == bytes) << name << " differs from the run's";
  }
  EXPECT_EQ(result.surface_intersections, summary["surface_intersections"].get<std::uint64_t>());
  const json report = json::parse(read_file(dir.path() / "reconstruct.json"));
  EXPECT_EQ(report["frames"], 6);
  EXPECT_EQ(report["surface_intersections"], result.surface_intersections);
  EXPECT_EQ(report["cell_size"], 0.004);
  EXPECT_EQ(report["contact_aware"], true);
  EXPECT_TRUE(report["timings_s"].contains("surface"));
  EXPECT_TRUE(report["timings_s"].contains("surface_audit"));
}

TEST(ReconstructRun, APlainSurfaceCrossesTheObstacleWhereTheContactAwareOneDoesNot) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());  // no surface effect: reconstruct adds it to accept surface.*
  const ReconstructResult plain = reconstruct(dir.path(), {"surface.contact_aware=false"});
  EXPECT_EQ(json::parse(read_file(dir.path() / "reconstruct.json"))["contact_aware"], false);
  const ReconstructResult aware = reconstruct(dir.path(), {"surface.cell_size=0.004"});
  EXPECT_GT(plain.surface_intersections, 0u);
  EXPECT_EQ(aware.surface_intersections, 0u);
  EXPECT_EQ(aware.frames, 6);
  EXPECT_GT(aware.surface_triangles, 0u);
}

TEST(ReconstructRun, AMissingSceneIsNamedAndNothingIsWritten) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  fs::remove(dir.path() / "scene.json");
  EXPECT_TRUE(
      fails_writing_nothing<IoError>(dir.path(), {}, (dir.path() / "scene.json").string() + ": missing"));
}

TEST(ReconstructRun, MissingFramesAreNamedAndNothingIsWritten) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  for (const auto& entry : fs::directory_iterator(dir.path() / "frames"))
    fs::remove(entry.path());
  EXPECT_TRUE(fails_writing_nothing<IoError>(dir.path(), {}, "frames: no fluid_NNNN.ply frames"));
  fs::remove(dir.path() / "frames");
  EXPECT_TRUE(fails_writing_nothing<IoError>(dir.path(), {}, (dir.path() / "frames").string() + ": missing"));
}

TEST(ReconstructRun, AMalformedFrameIsNamedAndNothingIsWritten) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  // The last frame truncated: every earlier one is fine, and still nothing may be written.
  const fs::path last = dir.path() / "frames" / "fluid_0005.ply";
  const std::string bytes = read_file(last);
  std::ofstream(last, std::ios::binary) << bytes.substr(0, bytes.size() - 7);
  EXPECT_TRUE(fails_writing_nothing<IoError>(dir.path(), {}, last.string() + ": truncated"));
}

TEST(ReconstructRun, MalformedObstaclesAreNamedAndNothingIsWritten) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  std::ofstream(dir.path() / "obstacles.ply", std::ios::binary) << "ply\nformat ascii 1.0\nend_header\n";
  EXPECT_TRUE(fails_writing_nothing<IoError>(dir.path(), {},
                                             (dir.path() / "obstacles.ply").string() + ": header line 2"));
}

TEST(ReconstructRun, AMissingClothFrameIsNamedWhenOthersExist) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  fs::copy_file(dir.path() / "obstacles.ply", dir.path() / "frames" / "cloth_0000.ply");
  EXPECT_TRUE(fails_writing_nothing<IoError>(
      dir.path(), {}, (dir.path() / "frames" / "cloth_0001.ply").string() + ": missing"));
}

TEST(ReconstructRun, ABadOverrideIsNamedAndNothingIsWritten) {
  const TempDir dir;
  run(drop_into_v(false), dir.path());
  EXPECT_TRUE(fails_writing_nothing<SceneError>(dir.path(), {"surface.cell_size=-1"},
                                                "surface.cell_size must be > 0"));
  EXPECT_TRUE(
      fails_writing_nothing<SceneError>(dir.path(), {"surface.cell=1"}, "surface.cell is not a known key"));
}

}  // namespace
}  // namespace drench
