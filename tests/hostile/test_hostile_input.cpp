// Hostile input and hard cases (issue 39): input. Each test gives drench what a careful user gave it (a
// scene nested 100,000 deep, /dev/zero, an OBJ index past 2^32, a spacing of 1e-308, a cloth of 4096 x 4096
// nodes, ...) and asserts the refusal: its message names the key, path or file, and it comes before
// anything is allocated or written (the output folder stays absent, the command returns at once).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include <drench/ccd/ccd_query_file.hpp>
#include <drench/common/error.hpp>
#include <drench/io/obj_reader.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_resources.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/surface/surface_reconstruction.hpp>
#include "../assertions.hpp"
#include "../drench_command.hpp"
#include "../temp_dir.hpp"

namespace drench {
namespace {

using drench::test::read_text;

using drench::test::throws_containing;

namespace fs = std::filesystem;

/// Exit status and output (stdout and stderr together) of one `drench` command, and its wall time (s).
struct Command {
  int status = -1;
  std::string output;
  double seconds = 0.0;
};

/// Runs `drench ARGUMENTS` in `folder` (the working directory), as a user does.
Command drench_command(const std::string& arguments, const fs::path& log, const fs::path& folder = ".") {
  const std::string command = "cd '" + folder.string() + "' && " + std::string(DRENCH_EXECUTABLE) + " " +
                              arguments + " > '" + log.string() + "' 2>&1";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  Command result;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = read_text(log);
  return result;
}

std::string demo(const std::string& name) {
  return std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/" + name;
}

testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return testing::AssertionSuccess();
  return testing::AssertionFailure() << "\"" << text << "\" does not contain \"" << part << "\"";
}

/// `drench run` of the jet on a cloth with `--set assignment`: refused at once (exit 1 within 5 s), its
/// message containing `expected`, and nothing written.
void expect_jet_refused_at_once(const std::string& assignment, const std::string& expected) {
  const test::TempDir dir;
  const Command c = drench_command("run " + demo("jet_on_cloth.json") + " --steps 1 --out " +
                                       (dir.path() / "out").string() + " --set " + assignment,
                                   dir.path() / "log");
  EXPECT_EQ(c.status, 1) << assignment << ": " << c.output;
  EXPECT_TRUE(contains(c.output, expected)) << c.output;
  EXPECT_LT(c.seconds, 5.0) << assignment;
  EXPECT_FALSE(fs::exists(dir.path() / "out")) << assignment;
}

SceneConfig parse(const std::string& text) {
  return parse_scene(nlohmann::json::parse(text), "x.json");
}

// 1. JSON: nesting, duplicate keys, the file itself, and --set values held to the same.

TEST(HostileInput, SceneNestedDeeperThan64LevelsIsRefusedNamingTheFile) {
  const test::TempDir dir;
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  const std::string file = dir.write("deep.json", deep);
  const Command c =
      drench_command("run " + file + " --out " + (dir.path() / "out").string(), dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(contains(c.output, file + ": JSON nested deeper than 64 levels")) << c.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  // 64 levels are fine as JSON (the scene is then refused for its content, not its depth).
  const std::string ok = dir.write("ok.json", "{\"a\": " + std::string(63, '[') + std::string(63, ']') + "}");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(ok); }, {"a is not a known key"}));
}

TEST(HostileInput, DuplicateKeyIsRefusedNamingItsJsonPathAndFile) {
  const test::TempDir dir;
  const std::string file = dir.write(
      "dup.json", R"({"time": {"dt": 0.001, "duration": 1}, "emitters": [{"type": "box"}, {"type": "box",
      "min": [0, 0, 0], "min": [1, 1, 1]}]})");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file); },
                                            {file + ": duplicate key \"min\" at emitters[1].min"}));
  const std::string top = dir.write("top.json", R"({"time": {"dt": 0.001}, "time": {"dt": 0.002}})");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(top); },
                                            {top + ": duplicate key \"time\" at time"}));
}

