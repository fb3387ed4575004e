#pragma once
/// Basic numeric types shared by every drench module. All quantities are SI (m, s, kg) and double precision,
/// matching Bullet's double build (bullet-float64) that the adapter links.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
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
/// A triangle as three node indices, counter-clockwise seen from the side its normal points to.
using Triangle = std::array<Index, 3>;

/// The most passes a setting may ask for within one scene step (sub-steps, iterations, sweeps, CCD rounds):
/// a step is not interrupted (a stop signal ends a run after it), so a count of 1e9 would hold a run for
/// years; no scene needs more than a thousand, where the published methods use a few to a hundred.
inline constexpr int kMaxPassesPerStep = 1000;

/// The largest |coordinate| and extent anything in a scene may have (unit: m): 10,000 km, past the Earth's
/// radius, so only a typo reaches it. Beyond it frames' float32 positions lose the particles (1e300 m was
/// written as inf), and a surface grid's int32 cells run out past 2^30 cells (2,700 km at 2.5 mm cells).
inline constexpr double kMaxCoordinate = 1e7;

/// The 3 N coordinates of `points` as one array of doubles (x0 y0 z0 x1 ...), for loops that gather by index;
/// nullptr when there are none. A cast, not `points.data()->data()`, which accesses a member through a null
/// pointer when `points` is empty (UBSan), nor a select on empty(), which slowed the gradient factors
/// of PCISPH's neighbor lists (bench_pair_loops neighbor_lists).
static_assert(sizeof(Vec3) == 3 * sizeof(Scalar), "a Vec3Array must be N x 3 contiguous doubles");
inline const Scalar* coordinates(const Vec3Array& points) {
  return reinterpret_cast<const Scalar*>(points.data());
}

}  // namespace drench
