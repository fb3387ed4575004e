#include <drench/common/triangle_geometry.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace drench {

Vec3 closest_point_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (nn > 0.0 && std::isfinite(nn)) {
    const double wa = n.dot((b - p).cross(c - p)) / nn;
    const double wb = n.dot((c - p).cross(a - p)) / nn;
    const Vec3 weights(wa, wb, 1.0 - wa - wb);
    if (weights.minCoeff() >= 0.0 && weights.allFinite()) return weights;
  }
  const std::array<const Vec3*, 3> v = {&a, &b, &c};
  Vec3 best(1.0, 0.0, 0.0);
  double best_distance = (p - a).squaredNorm();
  for (int i = 0; i < 3; ++i) {
    const Vec3& u = *v[i];
    const Vec3 e = *v[(i + 1) % 3] - u;
    const double ee = e.squaredNorm();
    double s = ee > 0.0 ? (p - u).dot(e) / ee : 0.0;
    s = std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.0;
    const double distance = (p - (u + s * e)).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = Vec3::Zero();
      best[i] = 1.0 - s;
      best[(i + 1) % 3] = s;
    }
  }
  return best;
}

}  // namespace drench
