/// `camera` of a scene: where `drench render` looks from (CameraSettings, scene/scene_config.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

CameraSettings read_camera(const Node& node) {
  CameraSettings camera;
  const ObjectReader r(node, {"position", "target", "fov_deg"});
  if (const Node n = r["position"]; n.present()) camera.position = n.vec3();
  if (const Node n = r["target"]; n.present()) camera.target = n.vec3();
  r.read("fov_deg", camera.fov_deg, Range{0.0, true, 180.0, true});
  // Half a camera would be framed by guesswork; say which half is missing instead.
  if (camera.position && !camera.target)
    r["target"].fail_without_value("is missing; give camera.position and camera.target together");
  if (camera.target && !camera.position)
    r["position"].fail_without_value("is missing; give camera.position and camera.target together");
  if (camera.position && *camera.position == *camera.target)
    r["target"].fail("must differ from camera.position");
  return camera;
}

}  // namespace drench::loader
