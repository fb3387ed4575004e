/// `surface_tension` of a scene: the water's surface tension coefficient (SurfaceTensionSettings,
/// sph/fluid_settings.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

SurfaceTensionSettings read_surface_tension(const Node& node) {
  SurfaceTensionSettings surface_tension;
  const ObjectReader r(node, {"sigma"});
  r.read("sigma", surface_tension.sigma, kNonNegative);
  return surface_tension;
}

}  // namespace drench::loader