TEST(HostileInput, SceneFileMustBeARegularFileOfAtMost16MiB) {
  const test::TempDir dir;
  EXPECT_TRUE(throws_containing<IoError>(
      [&] { load_scene_file("/dev/zero"); },
      {"/dev/zero: cannot read scene file: not a regular file (a FIFO, device or socket)"}));
  EXPECT_TRUE(throws_containing<IoError>([&] { load_scene_file(dir.path().string()); },
                                         {": cannot read scene file: it is a folder"}));
  const std::string fifo = (dir.path() / "fifo.json").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_TRUE(throws_containing<IoError>([&] { load_scene_file(fifo); },
                                         {fifo + ": cannot read scene file: not a regular file"}));
  const std::string large = (dir.path() / "large.json").string();
  { std::ofstream(large) << "{}"; }
  fs::resize_file(large, kMaxSceneFileBytes + 1);  // sparse: no 16 MiB written
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { load_scene_file(large); },
      {large + ": cannot read scene file: 16777217 bytes, more than the 16 MiB"}));
  // The command returns at once on /dev/zero (it read forever) and writes nothing.
  const Command c =
      drench_command("run /dev/zero --out " + (dir.path() / "out").string(), dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_LT(c.seconds, 5.0);
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

TEST(HostileInput, CcdQueryFilesAndObjMeshesMustBeRegularFiles) {
  const test::TempDir dir;
  const std::string fifo = (dir.path() / "fifo.vf.txt").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // /dev/zero was read without end (3.5 GB in 5 s) and a FIFO blocked: both are refused before opening.
  for (const std::string& path : {std::string("/dev/zero"), fifo}) {
    const Command c = drench_command("ccd " + path, dir.path() / "log");
    EXPECT_EQ(c.status, 1) << c.output;
    EXPECT_LT(c.seconds, 5.0);
    EXPECT_TRUE(contains(c.output, path + ": cannot read CCD query file: not a regular file")) << c.output;
    EXPECT_TRUE(throws_containing<SceneError>([&] { load_obj_mesh(path, "obstacles[0].mesh"); },
                                              {"obstacles[0].mesh", path, "not a regular file"}));
  }
  const std::string large = (dir.path() / "large.vf.txt").string();
  { std::ofstream(large) << "#"; }
  fs::resize_file(large, ccd::kMaxCcdQueryFileBytes + 1);  // sparse: nothing written
  const Command c = drench_command("ccd " + large, dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(
      contains(c.output, large + ": cannot read CCD query file: 1073741825 bytes, more than the 1 GiB"))
      << c.output;
}

TEST(HostileInput, SetValuesAreHeldToTheSameJsonLimits) {
  const test::TempDir dir;
  const std::string file = dir.write("scene.json", "{}");
  const std::string deep = "fluid=" + std::string(100, '[') + std::string(100, ']');
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file, {deep}); },
                                            {"--set fluid=[[[", "JSON nested deeper than 64 levels"}));
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_scene_file(file, {R"(time={"dt": 1, "dt": 2})"}); },
                                            {"duplicate key \"dt\" at time.dt"}));
}

// 2. Paths: relative to the scene file's folder, wherever drench runs, and the same in the run's copy.

