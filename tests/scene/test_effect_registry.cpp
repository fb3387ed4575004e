// The effect registry (scene/effect_registry.hpp) is the one list of effects: docs/scenes.md documents
// exactly its effects in its order, the loader checks what each entry says it needs, and build_effects builds
// only the effects a scene lists.

#include <drench/scene/effect_registry.hpp>

#include <gtest/gtest.h>

#include <algorithm>
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

// Builds run in the registry's order, so an effect built on another (the wetting on the coupler) must come
// after it.
TEST(EffectRegistry, AnEffectNeedsOnlyEffectsBeforeIt) {
  const std::vector<std::string> names = registry_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const char* needed = effect_registry()[i].needs.effect;
    if (!needed) continue;
    const auto at = std::find(names.begin(), names.end(), needed);
    ASSERT_NE(at, names.end()) << names[i] << " needs an effect the registry does not have: " << needed;
    EXPECT_LT(static_cast<std::size_t>(at - names.begin()), i) << names[i] << " needs " << needed;
  }
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

// A 2 x 2 cloth (validated), every effect listed in turn and all at once: only the listed ones are built.
TEST(EffectRegistry, BuildsOnlyTheListedEffects) {
  const ClothMesh cloth = ClothMesh::grid(2, 0.1, 0.0, 1.0);
  SceneConfig config;
  config.cloth = ClothSettings{};
  const auto built = [&](const std::vector<std::string>& effects) {
    config.effects = effects;
    return build_effects({config, &cloth, &cloth});
  };
  const EffectParts none = built({});
  EXPECT_FALSE(none.viscosity);
  EXPECT_FALSE(none.coupler || none.obstacle || none.carried || none.wetting);
  EXPECT_FALSE(none.leak_audit);
  EXPECT_EQ(none.leak_counter.constructed + none.wetting_counter.constructed, 0u);

  EXPECT_TRUE(built({"viscosity"}).viscosity);
  EXPECT_TRUE(built({"leak_audit"}).leak_audit);
  EXPECT_EQ(built({"leak_audit"}).leak_counter.constructed, 1u);
  const EffectParts coupling = built({"coupling"});
  ASSERT_TRUE(coupling.coupler);
  EXPECT_EQ(coupling.coupler->friction_counter().constructed, 0u) << "friction is not listed";
  EXPECT_TRUE(coupling.obstacle && coupling.carried) << "the default coupling settings use both";
  EXPECT_FALSE(coupling.wetting);
  EXPECT_EQ(built({"friction", "coupling"}).coupler->friction_counter().constructed, 1u);

  const EffectParts all = built(registry_names());
  EXPECT_TRUE(all.viscosity && all.leak_audit);
  ASSERT_TRUE(all.coupler && all.wetting);
  EXPECT_EQ(all.coupler->friction_counter().constructed, 1u);
  EXPECT_EQ(all.wetting_counter.constructed, 1u);

  // Without a mesh there is nothing to couple, audit or wet, whatever the scene lists.
  config.effects = registry_names();
  const EffectParts meshless = build_effects({config, nullptr, nullptr});
  EXPECT_TRUE(meshless.viscosity);
  EXPECT_FALSE(meshless.coupler || meshless.leak_audit || meshless.wetting);
}

}  // namespace
}  // namespace drench
