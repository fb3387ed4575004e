#include <drench/render/camera.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace drench::render {

namespace {

constexpr Scalar kPi = 3.14159265358979323846;

Scalar radians(Scalar degrees) {
  return degrees * kPi / 180.0;
}

}  // namespace

Camera frame_bounds(const Eigen::AlignedBox3d& bounds, Scalar aspect, Scalar fov_deg) {
  const Vec3 centre = bounds.center();
  const Scalar tan_vertical = std::tan(0.5 * radians(fov_deg));
  const Scalar tan_horizontal = tan_vertical * aspect;
  const Scalar azimuth = radians(30.0), elevation = radians(25.0);
  const Vec3 to_eye(std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                    std::cos(azimuth) * std::cos(elevation));
  Camera camera;
  camera.target = centre;
  camera.fov_deg = fov_deg;
  camera.position = centre + to_eye;
  const Eigen::Matrix4d view = view_matrix(camera);  // its axes do not depend on the distance
  const Vec3 right = view.block<1, 3>(0, 0).transpose(), up = view.block<1, 3>(1, 0).transpose();
  // The nearest distance at which every corner of the box is inside both fields of view: a corner at offset
  // o from the centre is at depth d - o . to_eye and must have |o . right| <= depth tan(horizontal half
  // angle), likewise upwards. 5 % of margin keeps the scene off the image's edges.
  Scalar distance = 0.0;
  const Vec3 half = 0.5 * bounds.sizes().cwiseMax(Vec3::Constant(1e-3));
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 o((corner & 1 ? 1 : -1) * half.x(), (corner & 2 ? 1 : -1) * half.y(),
                 (corner & 4 ? 1 : -1) * half.z());
    distance = std::max({distance, o.dot(to_eye) + std::abs(o.dot(right)) / tan_horizontal,
                         o.dot(to_eye) + std::abs(o.dot(up)) / tan_vertical});
  }
  camera.position = centre + to_eye * (1.05 * distance);
  return camera;
}

Eigen::AlignedBox3d points_box(const Vec3Array& points) {
  Eigen::AlignedBox3d box;
  for (const Vec3& p : points)
    box.extend(p);
  return box;
}

Eigen::AlignedBox3d quantile_box(const Vec3Array& points, double lo, double hi) {
  Eigen::AlignedBox3d box;
  if (points.empty()) return box;
  std::vector<double> values(points.size());
  Vec3 min, max;
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < points.size(); ++i)
      values[i] = points[i][a];
    const auto at = [&](double q) {
      const std::size_t k = static_cast<std::size_t>(q * (values.size() - 1));
      std::nth_element(values.begin(), values.begin() + k, values.end());
      return values[k];
    };
    min[a] = at(lo);
    max[a] = at(hi);
  }
  return Eigen::AlignedBox3d(min, max);
}

Eigen::AlignedBox3d framed_bounds(const SceneConfig& config, const Eigen::AlignedBox3d& stage,
                                  const Eigen::AlignedBox3d& fluid) {
  Eigen::AlignedBox3d bounds = stage;
  if (!stage.isEmpty()) {
    for (const EmitterSettings& emitter : config.emitters) {
      if (emitter.kind == EmitterSettings::Kind::NOZZLE) {
        bounds.extend(emitter.nozzle.center);
      } else {
        bounds.extend(emitter.box.min);
        bounds.extend(emitter.box.max);
      }
    }
  } else {
    bounds = fluid;
  }
  if (bounds.isEmpty()) bounds = Eigen::AlignedBox3d(Vec3::Constant(-0.5), Vec3::Constant(0.5));
  return bounds;
}

Camera resolve_camera(const std::optional<CameraSettings>& settings, const Eigen::AlignedBox3d& bounds,
                      Scalar aspect) {
  if (!settings) return frame_bounds(bounds, aspect);
  if (!settings->position || !settings->target) return frame_bounds(bounds, aspect, settings->fov_deg);
  Camera camera;
  camera.position = *settings->position;
  camera.target = *settings->target;
  camera.fov_deg = settings->fov_deg;
  return camera;
}