TEST(HostileInput, RelativeObjPathIsTheSceneFoldersInRunAndInTheRunsCopy) {
  const test::TempDir dir;
  dir.write("scenes/rock.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
  const std::string scene = dir.write("scenes/scene.json",
                                      R"({"obstacles": [{"mesh": "rock.obj"}], "effects": ["coupling"],
          "time": {"dt": 0.01, "duration": 0.02, "frame_rate": 0}})");
  fs::create_directories(dir.path() / "elsewhere");
  const fs::path out = dir.path() / "out";
  const Command c = drench_command("run " + scene + " --out " + out.string() + " --quiet", dir.path() / "log",
                                   dir.path() / "elsewhere");
  ASSERT_EQ(c.status, 0) << c.output;
  // The run's scene.json names the file absolutely: it means the same wherever it is copied and read.
  const nlohmann::json saved = nlohmann::json::parse(read_text(out / "scene.json"));
  EXPECT_EQ(saved["obstacles"][0]["mesh"], (dir.path() / "scenes" / "rock.obj").string());
  const Command again = drench_command(
      "run " + (out / "scene.json").string() + " --out " + (dir.path() / "out2").string() + " --quiet",
      dir.path() / "log2", dir.path() / "elsewhere");
  EXPECT_EQ(again.status, 0) << again.output;
  // A path given with --set is the working directory's, as any path on a command line.
  const nlohmann::json overridden = read_scene_document(scene, {"obstacles[0].mesh=other.obj"});
  EXPECT_EQ(overridden["obstacles"][0]["mesh"],
            (fs::current_path() / "other.obj").lexically_normal().string());
}

// 3. OBJ indices: overflow and range, named with the file, the line and the index.

TEST(HostileInput, ObjIndexBeyond32BitsIsRefusedNamingFileLineAndIndex) {
  const test::TempDir dir;
  const std::string wrapped = dir.write("wrapped.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 4294967299\n");
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { load_obj_mesh(wrapped, "obstacles[0].mesh"); },
      {"obstacles[0].mesh: OBJ file \"" + wrapped + "\" line 4: vertex index 4294967299 out of range"}));
  const std::string negative = dir.write("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf -4294967297 2 3\n");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_obj_mesh(negative); },
                                            {"line 4: vertex index -4294967297 out of range"}));
  const std::string behind = dir.write("behind.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 0 1\n");
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { load_obj_mesh(behind); }, {"line 3: vertex index -3 out of range: only 2 vertices precede it"}));
  const std::string past = dir.write("past.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\nf 1 2 7\n");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_obj_mesh(past); },
                                            {"line 5: vertex index 7 out of range 1..3"}));
  EXPECT_TRUE(
      throws_containing<SceneError>([&] { load_obj_mesh("/dev/zero", "obstacles[0].mesh"); },
                                    {"obstacles[0].mesh: OBJ file \"/dev/zero\" cannot be read: not a "
                                     "regular file"}));
  const std::string texture = dir.write("texture.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1/99999999999 2 3\n");
  EXPECT_TRUE(throws_containing<SceneError>([&] { load_obj_mesh(texture); },
                                            {"line 4: texture index 99999999999 out of range"}));
}

// 4. Derived quantities: a mass that underflows or overflows is refused naming the key it comes from.

TEST(HostileInput, MassThatUnderflowsIsRefusedNamingTheKeyAndTheDerivedMass) {
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"cloth": {"area_density": 1e-308}})"); },
      {"cloth.area_density gives a cloth node of ", "kg and inverse mass inf", "got 1e-308 (x.json)"}));
  // The largest patch (1e7 m a side) at an area density that makes its nodes too heavy.
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"cloth": {"size": [1e7, 1e7], "nodes": [2, 2], "area_density": 1e140}})"); },
      {"gives a cloth node of ", "(x.json)"}));
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"fluid": {"rest_density": 1e-300}, "emitters": [{"type": "box"}]})"); },
      {"fluid.rest_density gives particles of ", "(fluid.rest_density x fluid.particle_spacing^3)"}));
  // The demo's cloth and fluid are far inside the range.
  EXPECT_NO_THROW(load_scene_file(demo("jet_on_cloth.json")));
}

// 5. Emitters that would lay nothing, or whose loop could not progress, are refused before they start.

