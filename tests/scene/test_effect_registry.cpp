// The effect registry (scene/effect_registry.hpp) is the one list of effects: docs/scenes.md documents
// exactly its effects in its order, and the loader checks what each entry says it needs.

#include <drench/scene/effect_registry.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/scene/scene_loader.hpp>

namespace drench {
namespace {

std::vector<std::string> registry_names() {
  std::vector<std::string> names;
  for (const EffectEntry& effect : effect_registry())
    names.emplace_back(effect.name);
  return names;
}

/// The names in the first column of the table under docs/scenes.md's "## effects", in its order.
std::vector<std::string> documented_effects() {
  std::ifstream in(std::string(DRENCH_SOURCE_DIR) + "/docs/scenes.md");
  std::vector<std::string> names;
  std::string line;
  bool in_section = false;
  const std::regex row(R"re(^\| `"([a-z_]+)"` \|)re");
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## effects";
    std::smatch match;
    if (in_section && std::regex_search(line, match, row)) names.push_back(match[1]);
  }
  return names;
}

/// The message of the SceneError that parsing `text` raises, or "" when it raises none.
std::string scene_error(const std::string& text) {
  try {
    parse_scene(nlohmann::json::parse(text), "x.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string quoted(const std::string& name) {
  return "\"" + name + "\"";
}

// summary.json's effects_ran follows docs/scenes.md's order (docs/output.md), which is the registry's.
TEST(EffectRegistry, DocsListEveryEffectInTheRegistrysOrder) {
  EXPECT_EQ(documented_effects(), registry_names())
      << "docs/scenes.md's effects table and effect_registry() disagree";
  EXPECT_EQ(known_effects(), registry_names());
}

TEST(EffectRegistry, EveryEntryIsComplete) {
  for (const EffectEntry& effect : effect_registry()) {
    SCOPED_TRACE(effect.name);
    EXPECT_EQ(find_effect(effect.name), &effect);
    EXPECT_GT(std::string(effect.description).size(), 20u);
    EXPECT_NE(effect.counter, nullptr);
    EXPECT_EQ(effect.settings.key == nullptr, effect.settings.what == nullptr);
  }
  EXPECT_EQ(find_effect("magic"), nullptr);
}

// Each entry's needs and settings section, checked by the loader with the effect's place in the list or the
// section's key; the message is the one docs/scenes.md describes.
TEST(EffectRegistry, TheLoaderChecksWhatEachEntryNeeds) {
  for (const EffectEntry& effect : effect_registry()) {
    SCOPED_TRACE(effect.name);
    const EffectNeeds& needs = effect.needs;
    // The effects it needs first, so that its own place is the last.
    std::string listed = needs.effect ? quoted(needs.effect) + ", " : "";
    const std::string place = "effects[" + std::to_string(needs.effect ? 1 : 0) + "]";
    listed = R"("effects": [)" + listed + quoted(effect.name) + "]";
    if (needs.mesh == EffectMesh::CLOTH_OR_OBSTACLES) {
      const std::string message = scene_error("{" + listed + "}");
      EXPECT_NE(message.find(place + " needs a cloth or obstacles; "), std::string::npos) << message;
    } else if (needs.mesh == EffectMesh::CLOTH) {
      // Obstacles, which the effects it needs may take instead of a cloth, do not do for it.
      const std::string message = scene_error(R"({"obstacles": [{"mesh": "v_plane"}], )" + listed + "}");
      EXPECT_NE(message.find(place + " needs a cloth; "), std::string::npos) << message;
    } else if (!needs.effect) {
      EXPECT_EQ(scene_error("{" + listed + "}"), "") << "needs nothing";
    }
    if (needs.effect) {
      const std::string message = scene_error(R"({"cloth": {}, "effects": [)" + quoted(effect.name) + "]}");
      EXPECT_NE(
          message.find("effects[0] needs the " + quoted(needs.effect) + " effect" + needs.why + ", got"),
          std::string::npos)
          << message;
    }
    if (effect.settings.key) {
      const std::string message = scene_error("{" + quoted(effect.settings.key) + ": {}}");
      EXPECT_NE(message.find(std::string(effect.settings.key) + " sets " + effect.settings.what +
                             ", but effects does not list " + quoted(effect.name)),
                std::string::npos)
          << message;
    }
  }
}

}  // namespace
}  // namespace drench
