// A SceneConfig written back as its scene file (src/drench/scene/scene_document.hpp): the loader's inverse,
// and the checks a scene built in code meets through it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <string>

#include <drench/common/error.hpp>
#include <drench/scene/scene_document.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/simulation.hpp>
#include "../assertions.hpp"

namespace drench {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// A scene with every section, kind and effect, its settings off their defaults where a file may say so.
SceneConfig everything() {
  SceneConfig c = parse_scene(json::parse(R"({
    "fluid": {"particle_spacing": 0.01, "pressure_solver": "dfsph", "wcsph": {"speed_of_sound": 30},
              "pcisph": {"precision": "double"}, "pbf": {"scorr_substep": null}, "max_speed": 50},
    "emitters": [{"type": "nozzle", "center": [0, 0.3, 0]}, {"type": "box", "max": [0.1, 0.1, 0.1]}],
    "boundaries": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, {"type": "plane", "size": [2, 3]}],
    "kill_regions": [{"type": "plane", "point": [0, -2, 0]}, {"type": "box", "min": [-3, -3, -3],
                      "max": [3, 3, 3]}],
    "time": {"dt": 0.001, "duration": 0.1, "adaptive": true, "dt_min": 0.0001},
    "cloth": {"nodes": [9, 9], "adhesion": 0.1},
    "obstacles": [{"mesh": "v_plane", "adhesion": 0.05}, {"mesh": "/tmp/x.obj", "scale": 2}],
    "coupling": {"slip": "no_slip", "cloth_thickness": 0.002},
    "surface": {"cell_size": 0.004, "contact_offset": 0.001, "kernel": "anisotropic"},
    "wetting": {"diffusion": 0.001},
    "surface_tension": {"sigma": 0.05, "model": "akinci"},
    "effects": ["viscosity", "surface_tension", "coupling", "friction", "adhesion", "leak_audit", "surface",
                "wetting"],
    "camera": {"position": [1, 1, 1], "target": [0, 0, 0]}})"),
                              "everything.json");
  return c;
}

/// Whether the JSON path `key` of docs/scenes.md (`fluid.pbf.scorr_n`, `emitters[i].radius`) is in
/// `document`; `[i]` holds when some element of the list has the rest.
bool has_key(const json& document, const std::string& key) {
  const std::size_t dot = key.find('.');
  const std::string head = key.substr(0, dot);
  const std::string rest = dot == std::string::npos ? "" : key.substr(dot + 1);
  if (head.size() > 3 && head.compare(head.size() - 3, 3, "[i]") == 0) {
    const std::string list = head.substr(0, head.size() - 3);
    if (!document.contains(list)) return false;
    for (const json& element : document[list])
      if (rest.empty() || has_key(element, rest)) return true;
    return false;
  }
  if (!document.is_object() || !document.contains(head)) return false;
  return rest.empty() || has_key(document[head], rest);
}

TEST(SceneDocument, WritesEveryKeyDocsScenesListsForAFullScene) {
  // Every key of docs/scenes.md's tables: a key the writer forgot would go unchecked for scenes built in
  // code. Under "## obstacles" the tables name an element's keys alone.
  std::ifstream docs(std::string(DRENCH_SOURCE_DIR) + "/docs/scenes.md");
  ASSERT_TRUE(docs);
  const json document = scene_document(everything());
  const std::regex row(R"(^\| `([a-z_\.\[\]]+)`( \([a-z]+\))? \|)");
  std::string line, section;
  int keys = 0;
  while (std::getline(docs, line)) {
    if (line.rfind("## ", 0) == 0) section = line.substr(3);
    std::smatch match;
    if (!std::regex_search(line, match, row)) continue;
    std::string key = match[1];
    if (section == "obstacles" && key.find('.') == std::string::npos && key != "obstacles")
      key = "obstacles[i]." + key;
    if (section == "effects") continue;  // the effects' names, not keys
    ++keys;
    EXPECT_TRUE(has_key(document, key)) << key << " (docs/scenes.md, ## " << section << ")";
  }
  EXPECT_GT(keys, 120);
}

TEST(SceneDocument, ParsesBackToTheSameDocument) {
  const SceneConfig config = everything();
  const json document = scene_document(config);
  EXPECT_EQ(scene_document(parse_scene(document, "written.json")), document);
}