TEST(HostileInput, EmitterThatWouldEmitNothingIsRefusedNamingTheKey) {
  const std::string nozzle = R"("emitters": [{"type": "nozzle", "center": [0, 0.3, 0]}])";
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { parse(R"({"fluid": {"particle_spacing": 1e-12}, )" + nozzle + "}"); },
      {"fluid.particle_spacing is too fine for emitters[0] at coordinates up to 0.32 m", "got 1e-12"}));
  EXPECT_TRUE(
      throws_containing<SceneError>([&] { parse(R"({"emitters": [{"type": "nozzle", "radius": 1e7}]})"); },
                                    {"emitters[0].radius gives a nozzle disc", "got 10000000"}));
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] {
        parse(
            R"({"fluid": {"particle_spacing": 1e-12}, "emitters": [{"type": "box", "max": [0.1, 0.1, 0.1]}]})");
      },
      {"fluid.particle_spacing is too fine for emitters[0]"}));
  // 1e-308 hung in the nozzle's emit loop: refused in the loader, before the loop.
  expect_jet_refused_at_once("fluid.particle_spacing=1e-308", "fluid.particle_spacing");
  // A layer period below what double resolves over the run's times: the loop could not advance.
  EXPECT_TRUE(throws_containing<SceneError>(
      [] {
        parse(R"({"fluid": {"max_speed": null}, "emitters": [{"type": "nozzle", "speed": 1e300}],
                  "time": {"duration": 1}})");
      },
      {"emitters[0].speed makes emitters[0] release a layer every", "could not progress"}));
}

// 6. Resources, estimated from the scene and refused before any allocation or output.

TEST(HostileInput, StepAndFrameCountsThatOverflowAreRefusedNamingTheKey) {
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"time": {"duration": 1e308}})"); },
      {"time.duration gives inf steps (time.duration / time.dt); at most 2^53", "got 1e+308"}));
  EXPECT_TRUE(throws_containing<SceneError>([] { parse(R"({"time": {"frame_rate": 1e308}})"); },
                                            {"time.frame_rate gives 1e+308 frames", "at most 2^53"}));
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"time": {"adaptive": true, "dt_min": 1e-300, "dt": 1e-3, "duration": 1}})"); },
      {"time.duration gives 1e+300 steps (time.duration / time.dt_min)", "got 1 (x.json)"}));
}

