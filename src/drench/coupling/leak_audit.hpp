#pragma once
/// The leak audit: counts particles that cross the cloth during a step, judged on the final motion (start
/// positions to end positions after every correction, linear in between). Independent of the coupler on
/// purpose: its own broad phase, its own floating-point filter with a certified error bound, and the exact
/// rational reference (ccd_exact_reference.hpp) whenever that filter cannot decide. Between the two sits the
/// CCD's certified Bernstein filter (ccd::transversal_crossing, checked against the exact reference by its
/// own tests): a pair it decides costs about 1/40 of the exact reference's instructions (issue 41).

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <drench/common/cell_lists.hpp>
#include <drench/common/types.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_mesh.hpp>

namespace drench {

struct LeakAuditStats {
  std::uint64_t leaks = 0;  ///< particles that crossed a triangle (each at most once per step)
  /// Of `leaks`: particles a face crossed between two steps (audit_face_jumps), as where a rigid impact zone
  /// had moved a body's face and the next step started from where its engine holds it.
  std::uint64_t jump_leaks = 0;
  std::uint64_t pairs = 0;         ///< particle-triangle pairs whose swept boxes overlap
  std::uint64_t exact_checks = 0;  ///< pairs the filters left to the exact reference
  double seconds = 0.0;            ///< wall time (unit: s)
  /// A leak of the latest step that had any: the particle of lowest index in that step's arrays and a
  /// triangle it crossed; -1 while none leaked.
  std::int64_t leak_particle = -1;
  std::int64_t leak_triangle = -1;
};

/// The leak audit of a run, step after step: audit_leaks with its grid of triangles kept from one step to the
/// next. Only the triangles whose swept box now covers other cells than those they are filed in are filed
/// again: in a game's level most never move (the ground's 3,200 faces, a table), a cloth's move by a small
/// part of a cell per step, and filing every face afresh each step was most of the audit's time (issue 41's
/// profile); the filing is then the one a fresh grid of the same cell would make. The grid's cell, the median
/// triangle's box size as in audit_leaks, is kept while that median stays within a factor 2 of it; the cell
/// decides only how fast pairs are found, and which triangle is named when a particle crosses several, never
/// whether it leaked.
namespace leak_audit_detail {
/// A swept box (unit: m).
struct Bounds {
  Vec3 lo, hi;
};
/// The grid cells a box covers, [lo, hi] per axis (integer coordinates as doubles).
struct CellRange {
  Eigen::Array3d lo = Eigen::Array3d::Zero(), hi = Eigen::Array3d::Zero();
};
}  // namespace leak_audit_detail

class LeakAudit {
 public:
  /// As audit_leaks, which it is with the grid of the last call kept.
  std::uint64_t audit(const Vec3Array& particles_t0, const Vec3Array& particles_t1, const ClothMesh& cloth,
                      LeakAuditStats& stats, std::vector<std::uint8_t>* leaked = nullptr);

 private:
  using Bounds = leak_audit_detail::Bounds;
  using CellRange = leak_audit_detail::CellRange;
  /// Brings the grid to `cloth`'s swept triangle boxes.
  void update_grid(const ClothMesh& cloth);
  /// The cells of the grid that `box` covers.
  CellRange cell_range(const Bounds& box) const;
  /// Files triangle t in the cells of `range`, or with the oversized ones when they are over 4,096.
  void file(Index t, const CellRange& range);
  /// Takes triangle t out of where file(t, range) put it.
  void unfile(Index t, const CellRange& range);
  /// Moves triangle t from where file(t, from) put it to where file(t, to) would, touching only the cells in
  /// one range and not the other: a box sliding into the next cells keeps most of its cells, and the lists
  /// (ascending) come out the same as unfile then file would leave them.
  void refile(Index t, const CellRange& from, const CellRange& to);
  /// True when `range` is over 4,096 cells or not finite: its triangle is tested by every particle.
  static bool oversized(const CellRange& range);
  /// The median of m_sizes (non-empty), raised to 1e-9 m (also a NaN median): the grid's cell (unit: m).
  double median_size();
  /// Where a box size lies against the cell: below half of it, within [half, twice], above, or a NaN.
  int size_class(double size) const;
  enum : int { kSmaller = 0, kWithin = 1, kLarger = 2, kUnordered = 3 };

  double m_cell = 0.0;                     // edge of the grid's cells (unit: m)
  TriangleBoxKey m_built_for;              // the mesh the grid was last brought to
  std::vector<std::uint8_t> m_moved;       // scratch: the nodes moved since then
  std::vector<std::uint8_t> m_face_moved;  // scratch: the triangles with such a node
  std::vector<Bounds> m_boxes;             // per triangle, its swept box
  std::vector<double> m_sizes;             // per triangle, its box's largest extent (unit: m)
  std::vector<double> m_median_scratch;    // scratch: m_sizes, partly sorted for the median
  std::vector<CellRange> m_ranges;         // per triangle, the cells it is filed in
  CellLists<Index> m_grid;                 // each cell key's triangles, ascending
  std::vector<Index> m_oversized;          // triangles over 4,096 cells, ascending: every particle's
  // How many of m_sizes have each size_class at m_cell.
  std::array<std::size_t, 4> m_size_classes{};
};

/// A leak is a transversal crossing: at some time of the step the particle lies in a closed triangle and its
/// side of that triangle (the sign of the signed volume, eq. 6) differs just before and just after. Touching
/// and returning is not a leak; how deep inside the cloth thickness a particle goes does not matter. A
/// LeakAudit kept over the steps of a run gives the same counts at less cost.
/// @param particles_t0, particles_t1  N particle positions at the start and the end of the step (unit: m)
/// @param cloth  final node positions at the start and end of the step
/// @param leaked  optional output, N flags set for the particles that leaked
/// @param stats  adds pairs, exact checks, leaks and time; names this step's first leak, if any, in
///        leak_particle and leak_triangle
/// @return the number of particles that leaked in this step
std::uint64_t audit_leaks(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                          const ClothMesh& cloth, LeakAuditStats& stats,
                          std::vector<std::uint8_t>* leaked = nullptr);

/// The audit of what happens to the faces between two steps: each face moves from where the last audited
/// step left it to where the next step starts it, the particles stay still, and a particle a face crosses
/// (audit_leaks' transversal crossing, exactly as within a step) has leaked. A face's engine may start it
/// elsewhere than the coupler left it: a rigid body's engine ignores what an impact zone did to its nodes
/// (CouplingStepStats::zone_ignored_shift), and so does a cloth's for its pinned nodes; the water placed
/// against the moved face would then be inside the body, crossing nothing within either step. Only the
/// faces with a node that moved are examined, so a run whose faces start where they ended pays one pass
/// over the nodes.
/// @param particles  N particle positions between the steps (unit: m)
/// @param triangles  F triangles, node indices < M
/// @param end  M node positions where the last audited step ended (unit: m)
/// @param start  M node positions where the next step starts (unit: m)
/// @param stats  adds leaks (and jump_leaks), pairs, exact checks and time; names this call's first leak,
///        if any, in leak_particle and leak_triangle (an index into `triangles`)
/// @param leaked  optional output, N flags set for the particles that leaked
/// @return the number of particles a face crossed
/// @throws std::invalid_argument when `end` and `start` differ in size
std::uint64_t audit_face_jumps(const Vec3Array& particles, const std::vector<Triangle>& triangles,
                               const Vec3Array& end, const Vec3Array& start, LeakAuditStats& stats,
                               std::vector<std::uint8_t>* leaked = nullptr);

}  // namespace drench
