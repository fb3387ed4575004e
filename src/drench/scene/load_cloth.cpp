/// `cloth` of a scene: the mesh (a patch or an OBJ file), its mass and pinning, and the cloth solver's
/// settings (ClothSettings, coupling/cloth_engine.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

ClothSettings read_cloth(const Node& node) {
  ClothSettings cloth;
  const ObjectReader r(
      node, {"mesh", "center", "size", "nodes", "area_density", "pinned", "position_iterations", "substeps",
             "stretch_stiffness", "bending_stiffness", "damping", "max_speed", "max_strain", "adhesion"});
  if (const Node mesh = r["mesh"]; mesh.present()) {
    cloth.mesh = mesh.string();
    if (cloth.mesh.empty()) mesh.fail("must be \"patch\" or the path of an OBJ file");
  }
  r.read("center", cloth.center, kCoordinate);
  if (const Node size = r["size"]; size.present()) {
    if (!size.value().is_array() || size.value().size() != 2)
      size.fail("must be an array of 2 numbers [x, z]");
    cloth.size_x = size.element(0).number(kLength);
    cloth.size_z = size.element(1).number(kLength);
  }
  if (const Node nodes = r["nodes"]; nodes.present()) {
    if (!nodes.value().is_array() || nodes.value().size() != 2)
      nodes.fail("must be an array of 2 integers [x, z]");
    cloth.nodes_x = nodes.element(0).integer<int>(Range{2.0, false, 4096.0, false});
    cloth.nodes_z = nodes.element(1).integer<int>(Range{2.0, false, 4096.0, false});
  }
  r.read("area_density", cloth.area_density, kPositive);
  if (const Node pinned = r["pinned"]; pinned.present()) {
    cloth.pinned = pinned.string();
    if (cloth.pinned != "corners" && cloth.pinned != "corner" && cloth.pinned != "none")
      pinned.fail("must be one of \"corners\", \"corner\", \"none\"");
  }
  r.read("position_iterations", cloth.position_iterations,
         Range{kMinClothPositionIterations, false, kMaxPassesPerStep, false});
  r.read("substeps", cloth.substeps, kPassesPerStep);
  r.read("stretch_stiffness", cloth.stretch_stiffness, Range{0.0, true, 1.0, false});
  r.read("bending_stiffness", cloth.bending_stiffness, Range{0.0, false, 1.0, false});
  r.read("damping", cloth.damping, Range{0.0, false, 1.0, false});
  r.read("adhesion", cloth.adhesion, Range{0.0, false, kMaxWorkOfAdhesion, false});
  // null is "no limit", so that --set cloth.max_speed=null can undo the default.
  if (const Node c = r["max_speed"]; c.present())
    cloth.max_speed = c.value().is_null() ? std::nullopt : std::optional<double>(c.number(kPositive));
  if (const Node c = r["max_strain"]; c.present())
    cloth.max_strain = c.value().is_null() ? std::nullopt : std::optional<double>(c.number(kPositive));
  return cloth;
}

}  // namespace drench::loader