// A step runs to its end (a stop signal ends the run after it): a count of passes within one step of 1e9
// held `drench run` of the hydrostatic tank inside its first step, deaf to Ctrl-C. Every such count is at
// most 1000, refused by its key at once and before the output folder is made.
TEST(HostileInput, PassesPerStepOver1000AreRefusedNamingTheKey) {
  for (const std::string key :
       {"fluid.pbf.substeps", "fluid.pbf.iterations", "fluid.pcisph.max_iterations",
        "fluid.dfsph.max_iterations", "fluid.dfsph.max_divergence_iterations", "cloth.substeps",
        "cloth.position_iterations", "coupling.repulsion_sweeps", "coupling.max_ccd_iterations"}) {
    const std::size_t dot = key.find('.'), last = key.rfind('.');
    std::string text = "{\"" + key.substr(0, dot) + "\": {";
    if (last != dot) text += "\"" + key.substr(dot + 1, last - dot - 1) + "\": {";
    text += "\"" + key.substr(last + 1) + "\": 1001}}" + (last != dot ? "}" : "");
    // Bullet's cloth needs at least 4 position iterations (kMinClothPositionIterations).
    const std::string least = key == "cloth.position_iterations" ? "4" : "1";
    EXPECT_TRUE(throws_containing<SceneError>([&] { parse(text); },
                                              {key + " must be in [" + least + ", 1000], got 1001 (x.json)"}))
        << text;
    EXPECT_NO_THROW(parse(text.replace(text.find("1001"), 4, "1000"))) << text;
  }
  // One step of 1001 (not 1e9, so that a regression fails in seconds rather than hangs).
  const test::TempDir dir;
  const Command c = drench_command("run " + demo("hydrostatic_tank.json") + " --steps 1 --out " +
                                       (dir.path() / "out").string() +
                                       " --set fluid.pressure_solver=pbf --set fluid.pbf.substeps=1001",
                                   dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(contains(c.output, "fluid.pbf.substeps must be in [1, 1000], got 1001")) << c.output;
  EXPECT_LT(c.seconds, 5.0);
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

TEST(HostileInput, SettingsWhoseCostHasNoBoundAreRefusedNamingTheKey) {
  // Each ran for tens of seconds a step or hung (the probe of 2026-11-27): a speed of sound of 1e5 m/s, a
  // cloth thickness of 1 m, an s_corr exponent of 2^31 - 1, a work of adhesion of 1e200 N/m.
  const std::string cloth = R"("cloth": {"adhesion": %}, "effects": ["coupling", "adhesion"])";
  const struct {
    std::string scene, refused, accepted, message;
  } cases[] = {
      {R"({"fluid": {"wcsph": {"speed_of_sound": %}}})", "2001", "2000",
       "fluid.wcsph.speed_of_sound must be in (0, 2000], got 2001 (x.json)"},
      {R"({"fluid": {"pbf": {"scorr_n": %}}})", "17", "16",
       "fluid.pbf.scorr_n must be in [1, 16], got 17 (x.json)"},
      {R"({"fluid": {"particle_spacing": 0.005}, "coupling": {"cloth_thickness": %},
           "obstacles": [{"mesh": "v_plane"}], "effects": ["coupling"]})",
       "0.0101", "0.01", "coupling.cloth_thickness must be <= 2 fluid.particle_spacing = 0.01 m"},
      {"{" + cloth + "}", "1.5", "1", "cloth.adhesion must be in [0, 1], got 1.5 (x.json)"},
      {R"({"obstacles": [{"mesh": "v_plane", "adhesion": %}], "effects": ["coupling", "adhesion"]})", "1e200",
       "0", "obstacles[0].adhesion must be in [0, 1], got 1e+200 (x.json)"},
  };
  for (const auto& c : cases) {
    const auto with = [&](const std::string& value) {
      std::string text = c.scene;
      return text.replace(text.find('%'), 1, value);
    };
    EXPECT_TRUE(throws_containing<SceneError>([&] { parse(with(c.refused)); }, {c.message})) << c.scene;
    EXPECT_NO_THROW(parse(with(c.accepted))) << c.scene;
  }
  // The default thickness (1 mm) on a fluid of 0.4 mm particles is refused as a default.
  EXPECT_TRUE(throws_containing<SceneError>(
      [] {
        parse(R"({"fluid": {"particle_spacing": 0.0004}, "obstacles": [{"mesh": "v_plane"}],
                  "effects": ["coupling"]})");
      },
      {"coupling.cloth_thickness must be <= 2 fluid.particle_spacing = 0.0008 m", "(with its default)"}));

  // A scene built in code meets the same bounds before anything is built.
  SceneConfig config = parse(R"({"obstacles": [{"mesh": "v_plane"}], "effects": ["coupling"]})");
  config.fluid.particle_spacing = 0.005;
  config.coupling.cloth_thickness = 1.0;
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] { Simulation simulation(config); },
      {"coupling.cloth_thickness must be <= 2 fluid.particle_spacing = 0.01 m", "got 1.0 (x.json)"}));
  // (FluidSolver.RefusesSettingsOutOfRangeNamingTheField holds the fluid's bounds in code.)

  // The command refuses the 1 m cloth at once and writes nothing.
  expect_jet_refused_at_once("coupling.cloth_thickness=1",
                             "coupling.cloth_thickness must be <= 2 fluid.particle_spacing");
}

