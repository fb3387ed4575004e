/// `obstacles` of a scene: static triangle meshes, the built-in V of Fig. 8 or OBJ files (ObstacleSettings,
/// coupling/static_obstacles.hpp).

#include <cmath>

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

ObstacleSettings read_obstacle(const Node& node) {
  ObstacleSettings obstacle;
  const ObjectReader r(
      node, {"mesh", "center", "scale", "angle_deg", "size", "width", "triangle_size", "adhesion"});
  const Node mesh = r["mesh"];
  if (!mesh.present()) mesh.fail_without_value("is missing; must be \"v_plane\" or the path of an OBJ file");
  obstacle.mesh = mesh.string();
  if (obstacle.mesh.empty()) mesh.fail("must be \"v_plane\" or the path of an OBJ file");
  r.read("center", obstacle.center, kCoordinate);
  const bool v_plane = obstacle.mesh == "v_plane";
  // A key of the other kind would be silently ignored.
  for (const char* key : {"angle_deg", "size", "width", "triangle_size"}) {
    if (!v_plane && r[key].present()) r[key].fail("applies to \"mesh\": \"v_plane\" only");
  }
  if (v_plane && r["scale"].present()) r["scale"].fail("applies to an OBJ mesh only");
  r.read("scale", obstacle.scale, kPositive);
  r.read("angle_deg", obstacle.angle_deg, Range{0.0, true, 180.0, true});
  r.read("size", obstacle.size, kLength);
  r.read("width", obstacle.width, kLength);
  r.read("triangle_size", obstacle.triangle_size, kLength);
  r.read("adhesion", obstacle.adhesion, Range{0.0, false, kMaxWorkOfAdhesion, false});
  if (v_plane) {
    // As v_plane_mesh counts them, here so that the message names the file.
    const double nodes = (2.0 * std::ceil(obstacle.size / obstacle.triangle_size - 1e-9) + 1.0) *
                         (std::ceil(obstacle.width / obstacle.triangle_size - 1e-9) + 1.0);
    if (!(nodes <= kMaxVPlaneNodes)) {
      const Node key = r["triangle_size"].present() ? r["triangle_size"]
                       : r["size"].present()        ? r["size"]
                                                    : r["width"];
      key.fail("gives the V " + show(nodes) + " nodes (size and width over triangle_size); at most 1e7");
    }
  }
  return obstacle;
}

}  // namespace drench::loader
