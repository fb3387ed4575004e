#pragma once
/// The fluid's surface as a triangle mesh (Huber et al. 2013 sec. 4): a Zhu & Bridson 2005 scalar field on
/// the grid nodes within reach of a particle, made contact-aware by a visibility criterion (Fig. 2a) and a
/// node reset near every triangle of the cloth and obstacles (Fig. 2b), then meshed by OpenVDB's
/// volumeToMesh (marching cubes over the sparse grid).

#include <cstdint>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/surface/surface_settings.hpp>

namespace drench {

/// A triangle soup the surface must respect: M node positions and F triangles (indices < M), at the time of
/// the particles (unit: m). Borrowed, not owned.
struct SurfaceObstacle {
  const Vec3Array* positions = nullptr;
  const std::vector<Triangle>* triangles = nullptr;
};

/// A reconstructed surface: V vertices with unit normals pointing out of the fluid, T triangles whose
/// corners run counter-clockwise seen from outside (unit: m).
struct SurfaceMesh {
  Vec3Array positions;              ///< V vertices (unit: m)
  Vec3Array normals;                ///< V unit normals, out of the fluid
  std::vector<Triangle> triangles;  ///< T, indices < V
};

/// What one reconstruction did.
struct SurfaceStats {
  std::uint64_t nodes = 0;     ///< grid nodes given a field value
  std::uint64_t occluded = 0;  ///< node-particle pairs whose segment crossed a triangle (Fig. 2a)
  /// Nodes set outside for being within contact_offset of a face (Fig. 2b); of the anisotropic kernels'
  /// field, only nodes some kernel's support holds (the others are outside anyway, and not tested).
  std::uint64_t reset_nodes = 0;
  std::uint64_t anisotropic = 0;  ///< particles given an anisotropic kernel (kernel ANISOTROPIC)
  double seconds = 0.0;           ///< wall time (unit: s)
  /// Wall time of the stages within `seconds` (unit: s), to see where a reconstruction's time goes
  /// (bench_surface): activating the grid's nodes around the particles and listing them; sorting the
  /// particles into cells and their inverse number densities (and the obstacles' triangles into bins); the
  /// field at every node, visibility and reset included; marching cubes and the vertex normals. Before them,
  /// the anisotropic kernels (0 for the isotropic ones).
  double seconds_kernels = 0.0;
  double seconds_grid = 0.0;
  double seconds_densities = 0.0;
  double seconds_field = 0.0;
  double seconds_mesh = 0.0;
};

/// Reconstructs the surface of `particles` (N positions, unit: m; all finite) sampled at `particle_spacing`
/// (m, > 0). With settings.contact_aware, the triangles of `obstacles` occlude particles and push the surface
/// off their faces. Deterministic: the same input gives the same mesh for any thread count.
/// @throws SceneError when the cell size, the offset or the spacing is not positive and finite, a particle
///         or an obstacle node is not finite (naming its index), or an obstacle triangle names a node out of
///         range.
/// An empty `particles` gives an empty mesh.
SurfaceMesh reconstruct_surface(const Vec3Array& particles, Scalar particle_spacing,
                                const SurfaceSettings& settings,
                                const std::vector<SurfaceObstacle>& obstacles, SurfaceStats* stats = nullptr);

/// Number of (surface triangle, obstacle triangle) pairs that share a point (closed triangles: touching
/// counts). Independent of how the surface was made, so it measures the claim of sec. 4 (0 for a
/// contact-aware surface). Decided exactly (ccd/exact_predicates.hpp); candidates from a grid of triangle
/// boxes.
std::uint64_t count_surface_intersections(const SurfaceMesh& surface,
                                          const std::vector<SurfaceObstacle>& obstacles);

}  // namespace drench
