#pragma once
/// The leak audit: counts particles that cross the cloth during a step, judged on the final motion (start
/// positions to end positions after every correction, linear in between). Independent of the coupler on
/// purpose: its own broad phase, its own floating-point filter with a certified error bound, and the exact
/// rational reference (ccd_exact_reference.hpp) whenever that filter cannot decide.

#include <cstdint>

#include <drench/common/types.hpp>
#include <drench/coupling/cloth_mesh.hpp>

namespace drench {

struct LeakAuditStats {
  std::uint64_t leaks = 0;         ///< particles that crossed a triangle (each at most once per step)
  std::uint64_t pairs = 0;         ///< particle-triangle pairs whose swept boxes overlap
  std::uint64_t exact_checks = 0;  ///< pairs the filter left to the exact reference
  double seconds = 0.0;            ///< wall time (unit: s)
  /// A leak of the latest step that had any: the particle of lowest index in that step's arrays and a
  /// triangle it crossed; -1 while none leaked.
  std::int64_t leak_particle = -1;
  std::int64_t leak_triangle = -1;
};

/// A leak is a transversal crossing: at some time of the step the particle lies in a closed triangle and its
/// side of that triangle (the sign of the signed volume, eq. 6) differs just before and just after. Touching
/// and returning is not a leak; how deep inside the cloth thickness a particle goes does not matter.
/// @param particles_t0, particles_t1  N particle positions at the start and the end of the step (unit: m)
/// @param cloth  final node positions at the start and end of the step
/// @param leaked  optional output, N flags set for the particles that leaked
/// @param stats  adds pairs, exact checks, leaks and time; names this step's first leak, if any, in
///        leak_particle and leak_triangle
/// @return the number of particles that leaked in this step
std::uint64_t audit_leaks(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                          const ClothMesh& cloth, LeakAuditStats& stats,
                          std::vector<std::uint8_t>* leaked = nullptr);

}  // namespace drench