TEST(HostileInput, PositionsBeyondWhatFramesHoldAreRefusedBeforeTheFolder) {
  // Positions and lengths the scene writes: at most 1e7 m, by key.
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"obstacles": [{"mesh": "v_plane", "center": [1e100, 0, 0]}]})"); },
      {"obstacles[0].center[0] must be in [-10000000, 10000000], got 1e+100 (x.json)"}));
  EXPECT_TRUE(
      throws_containing<SceneError>([] { parse(R"({"obstacles": [{"mesh": "v_plane", "size": 1e300}]})"); },
                                    {"obstacles[0].size must be in (0, 10000000], got 1e+300 (x.json)"}));
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"boundaries": [{"type": "box", "max": [1e200, 1, 1]}]})"); },
      {"boundaries[0].max[0] must be in [-10000000, 10000000], got 1e+200 (x.json)"}));
  // A V of too many nodes names its triangle_size and the file (an int overflowed at size 1e300 before).
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"obstacles": [{"mesh": "v_plane", "triangle_size": 1e-5}]})"); },
      {"obstacles[0].triangle_size gives the V", "nodes (size and width over triangle_size); at most 1e7",
       "(x.json)"}));

  const test::TempDir dir;
  // An OBJ scaled to points, and a cloth OBJ far beyond float32: refused naming the file, writing nothing.
  const std::string obj = dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
  const std::string far_obj = dir.write("far.obj", "v 1e300 0 0\nv 1e300 0 1\nv 1e300 1 0\nf 1 2 3\n");
  const std::string base = R"({"time": {"dt": 0.001, "duration": 0.002}, )";
  const struct {
    std::string scene, message;
  } cases[] = {
      {base + R"("obstacles": [{"mesh": ")" + obj + R"(", "scale": 1e-300}], "effects": ["coupling"]})",
       "obstacles[0].mesh \"" + obj +
           "\" at obstacles[0].scale 1e-300 and center [0, 0, 0]: triangle 0 has "
           "zero area"},
      {base + R"("cloth": {"mesh": ")" + far_obj + R"("}, "effects": ["coupling"]})",
       "cloth node 0 at [1e+300, 0, 0] m is beyond what frames hold: a scene reaches "
       "10000000 m from the origin"},
      // 1e6 m is within a scene, but not within a surface grid of 0.3 mm cells (2^30 cells: 3.4e5 m).
      {base + R"("fluid": {"particle_spacing": 0.005},
          "emitters": [{"type": "box", "min": [1e6, 0, 0], "max": [1000000.02, 0.02, 0.02]}],
          "effects": ["surface"], "surface": {"cell_size": 0.0003125}})",
       "m is beyond what frames hold: the surface grid's int32 cells reach"},
  };
  for (const auto& c : cases) {
    const std::string scene = dir.write("scene.json", c.scene);
    const Command run =
        drench_command("run " + scene + " --out " + (dir.path() / "out").string(), dir.path() / "log");
    EXPECT_EQ(run.status, 1) << run.output;
    EXPECT_TRUE(contains(run.output, c.message)) << run.output;
    EXPECT_TRUE(contains(run.output, "(" + scene + ")")) << run.output;
    EXPECT_FALSE(fs::exists(dir.path() / "out"));
  }
}

TEST(HostileInput, BoundaryBeyondTheDoublesIsCountedAsInfiniteNotNaN) {
  // Bypassing the loader's coordinate range: the shell's count inf - inf was NaN, the message said "-nan
  // bytes" and blamed the emitter.
  SceneConfig config = parse(R"({"boundaries": [{"type": "box", "max": [1, 1, 1]}]})");
  config.boundaries[0].max = Vec3(1e200, 1e200, 1e200);
  const ResourceEstimate e = estimate_resources(config);
  EXPECT_EQ(e.boundary_particles.value, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] {
        check_resources(config, e, {1e12, 1e12, 1e12});
      },
      {"boundaries[0] with fluid.particle_spacing", "inf bytes"}));
}

