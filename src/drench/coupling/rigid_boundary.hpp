#pragma once
/// Boundary particles on the surfaces of dynamic rigid bodies (Akinci et al. 2012, "Versatile rigid-fluid
/// coupling for incompressible SPH"), beside the coupling's impulses: the impulses keep the water out (eq.
/// 1-6, no leaks at any step), the boundary particles give the water next to a body its full density, so that
/// its pressure there is the hydrostatic one and the body floats by Archimedes. Without them the water under
/// a body lacks neighbours and is compressed as at a free surface, so bodies float far too deep
/// (test RigidBodies.ABallOfHalfTheWatersDensityFloatsHalfSubmergedAtTwoSpacings).

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/coupling/rigid_bodies.hpp>

namespace drench {

/// The most boundary samples one dynamic body may take (about 100 bytes each with their neighbor lists):
/// a 2 m box at 5 mm particles takes about 2.2 million.
inline constexpr double kMaxSamplesPerBody = 4e6;

/// The boundary particles of every dynamic body of a step, laid out body after body.
class RigidBoundary {
 public:
  /// @param spacing  the fluid's particle spacing (unit: m), > 0: the samples' spacing, their inset and the
  ///        kernel of their volumes
  explicit RigidBoundary(Scalar spacing);

  /// The samples of every DYNAMIC surface at its positions_t0: on each face, the centroids of its
  /// sub-triangles of about the spacing (similar to the face, or for a sliver rows of pieces across it, a
  /// spacing apart; inside the face, none on its edges or corners, so that each pushes
  /// along its own face's normal), set inside the body by inset() so that the water's volume ends at the
  /// face, with Akinci et al. 2012 eq. 4's volume V_b = 1 / sum_k W_bk over the body's own samples. A body
  /// seen for the first time (or whose mesh changed) is sampled now; its samples are kept by key, in
  /// barycentric weights, since the body is rigid. Static and kinematic surfaces have none.
  /// A body whose positions_t0 are those of its last placing keeps its placed samples: a body at rest (a
  /// crate on a table, a sleeping ball) costs nothing, and the points are the same bits either way.
  /// @return true when positions(), volumes() or normals() changed: a body moved, came or went
  /// @throws Error when a body to sample would take more than kMaxSamplesPerBody samples
  bool place(const std::vector<RigidSurface>& surfaces);

  /// The samples of the last place(), body after body: B points (unit: m), their volumes (unit: m^3) and the
  /// outward unit normals of their faces.
  const Vec3Array& positions() const { return m_positions; }
  const ScalarArray& volumes() const { return m_volumes; }
  const Vec3Array& normals() const { return m_normals; }

  /// How far the samples sit inside the faces (unit: m): where a resting fluid's first layer, next to a plane
  /// of such samples, has the rest density, less half a spacing (0.60 spacings for the cubic spline). Where
  /// the body is thinner than twice this behind a sample (a plank, a small cube), the sample sits half way
  /// through it instead: deeper, it would stand outside the opposite face. Such a part displaces more water
  /// than its volume: the water rests (0.6 spacings - half its thickness) off each face, so a 2 mm plank at
  /// 1 cm particles displaces like a 12 mm slab.
  Scalar inset() const { return m_inset; }

  /// Adds the impulses on the samples of the last place() (B entries, unit: N s) to the nodes of their faces
  /// by the samples' barycentric weights: node_impulses[first_node[s] + node] for surface s. Samples with a
  /// zero impulse (those no water reached) are skipped: the same bits but for a node holding -0.
  void spread(const std::vector<RigidSurface>& surfaces, const Vec3Array& sample_impulses,
              const std::vector<std::size_t>& first_node, Vec3Array& node_impulses) const;

 private:
  struct Sample {
    Index triangle;
    Vec3 weights;
    Scalar volume;
    Scalar inset;  // how far inside its face (unit: m): inset(), or less in a thin part (sample())
  };
  struct Body {
    std::size_t nodes = 0, triangles = 0;
    std::uint64_t instance = 0;  // RigidSurface::instance it was sampled for
    std::vector<Sample> samples;
    Vec3Array placed_at;  // the positions_t0 of its last placing (unit: m); empty before the first
  };
  Body sample(const RigidSurface& surface) const;
  /// Places body's samples at surface.positions_t0 into m_positions and m_normals from index `first`.
  void place_samples(const RigidSurface& surface, const Body& body, std::size_t first);

  Scalar m_spacing;
  Scalar m_inset;
  std::unordered_map<std::uint64_t, Body> m_bodies;
  std::vector<Body*> m_placed;               // per surface of the last place(), null when not dynamic
  Vec3Array m_face_normals;                  // place(): scratch, the outward normals of one surface's faces
  std::vector<std::uint64_t> m_placed_keys;  // the keys of the bodies of m_positions, in order
  Vec3Array m_positions;                     // the last place()'s samples, body after body (unit: m)
  ScalarArray m_volumes;                     // their volumes (unit: m^3)
  Vec3Array m_normals;                       // their faces' outward unit normals
};

}  // namespace drench
