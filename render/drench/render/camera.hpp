#pragma once
/// The camera of `drench render` (and the viewer to come): where it looks from, and where a world point lands
/// in the image. Pure geometry, no OpenGL: tests project known points with it and check the pixels there.

#include <optional>

#include <drench/common/types.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench::render {

/// A perspective pinhole camera. +y is the world's up (scene_config.hpp), so the image's up is +y as seen
/// from the camera, or -z when the camera looks straight up or down.
struct Camera {
  Vec3 position = Vec3(0.0, 0.0, 1.0);  ///< eye (unit: m)
  Vec3 target = Vec3::Zero();           ///< drawn at the image's centre (unit: m), != position
  Scalar fov_deg = 45.0;                ///< vertical field of view (unit: degree), in (0, 180)
};

/// A camera that shows all of `bounds` at `aspect`: it looks at the box's centre from above and in front
/// (30 degrees of azimuth from +z, 25 of elevation), from 5 % beyond the nearest distance at which all eight
/// corners of the box are inside both fields of view. Deterministic, so every frame of a run is drawn from
/// the same place.
/// @param bounds  the scene's box (unit: m); must not be empty; a box of zero size is framed as 1 mm wide
/// @param aspect  width / height of the image, > 0
Camera frame_bounds(const Eigen::AlignedBox3d& bounds, Scalar aspect, Scalar fov_deg = 45.0);

/// The camera a render uses: `settings`' position and target when it has them (a scene's `camera` key or
/// `--camera`), else frame_bounds with its field of view (45 degrees without settings).
Camera resolve_camera(const std::optional<CameraSettings>& settings, const Eigen::AlignedBox3d& bounds,
                      Scalar aspect);

/// World to eye coordinates (OpenGL's convention: the camera looks down -z, +y up), a rigid motion.
Eigen::Matrix4d view_matrix(const Camera& camera);

/// Eye to clip coordinates, OpenGL's perspective projection.
/// @param aspect  width / height, > 0
/// @param near, far  clipping distances along the view direction (unit: m), 0 < near < far
Eigen::Matrix4d projection_matrix(const Camera& camera, Scalar aspect, Scalar near, Scalar far);

/// Where `point` (unit: m) lands in a `width` x `height` image of `camera`: x to the right and y downwards
/// in pixels from the image's top-left corner, as a PNG's rows run; pixel (i, j) covers [i, i + 1) x
/// [j, j + 1). std::nullopt when the point is not in front of the camera. Points outside the image give
/// coordinates outside [0, width) x [0, height).
std::optional<Eigen::Vector2d> project_to_pixel(const Camera& camera, int width, int height,
                                                const Vec3& point);

}  // namespace drench::render