TEST(HostileInput, EstimateCountsWhatTheSimulationBuilds) {
  // The dam break at 10 cm: the estimate's particles are emit_box's lattice exactly, its boundary
  // particles sample_box_container's.
  SceneConfig config = load_scene_file(demo("dam_break.json"), {"fluid.particle_spacing=0.1"});
  const ResourceEstimate e = estimate_resources(config);
  const Simulation simulation(config);
  EXPECT_EQ(e.particles.value, static_cast<double>(simulation.particles().size()));
  EXPECT_EQ(e.frames.value, 91.0);  // 3 s at 30 frames/s, and frame 0
  EXPECT_EQ(e.particles.key, "emitters[0] with fluid.particle_spacing = 0.1 m");
  EXPECT_GT(e.boundary_particles.value, 0.0);
  EXPECT_GT(e.memory_bytes.value, e.particles.value * 1000.0);
}

TEST(HostileInput, ParticlesBeyondMemoryAreRefusedBeforeAnyAllocation) {
  const test::TempDir dir;
  const Command c = drench_command("run " + demo("dam_break.json") + " --out " +
                                       (dir.path() / "out").string() + " --set fluid.particle_spacing=1e-9",
                                   dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(
      contains(c.output, "emitters[0] with fluid.particle_spacing = 1e-09 m: about 1e+27 fluid particles"))
      << c.output;
  EXPECT_TRUE(contains(c.output, "bytes available (MemAvailable)")) << c.output;
  EXPECT_LT(c.seconds, 5.0);
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  // drench sweep checks every run's scene before the first starts.
  const Command sweep =
      drench_command("sweep " + demo("dam_break.json") + " --vary fluid.particle_spacing=0.05,1e-9 --out " +
                         (dir.path() / "sweep").string(),
                     dir.path() / "log2");
  EXPECT_EQ(sweep.status, 1) << sweep.output;
  EXPECT_TRUE(contains(sweep.output, "about 1e+27 fluid particles")) << sweep.output;
  EXPECT_FALSE(fs::exists(dir.path() / "sweep"));
  // A boundary of 1 mm around a 1 km box: named by its key.
  const SceneConfig boundary = parse(
      R"({"fluid": {"particle_spacing": 0.001}, "boundaries": [{"type": "box", "max": [1000, 1000, 1000]}]})");
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] {
        check_resources(boundary, estimate_resources(boundary), {1e10, 1e12, 1e12});
      },
      {"boundaries[0] with fluid.particle_spacing = 0.001 m: about 12000048000000 boundary particles",
       "more than the 10000000000 bytes available"}));
}

