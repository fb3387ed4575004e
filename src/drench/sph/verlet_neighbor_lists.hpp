#pragma once
/// The fluid's neighbor lists, reused over several sub-steps (Verlet lists with a skin).

#include <cstdint>

#include <drench/common/types.hpp>
#include <drench/sph/cubic_spline_kernel.hpp>
#include <drench/sph/neighbor_search.hpp>

namespace drench {

/// Neighbor lists of the fluid particles (fluid -> fluid, self excluded; fluid -> static boundary points),
/// rebuilt on the uniform grid only when needed. A rebuild with skin s > 0 searches to support + s and keeps
/// those candidates; later updates reuse them while no particle has moved more than s / 2 since the rebuild:
/// two points that each moved less than s / 2 cannot have come within the support without having been within
/// support + s (Verlet 1967; boundary points do not move). Every update filters the candidates to distance <
/// support with the same arithmetic as NeighborSearch::find, so callers get exactly the neighbor sets of a
/// fresh search, in a deterministic order (candidates' order: by cell at the rebuild, then by index).
///
/// Why: WCSPH takes many short sub-steps (its sound speed bounds them), in which particles move a few
/// hundredths of a spacing, and a fresh grid search every sub-step was 60% of its time (bench_dam_break
/// wcsph_59k).
class VerletNeighborLists {
 public:
  /// @param kernel  the SPH kernel, copied: its support is the neighbor radius
  /// @param max_skin  the largest skin update() will be given (unit: m), >= 0; sets the rebuild grid's cells
  /// @param boundary  static boundary points (unit: m, finite), kept
  VerletNeighborLists(const CubicSplineKernel& kernel, Scalar max_skin, Vec3Array boundary);

  /// Brings fluid() and boundary() up to date for `positions`.
  /// @param positions  N particle positions (unit: m, finite)
  /// @param ids  N stable particle ids: any difference from those of the last rebuild (particles emitted,
  ///             removed or re-sorted) forces a rebuild
  /// @param skin  (unit: m), in [0, max_skin]: the skin of a rebuild made by this call. With 0 the search
  ///              goes exactly to the support and keeps no candidates, so the next update rebuilds again.
  /// @return true when the grid search ran
  bool update(const Vec3Array& positions, const std::vector<std::uint32_t>& ids, Scalar skin);

  /// Replaces the boundary points from index `first` on with `points` (unit: m, finite), e.g. with the moving
  /// bodies' at the start of a fluid step, keeping the first `first`; the next update() searches afresh.
  /// Written in place, as a game's bodies move every frame: no new array per call, and the kept points (a
  /// scene's walls, thousands) are not copied again.
  /// @param first  <= boundary_points().size()
  /// @param points  not boundary_points() itself
  void set_boundary_points(std::size_t first, const Vec3Array& points);
  /// Makes the next update() search afresh, keeping the boundary points and their grid: what
  /// set_boundary_points does for points that did not change.
  void search_afresh() { m_skin = 0.0; }

  /// Whether update() takes fluid_gradient_factors() (default true). Off, they stay empty: PBF takes the
  /// kernel's gradients at its iterations' positions, so without surface tension no one reads them, and they
  /// were 1% of issue 41's level (callgrind).
  void set_fluid_gradient_factors(bool wanted) { m_want_fluid_factors = wanted; }

  const NeighborList& fluid() const { return m_fluid; }
  const NeighborList& boundary() const { return m_boundary; }
  /// The boundary points: given at construction, or by the last set_boundary_points (unit: m).
  const Vec3Array& boundary_points() const { return m_boundary_points; }
  /// For every entry of fluid().indices, f with grad W(x_i - x_j) = f (x_i - x_j) at the positions of the
  /// last update (unit: 1/m^5), rounded to float (GradientFactorArray); empty when set_fluid_gradient_factors
  /// turned them off. Computed in the filter's pass, where
  /// the distance is at hand: a pass of its own re-read the lists and gathered the positions again, on a
  /// sub-step bound by memory traffic.
  const GradientFactorArray& fluid_gradient_factors() const { return m_fluid_factors; }
  /// The same for boundary().indices, with the boundary point in place of x_j (unit: 1/m^5).
  const GradientFactorArray& boundary_gradient_factors() const { return m_boundary_factors; }

  /// Permutation that orders `points` along the z-order curve of support-sized cells
  /// (NeighborSearch::z_order).
  IndexArray z_order(const Vec3Array& points) const { return m_exact_fluid.z_order(points); }

 private:
  /// True when some particle moved more than skin / 2 since the rebuild.
  bool moved_beyond_half_skin(const Vec3Array& positions) const;
  /// out = the candidates within the support, out_factors their kernel gradient factors (left empty when not
  /// `factors`): queries `x`, sources `sources`.
  void filter(const NeighborList& candidates, const Vec3Array& x, const Vec3Array& sources, NeighborList& out,
              GradientFactorArray& out_factors, bool factors = true);
  /// out_factors = the kernel gradient factors of the pairs of `list` (all within the support).
  void gradient_factors(const NeighborList& list, const Vec3Array& x, const Vec3Array& sources,
                        GradientFactorArray& out_factors) const;

  CubicSplineKernel m_kernel;  // a copy: a reference into the owner would dangle when the owner is moved
  Scalar m_support;
  Vec3Array m_boundary_points;
  bool m_want_fluid_factors = true;    // set_fluid_gradient_factors
  NeighborSearch m_exact_fluid;        // cells of the support: rebuilds without a skin, and z_order
  NeighborSearch m_exact_boundary;     // built once
  NeighborSearch m_wide_fluid;         // cells of support + max_skin
  NeighborSearch m_wide_boundary;      // built for the boundary points when a rebuild with a skin needs it
  bool m_wide_boundary_built = false;  // m_wide_boundary holds m_boundary_points
  Scalar m_skin = 0.0;                 // of the last rebuild (unit: m); 0: no candidates are kept
  std::vector<std::uint32_t> m_ids;    // at the last rebuild with a skin
  Vec3Array m_positions;               // at the last rebuild with a skin (unit: m)
  NeighborList m_fluid_candidates;
  NeighborList m_boundary_candidates;
  NeighborList m_fluid;
  NeighborList m_boundary;
  GradientFactorArray m_fluid_factors;
  GradientFactorArray m_boundary_factors;
  IndexArray m_kept;      // filter(): kept indices at their candidates' offsets
  ScalarArray m_kept_r2;  // filter(): their squared distances
};

}  // namespace drench
