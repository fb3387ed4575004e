/// `surface` of a scene: how the fluid's surface is reconstructed at every frame (SurfaceSettings,
/// surface/surface_settings.hpp).

#include <drench/scene/load_sections.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench::loader {

SurfaceSettings read_surface(const Node& node) {
  SurfaceSettings surface;
  const ObjectReader r(node, {"field", "kernel", "cell_size", "contact_aware", "contact_offset", "smoothing",
                              "max_anisotropy", "anisotropy_scale", "isolated_scale", "min_neighbours"});
  r.read_choice("kernel", surface.kernel, surface_kernel_names());
  // Yu & Turk's kernels are a density field's: that field unless the scene names another (an error then).
  if (surface.kernel == SurfaceKernel::ANISOTROPIC) surface.field = SurfaceField::DENSITY;
  r.read_choice("field", surface.field, surface_field_names());
  if (surface.kernel == SurfaceKernel::ANISOTROPIC && surface.field != SurfaceField::DENSITY) {
    r["field"].fail(
        "must be \"density\" with surface.kernel \"anisotropic\" (Yu & Turk's kernels are the "
        "density field's)");
  }
  r.read("cell_size", surface.cell_size, kPositive);
  r.read("contact_aware", surface.contact_aware);
  r.read("contact_offset", surface.contact_offset, kNonNegative);
  r.read("smoothing", surface.smoothing, Range{0.0, false, 1.0, false});
  r.read("max_anisotropy", surface.max_anisotropy, kAtLeastOne);
  r.read("anisotropy_scale", surface.anisotropy_scale, kPositive);
  r.read("isolated_scale", surface.isolated_scale, Range{0.0, true, 2.0, false});
  r.read("min_neighbours", surface.min_neighbours, kAtLeastOne);
  return surface;
}

}  // namespace drench::loader