TEST(HostileInput, ClothOf4096By4096NodesIsRefusedAtOnce) {
  const SceneConfig config = parse(R"({"cloth": {"nodes": [4096, 4096]}})");
  const ResourceEstimate e = estimate_resources(config);
  EXPECT_EQ(e.cloth_nodes.value, 4096.0 * 4096.0);
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] {
        check_resources(config, e, {8e9, 1e15, 1e15});
      },
      {"cloth.nodes: 16777216 cloth nodes need about 62120699200 bytes of memory",
       "more than the 8000000000 bytes available (MemAvailable) (x.json)"}));
  // Through the command: refused by its frames' size, in well under a second, writing nothing.
  const test::TempDir dir;
  const Command c =
      drench_command("run " + demo("jet_on_cloth.json") + " --out " + (dir.path() / "out").string() +
                         " --set cloth.nodes=[4096,4096] --max-output 1e9",
                     dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(contains(c.output, "cloth.nodes: ")) << c.output;
  // Memory or output, whichever this machine runs out of first.
  EXPECT_TRUE(contains(c.output, "16777216 cloth nodes")) << c.output;
  EXPECT_LT(c.seconds, 1.0);
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

TEST(HostileInput, FramesBeyondMaxOutputAreRefusedNamingTheFrameRate) {
  const test::TempDir dir;
  const Command c = drench_command("run " + demo("jet_on_cloth.json") + " --out " +
                                       (dir.path() / "out").string() + " --set time.frame_rate=1e6",
                                   dir.path() / "log");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(contains(c.output, "time.frame_rate: 500001 frames of about")) << c.output;
  EXPECT_TRUE(contains(c.output, "more than --max-output 10737418240 bytes")) << c.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  // The free disk is a limit too.
  const SceneConfig config = load_scene_file(demo("jet_on_cloth.json"));
  EXPECT_TRUE(throws_containing<SceneError>(
      [&] {
        check_resources(config, estimate_resources(config), {1e12, 1e6, 1e12});
      },
      {"31 frames of about", "more than the 1000000 bytes free on the disk of --out"}));
}

// 7. OpenVDB: the cell size is bounded by the spacing, and OpenVDB's exceptions become drench errors.

TEST(HostileInput, SurfaceCellSizeBelowTheBoundIsRefusedInRunAndReconstruct) {
  EXPECT_TRUE(throws_containing<SceneError>(
      [] { parse(R"({"effects": ["surface"], "surface": {"cell_size": 1e-7}})"); },
      {"surface.cell_size must be >= fluid.particle_spacing / 16 = 0.003125 m", "got 1e-07 (x.json)"}));
  const test::TempDir dir;
  const std::string scene = dir.write(
      "scene.json",
      R"({"fluid": {"particle_spacing": 0.05}, "emitters": [{"type": "box", "max": [0.2, 0.2, 0.2]}],
          "boundaries": [{"type": "box", "max": [0.4, 0.4, 0.4]}], "effects": ["surface"],
          "time": {"dt": 0.01, "duration": 0.02, "frame_rate": 50}})");
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(drench_command("run " + scene + " --out " + out.string() + " --quiet", dir.path() / "log").status,
            0);
  const std::string surface = read_text(out / "frames" / "surface_0001.ply");
  const Command c =
      drench_command("reconstruct " + out.string() + " --set surface.cell_size=1e-7", dir.path() / "log2");
  EXPECT_EQ(c.status, 1) << c.output;
  EXPECT_TRUE(contains(c.output, "surface.cell_size must be >= fluid.particle_spacing / 16")) << c.output;
  EXPECT_EQ(read_text(out / "frames" / "surface_0001.ply"), surface);  // nothing lost
  // 1e300 made no triangle and ended 0.
  const Command coarse =
      drench_command("reconstruct " + out.string() + " --set surface.cell_size=1e300", dir.path() / "log3");
  EXPECT_EQ(coarse.status, 1) << coarse.output;
  EXPECT_TRUE(contains(coarse.output, "surface.cell_size must be <= 4 x fluid.particle_spacing = 0.2 m"))
      << coarse.output;
  EXPECT_EQ(read_text(out / "frames" / "surface_0001.ply"), surface);
}

TEST(HostileInput, OpenVdbFailureBecomesADrenchError) {
  // Bypassing the loader (a program calling the library): a cell OpenVDB cannot invert, and a particle
  // beyond its int32 coordinates, are drench::Error naming what failed instead of an abort.
  SurfaceSettings settings;
  settings.cell_size = 1e-9;
  const Vec3Array particles = {Vec3(0, 0, 0), Vec3(1e-8, 0, 0)};
  EXPECT_TRUE(
      throws_containing<Error>([&] { reconstruct_surface(particles, 1e-8, settings, {}); },
                               {"surface: OpenVDB failed to build its grid at surface cell size 1e-09 m"}));
  settings.cell_size = 0.001;
  const Vec3Array far = {Vec3(0, 0, 0), Vec3(1e7, 0, 0)};
  EXPECT_TRUE(throws_containing<Error>(
      [&] { reconstruct_surface(far, 0.002, settings, {}); },
      {"surface: particle 1 at (1e+07, 0, 0) m is beyond the surface grid's int32"}));
}

}  // namespace
}  // namespace drench
