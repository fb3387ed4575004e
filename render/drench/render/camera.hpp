#pragma once
/// The camera of `drench render` and `drench view`: where it looks from, what it frames by default, how the
/// viewer's mouse moves it, and where a world point lands in the image. Pure geometry, no OpenGL: tests
/// project known points with it and check the pixels there.

#include <optional>

#include <drench/common/types.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench::render {

/// A perspective pinhole camera. +y is the world's up (scene_config.hpp), so the image's up is +y as seen
/// from the camera, or -z when the camera looks straight up or down.
struct Camera {
  Vec3 position = Vec3(0.0, 0.0, 1.0);  ///< eye (unit: m)
  Vec3 target = Vec3::Zero();           ///< drawn at the image's centre (unit: m), != position
  Scalar fov_deg = 45.0;  ///< vertical field of view (unit: degree), in [kMinFovDeg, kMaxFovDeg]
};

/// A camera that shows all of `bounds` at `aspect`: it looks at the box's centre from above and in front
/// (30 degrees of azimuth from +z, 25 of elevation), from 5 % beyond the nearest distance at which all eight
/// corners of the box are inside both fields of view. Deterministic, so every frame of a run is drawn from
/// the same place.
/// @param bounds  the scene's box (unit: m); must not be empty; a box of zero size is framed as 1 mm wide
/// @param aspect  width / height of the image, > 0
Camera frame_bounds(const Eigen::AlignedBox3d& bounds, Scalar aspect, Scalar fov_deg = 45.0);

/// The box of `points` (unit: m); empty when there are none.
Eigen::AlignedBox3d points_box(const Vec3Array& points);

/// The box from the `lo` to the `hi` quantile of `points` on each axis, 0 <= lo <= hi <= 1: stray droplets
/// do not shrink the picture. Empty when there are no points.
Eigen::AlignedBox3d quantile_box(const Vec3Array& points, double lo, double hi);

/// What the default camera frames, the same for `drench render` and `drench view`: the stage that holds the
/// water (`stage`: the cloth and the obstacles) with `config`'s emitters; only without a stage the `fluid`'s
/// box (a quantile_box, so that spray flying off does not shrink the picture); a 1 m cube about the origin
/// when both are empty.
Eigen::AlignedBox3d framed_bounds(const SceneConfig& config, const Eigen::AlignedBox3d& stage,
                                  const Eigen::AlignedBox3d& fluid);

/// The camera a render uses: `settings`' position and target when it has them (a scene's `camera` key or
/// `--camera`), else frame_bounds with its field of view (45 degrees without settings).
Camera resolve_camera(const std::optional<CameraSettings>& settings, const Eigen::AlignedBox3d& bounds,
                      Scalar aspect);

/// Turns `camera` about its target, as the viewer's left drag does: by `azimuth` about the world's +y and by
/// `elevation` upwards (unit: rad). The target and the distance stay; the elevation stops 1 degree short of
/// straight up or down, where the image's up would flip.
void orbit(Camera& camera, Scalar azimuth, Scalar elevation);

/// Moves the camera and its target together, as the viewer's right or middle drag does: a point at the
/// target's depth follows a cursor that moves `dx` pixels to the right and `dy` pixels down in an image
/// `height` pixels high (>= 1).
void pan(Camera& camera, Scalar dx, Scalar dy, int height);

/// Moves the camera towards its target (`factor` < 1) or away from it (> 1), as the viewer's scroll wheel
/// does: the distance is multiplied by `factor` (> 0) and kept at least 1 mm.
void zoom(Camera& camera, Scalar factor);

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
