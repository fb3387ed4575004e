#include <drench/scene/scene_config.hpp>

#include <algorithm>

#include <drench/scene/effect_registry.hpp>

namespace drench {

const std::vector<std::string>& known_effects() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> all;
    for (const EffectEntry& effect : effect_registry())
      all.emplace_back(effect.name);
    return all;
  }();
  return names;
}

bool SceneConfig::has_effect(const std::string& name) const {
  return std::find(effects.begin(), effects.end(), name) != effects.end();
}

}  // namespace drench