/// Whether every value `file` gives is in `written` at the same path and equal (numbers as doubles).
testing::AssertionResult gives_what_the_file_says(const json& file, const json& written,
                                                  const std::string& at) {
  if (file.is_object()) {
    for (const auto& [key, value] : file.items()) {
      if (!written.is_object() || !written.contains(key))
        return testing::AssertionFailure() << at << key << " is not written";
      const testing::AssertionResult inner = gives_what_the_file_says(value, written[key], at + key + ".");
      if (!inner) return inner;
    }
    return testing::AssertionSuccess();
  }
  if (file.is_array() && written.is_array() && file.size() == written.size()) {
    for (std::size_t i = 0; i < file.size(); ++i) {
      const testing::AssertionResult inner =
          gives_what_the_file_says(file[i], written[i], at + "[" + std::to_string(i) + "].");
      if (!inner) return inner;
    }
    return testing::AssertionSuccess();
  }
  if (file.is_number() && written.is_number() && file.get<double>() == written.get<double>())
    return testing::AssertionSuccess();
  if (file == written) return testing::AssertionSuccess();
  return testing::AssertionFailure() << at << " is " << written.dump() << " in the file " << file.dump();
}

TEST(SceneDocument, EachDemoSceneIsWrittenAsItsFileSaysIt) {
  for (const auto& entry : fs::directory_iterator(std::string(DRENCH_SOURCE_DIR) + "/demos/scenes")) {
    const std::string path = entry.path().string();
    std::ifstream in(path);
    json file = json::parse(in);
    const SceneConfig config = load_scene_file(path);
    const json written = scene_document(config);
    // load_scene_file makes mesh paths absolute; compare the rest.
    if (file.contains("cloth")) file["cloth"].erase("mesh");
    if (file.contains("obstacles")) {
      for (std::size_t i = 0; i < file["obstacles"].size(); ++i)
        if (file["obstacles"][i].value("mesh", "") != "v_plane") file["obstacles"][i].erase("mesh");
    }
    EXPECT_TRUE(gives_what_the_file_says(file, written, "")) << path;
    EXPECT_EQ(scene_document(parse_scene(written, path)), written) << path;
  }
}

TEST(SceneDocument, ASceneBuiltInCodeIsRefusedAsItsFileWouldBe) {
  // What only the loader checked before: a nozzle's radius, a box emitter turned inside out, a step longer
  // than the run, surface settings of the anisotropic kernel with another field.
  const auto refused = [](const std::function<void(SceneConfig&)>& change, const std::string& message) {
    SceneConfig config = parse_scene(json::parse(R"({"emitters": [{"type": "nozzle"}, {"type": "box"}],
                                                    "effects": ["surface"]})"),
                                     "x.json");
    config.source = "<code>";
    change(config);
    return test::throws_containing<SceneError>([&] { check_scene_built_in_code(config); }, {message});
  };
  EXPECT_TRUE(refused([](SceneConfig& c) { c.emitters[0].nozzle.radius = std::nan(""); },
                      "emitters[0].radius must be finite, got nan (<code>)"));
  EXPECT_TRUE(refused([](SceneConfig& c) { c.emitters[1].box.max = Vec3(-1, 1, 1); },
                      "emitters[1].max must be > emitters[1].min"));
  EXPECT_TRUE(refused([](SceneConfig& c) { c.time.dt = 2.0; },
                      "time.duration must be >= time.dt = 2, got 1.0 (<code>)"));
  EXPECT_TRUE(refused(
      [](SceneConfig& c) {
        c.surface.kernel = SurfaceKernel::ANISOTROPIC;
        c.surface.field = SurfaceField::ZHU_BRIDSON;
      },
      "surface.field must be \"density\" with surface.kernel \"anisotropic\""));
  EXPECT_TRUE(refused([](SceneConfig& c) { c.effects.push_back("coupling"); },
                      "effects[1] needs a cloth or obstacles"));
  // A program's own meshes (a CoupledWorld's Bullet cloth) meet the coupling's need.
  SceneConfig supplied = parse_scene(json::parse(R"({"effects": ["coupling", "wetting"]})"), "x.json",
                                     SuppliedMeshes{true, true});
  EXPECT_NO_THROW(check_scene_built_in_code(supplied, SuppliedMeshes{true, true}));
  // And the Simulation refuses before it builds anything.
  SceneConfig config;
  config.emitters.emplace_back();
  config.emitters[0].kind = EmitterSettings::Kind::NOZZLE;
  config.emitters[0].nozzle.radius = 1e9;
  EXPECT_TRUE(test::throws_containing<SceneError>(
      [&] { Simulation simulation(config); },
      {"emitters[0].radius must be in (0, 10000000], got 1000000000.0 (<code>)"}));
  // Nor beyond the machine's memory: a 10 x 9.5 x 10 m block of 1 cm water built in code threw
  // std::bad_alloc from a CoupledWorld's constructor.
  SceneConfig block;
  block.source = "<code>";
  block.emitters.emplace_back();
  block.emitters[0].kind = EmitterSettings::Kind::BOX;
  block.emitters[0].box.min = Vec3(-5, 0.5, -5);
  block.emitters[0].box.max = Vec3(5, 10, 5);
  block.fluid.particle_spacing = 0.001;  // 9.5e11 particles: beyond any machine's memory
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { Simulation simulation(block); },
                                                  {"emitters[0]", "bytes of memory", "(<code>)"}));
}

}  // namespace
}  // namespace drench
