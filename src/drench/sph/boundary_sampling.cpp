#include <drench/sph/boundary_sampling.hpp>

#include <algorithm>
#include <cmath>

namespace drench {

void BoundaryParticles::append(const BoundaryParticles& other) {
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  volumes.insert(volumes.end(), other.volumes.begin(), other.volumes.end());
}

BoundaryParticles sample_box_container(const Vec3& min, const Vec3& max, Scalar spacing, int layers,
                                       bool open_top) {
  Vec3i cells;
  Vec3 step;
  for (int a = 0; a < 3; ++a) {
    cells[a] = std::max(1, static_cast<int>(std::lround((max[a] - min[a]) / spacing)));
    step[a] = (max[a] - min[a]) / cells[a];
  }
  const int top = open_top ? cells.y() - 1 : cells.y() + layers - 1;
  BoundaryParticles points;
  for (int k = -layers; k < cells.z() + layers; ++k) {
    for (int j = -layers; j <= top; ++j) {
      for (int i = -layers; i < cells.x() + layers; ++i) {
        const bool inside = i >= 0 && i < cells.x() && j >= 0 && j < cells.y() && k >= 0 && k < cells.z();
        if (inside) continue;
        points.positions.emplace_back(min.x() + (i + 0.5) * step.x(), min.y() + (j + 0.5) * step.y(),
                                      min.z() + (k + 0.5) * step.z());
      }
    }
  }
  points.volumes.assign(points.positions.size(), step.prod());
  return points;
}

BoundaryParticles sample_plane(const Vec3& point, const Vec3& normal, const Scalar size[2], Scalar spacing,
                               int layers) {
  Vec3 first, second;
  plane_axes(normal, first, second);
  const int n0 = std::max(1, static_cast<int>(std::lround(size[0] / spacing)));
  const int n1 = std::max(1, static_cast<int>(std::lround(size[1] / spacing)));
  const Scalar s0 = size[0] / n0;
  const Scalar s1 = size[1] / n1;
  BoundaryParticles points;
  for (int l = 0; l < layers; ++l) {
    for (int j = 0; j < n1; ++j) {
      for (int i = 0; i < n0; ++i) {
        points.positions.push_back(point + (-0.5 * size[0] + (i + 0.5) * s0) * first +
                                   (-0.5 * size[1] + (j + 0.5) * s1) * second - (l + 0.5) * spacing * normal);
      }
    }
  }
  points.volumes.assign(points.positions.size(), s0 * s1 * spacing);
  return points;
}

void plane_axes(const Vec3& normal, Vec3& first, Vec3& second) {
  int least = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(normal[a]) < std::abs(normal[least])) least = a;
  }
  first = normal.cross(Vec3::Unit(least)).normalized();
  second = normal.cross(first);
}

bool enforce_boundary(const BoundarySettings& boundary, const Vec3& x_t0, Vec3& x_t1, Vec3& velocity) {
  bool moved = false;
  if (boundary.kind == BoundarySettings::Kind::BOX) {
    const bool top = !boundary.open_top;
    if ((x_t0.array() < boundary.min.array()).any() || (top && (x_t0.array() > boundary.max.array()).any()) ||
        (!top && (x_t0.x() > boundary.max.x() || x_t0.z() > boundary.max.z()))) {
      return false;
    }
    for (int a = 0; a < 3; ++a) {
      if (x_t1[a] < boundary.min[a]) {
        x_t1[a] = boundary.min[a];
        velocity[a] = std::max(velocity[a], 0.0);
        moved = true;
      } else if (x_t1[a] > boundary.max[a] && (a != 1 || top)) {
        x_t1[a] = boundary.max[a];
        velocity[a] = std::min(velocity[a], 0.0);
        moved = true;
      }
    }
    return moved;
  }
  const Vec3& n = boundary.normal;
  const Scalar d0 = (x_t0 - boundary.point).dot(n);
  const Scalar d1 = (x_t1 - boundary.point).dot(n);
  if (d0 < 0.0 || d1 >= 0.0) return false;
  const Vec3 crossing = x_t0 + (d0 / (d0 - d1)) * (x_t1 - x_t0) - boundary.point;
  Vec3 first, second;
  plane_axes(n, first, second);
  if (std::abs(crossing.dot(first)) > 0.5 * boundary.size[0] ||
      std::abs(crossing.dot(second)) > 0.5 * boundary.size[1]) {
    return false;
  }
  x_t1 -= d1 * n;
  velocity -= std::min(velocity.dot(n), 0.0) * n;
  return true;
}

}  // namespace drench