void orbit(Camera& camera, Scalar azimuth, Scalar elevation) {
  const Vec3 offset = camera.position - camera.target;
  const Scalar distance = offset.norm();
  const Scalar limit = radians(89.0);
  const Scalar old_elevation = std::asin(std::clamp(offset.y() / distance, -1.0, 1.0));
  const Scalar new_elevation = std::clamp(old_elevation + elevation, -limit, limit);
  const Scalar new_azimuth = std::atan2(offset.x(), offset.z()) + azimuth;
  camera.position = camera.target + distance * Vec3(std::sin(new_azimuth) * std::cos(new_elevation),
                                                    std::sin(new_elevation),
                                                    std::cos(new_azimuth) * std::cos(new_elevation));
}

void pan(Camera& camera, Scalar dx, Scalar dy, int height) {
  const Eigen::Matrix4d view = view_matrix(camera);
  const Vec3 right = view.block<1, 3>(0, 0).transpose(), up = view.block<1, 3>(1, 0).transpose();
  // The height of the image at the target's depth, over its pixels.
  const Scalar metres_per_pixel = 2.0 * (camera.position - camera.target).norm() *
                                  std::tan(0.5 * radians(camera.fov_deg)) / std::max(height, 1);
  const Vec3 shift = metres_per_pixel * (-dx * right + dy * up);
  camera.position += shift;
  camera.target += shift;
}

void zoom(Camera& camera, Scalar factor) {
  const Vec3 offset = camera.position - camera.target;
  const Scalar distance = std::max(offset.norm() * factor, 1e-3);
  camera.position = camera.target + offset.normalized() * distance;
}

Eigen::Matrix4d view_matrix(const Camera& camera) {
  const Vec3 forward = (camera.target - camera.position).normalized();
  // Straight up or down, +y cannot be the image's up; -z then is (the far side at the top, looking down).
  const Vec3 world_up = std::abs(forward.y()) > 0.999 ? Vec3(0, 0, -1) : Vec3(0, 1, 0);
  const Vec3 right = forward.cross(world_up).normalized();
  const Vec3 up = right.cross(forward);
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = right.transpose();
  view.block<1, 3>(1, 0) = up.transpose();
  view.block<1, 3>(2, 0) = -forward.transpose();
  view(0, 3) = -right.dot(camera.position);
  view(1, 3) = -up.dot(camera.position);
  view(2, 3) = forward.dot(camera.position);
  return view;
}

Eigen::Matrix4d projection_matrix(const Camera& camera, Scalar aspect, Scalar near, Scalar far) {
  const Scalar f = 1.0 / std::tan(0.5 * radians(camera.fov_deg));
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = f / aspect;
  projection(1, 1) = f;
  projection(2, 2) = (far + near) / (near - far);
  projection(2, 3) = 2.0 * far * near / (near - far);
  projection(3, 2) = -1.0;
  return projection;
}

std::optional<Eigen::Vector2d> project_to_pixel(const Camera& camera, int width, int height,
                                                const Vec3& point) {
  const Eigen::Vector4d eye = view_matrix(camera) * point.homogeneous();
  if (eye.z() >= 0.0) return std::nullopt;  // at or behind the eye
  const Scalar aspect = static_cast<Scalar>(width) / height;
  // near and far do not change x and y: any pair will do.
  const Eigen::Vector4d clip = projection_matrix(camera, aspect, 0.01, 100.0) * eye;
  const Scalar x_ndc = clip.x() / clip.w(), y_ndc = clip.y() / clip.w();
  return Eigen::Vector2d(0.5 * (x_ndc + 1.0) * width, 0.5 * (1.0 - y_ndc) * height);
}

}  // namespace drench::render
