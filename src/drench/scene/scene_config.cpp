#include <drench/scene/scene_config.hpp>

#include <algorithm>

namespace drench {

const std::vector<std::string>& known_effects() {
  // The single list the loader validates `effects` against and docs/scenes.md mirrors; new effects are added
  // here.
  static const std::vector<std::string> names = {"viscosity",  "coupling", "friction",
                                                 "leak_audit", "surface",  "wetting"};
  return names;
}

bool SceneConfig::has_effect(const std::string& name) const {
  return std::find(effects.begin(), effects.end(), name) != effects.end();
}

}  // namespace drench
