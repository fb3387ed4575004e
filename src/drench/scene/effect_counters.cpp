#include <drench/scene/effect_counters.hpp>

namespace drench {

const EffectCounter* EffectCounters::find(const std::string& name) const {
  if (name == "viscosity") return &viscosity;
  if (name == "coupling") return &coupling;
  if (name == "friction") return &friction;
  if (name == "leak_audit") return &leak_audit;
  if (name == "surface") return &surface;
  if (name == "wetting") return &wetting;
  return nullptr;
}

}  // namespace drench
