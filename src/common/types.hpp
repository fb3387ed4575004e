#pragma once
/// Basic numeric types shared by every drench module. All quantities are SI (m, s, kg) and double precision,
/// matching Bullet's double build (bullet-float64) that the adapter links.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace drench {

using Scalar = double;
using Vec3 = Eigen::Vector3d;
using Vec3i = Eigen::Vector3i;
/// Per-particle (or per-node) vectors: N entries of Vec3, one per item, stored contiguously (N x 3 layout).
using Vec3Array = std::vector<Vec3>;
using ScalarArray = std::vector<Scalar>;
using Index = std::uint32_t;
using IndexArray = std::vector<Index>;

}  // namespace drench
