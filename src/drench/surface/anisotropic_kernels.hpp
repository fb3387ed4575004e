#pragma once
/// Yu & Turk 2013's anisotropic kernels ("Reconstructing surfaces of particle-based fluids using anisotropic
/// kernels", ACM TOG 32(1)), kept contact-aware for Huber et al. 2013 sec. 4: a neighbour whose segment to
/// the particle crosses a cloth or obstacle triangle is not part of its neighbourhood, and a smoothed centre
/// is never moved across a triangle.

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <drench/common/types.hpp>
#include <drench/surface/surface_reconstruction.hpp>
#include <drench/surface/surface_settings.hpp>

namespace drench {

class TriangleBins;

/// Per obstacle, per triangle: the triangle's box, grown by far more than segment_crosses_triangle's
/// tolerance, so that a segment whose box misses it cannot cross the triangle (unit: m).
using ObstacleFaceBoxes = std::vector<std::vector<Eigen::AlignedBox3d>>;

/// The boxes of every triangle of `obstacles`, in their order: the visibility tests of the anisotropic
/// kernels (their neighbourhoods here, the node-to-centre segments in reconstruct_surface) skip the faces a
/// segment's box misses.
ObstacleFaceBoxes obstacle_face_boxes(const std::vector<SurfaceObstacle>& obstacles);

/// Whether the segment pq crosses one of the triangles `faces` ((obstacle, triangle) pairs of `obstacles`),
/// as segment_crosses_triangle decides; a face whose box in `boxes` misses the segment's box is skipped
/// without a test.
bool segment_crosses_faces(const Vec3& p, const Vec3& q, const std::vector<std::pair<Index, Index>>& faces,
                           const std::vector<SurfaceObstacle>& obstacles, const ObstacleFaceBoxes& boxes);

/// One ellipsoidal kernel per particle, by particle index.
struct AnisotropicKernels {
  /// N smoothed centres x_i' (unit: m).
  Vec3Array centres;
  /// N matrices G_i (unit: 1/m): the kernel at x is the isotropic one of radius 1 at |G_i (x - x_i')|, so its
  /// support is the ellipsoid |G_i (x - x_i')| < 1.
  std::vector<Eigen::Matrix3d> transforms;
  /// N factors det(G_i) R^3 (R the kernel radius): the kernel's amplitude relative to the isotropic one, so
  /// that every kernel holds the isotropic one's volume.
  std::vector<double> amplitudes;
  /// N longest semi-axes of the supports (unit: m), <= 2 R.
  std::vector<double> reaches;
  std::uint64_t anisotropic = 0;   ///< particles with at least min_neighbours neighbours
  std::uint64_t occluded = 0;      ///< particle-neighbour pairs whose segment crosses a triangle
  std::uint64_t kept_centres = 0;  ///< particles whose smoothed centre would have crossed a triangle
};

/// Yu & Turk 2013 sec. 3-4 for every particle i: its neighbours j within r_i = 2 `radius` weighted by
/// w_ij = 1 - (|x_i - x_j| / r_i)^3, their weighted mean m_i and covariance C_i; the centre
/// x_i' = (1 - lambda) x_i + lambda m_i; C_i = R S R^T (SVD), S's values clamped to at least 1 / k_r of the
/// largest and scaled by k_s / r_i^2 (k_n for fewer than N_eps neighbours, isotropic), at most 2;
/// G_i = (1 / radius) R S^-1 R^T. With `bins` (the triangles of `obstacles`, non-empty), a neighbour whose
/// segment to x_i crosses a triangle is left out, and a centre whose segment from x_i would cross one stays
/// at x_i.
/// @param particles  N positions (unit: m), finite
/// @param radius  the isotropic kernel radius R (unit: m), > 0
/// @param settings  lambda, k_r, k_s, k_n and N_eps (checked by reconstruct_surface)
/// @param bins  the obstacles' triangles, or nullptr for a reconstruction that ignores them
AnisotropicKernels anisotropic_kernels_yu_turk(const Vec3Array& particles, Scalar radius,
                                               const SurfaceSettings& settings,
                                               const std::vector<SurfaceObstacle>& obstacles,
                                               const TriangleBins* bins);

}  // namespace drench
