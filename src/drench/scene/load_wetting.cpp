/// `wetting` of a scene: the water the cloth absorbs, spreads and drips (WettingSettings,
/// wetting/wetting_settings.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

WettingSettings read_wetting(const Node& node) {
  WettingSettings wetting;
  const ObjectReader r(node, {"max_saturation", "absorption_rate", "diffusion", "gravity_flow"});
  r.read("max_saturation", wetting.max_saturation, kPositive);
  r.read("absorption_rate", wetting.absorption_rate, kNonNegative);
  r.read("diffusion", wetting.diffusion, Range{0.0, false, kMaxWettingDiffusion, false});
  r.read("gravity_flow", wetting.gravity_flow, Range{0.0, false, kMaxGravityFlow, false});
  return wetting;
}

}  // namespace drench::loader
