#include <drench/scene/effect_counters.hpp>

#include <drench/scene/effect_registry.hpp>

namespace drench {

const EffectCounter* EffectCounters::find(const std::string& name) const {
  const EffectEntry* effect = find_effect(name);
  return effect ? &(this->*(effect->counter)) : nullptr;
}

}  // namespace drench
