/// `surface_tension` of a scene: the water's surface tension coefficient and model (SurfaceTensionSettings,
/// sph/fluid_settings.hpp).

#include <drench/scene/load_sections.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench::loader {

SurfaceTensionSettings read_surface_tension(const Node& node) {
  SurfaceTensionSettings surface_tension;
  const ObjectReader r(node, {"sigma", "model"});
  r.read("sigma", surface_tension.sigma, kNonNegative);
  r.read_choice("model", surface_tension.model, surface_tension_model_names());
  return surface_tension;
}

}  // namespace drench::loader
