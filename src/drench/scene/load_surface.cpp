/// `surface` of a scene: how the fluid's surface is reconstructed at every frame (SurfaceSettings,
/// surface/surface_settings.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

SurfaceSettings read_surface(const Node& node) {
  SurfaceSettings surface;
  const ObjectReader r(node, {"field", "cell_size", "contact_aware", "contact_offset"});
  r.read_choice(
      "field", surface.field,
      Choices<SurfaceField>{{"zhu_bridson", SurfaceField::ZHU_BRIDSON}, {"density", SurfaceField::DENSITY}});
  r.read("cell_size", surface.cell_size, kPositive);
  r.read("contact_aware", surface.contact_aware);
  r.read("contact_offset", surface.contact_offset, kNonNegative);
  return surface;
}

}  // namespace drench::loader
