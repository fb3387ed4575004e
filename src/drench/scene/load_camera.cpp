/// `camera` of a scene: where `drench render` looks from (CameraSettings, scene/scene_config.hpp).

#include <drench/scene/load_sections.hpp>

namespace drench::loader {

CameraSettings read_camera(const Node& node) {
  CameraSettings camera;
  const ObjectReader r(node, {"position", "target", "fov_deg"});
  // Bounded as every scene coordinate is: a camera at 1e300 m, or 1e-300 m from its target, drew a blank
  // image, and so did a field of view of 1e-300 degrees.
  if (const Node n = r["position"]; n.present()) camera.position = n.vec3(kCoordinate);
  if (const Node n = r["target"]; n.present()) camera.target = n.vec3(kCoordinate);
  r.read("fov_deg", camera.fov_deg, Range{kMinFovDeg, false, kMaxFovDeg, false});
  // Half a camera would be framed by guesswork; say which half is missing instead.
  if (camera.position && !camera.target)
    r["target"].fail_without_value("is missing; give camera.position and camera.target together");
  if (camera.target && !camera.position)
    r["position"].fail_without_value("is missing; give camera.position and camera.target together");
  if (camera.position && !((*camera.position - *camera.target).norm() >= kMinCameraDistance))
    r["target"].fail("must be at least 1e-6 m from camera.position");
  return camera;
}

}  // namespace drench::loader
