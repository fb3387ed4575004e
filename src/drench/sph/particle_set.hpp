#pragma once
/// Fluid particles stored as a structure of arrays.

#include <cstdint>

#include <drench/common/types.hpp>

namespace drench {

/// Structure of arrays of N particles. Every array has N entries; entry i of each array belongs to the same
/// particle. Arrays are re-ordered (z-order sorting) and compacted (removal) together; `ids` stay with their
/// particle for its whole life and are never reused.
struct ParticleSet {
  Vec3Array positions;             ///< N (unit: m)
  Vec3Array velocities;            ///< N (unit: m/s)
  ScalarArray densities;           ///< N (unit: kg/m^3), from the last density evaluation
  ScalarArray pressures;           ///< N (unit: Pa), from the last pressure solve
  ScalarArray masses;              ///< N (unit: kg), > 0
  std::vector<std::uint32_t> ids;  ///< N, unique, stable
  /// N, positions at the start of the current step (unit: m): set by FluidSolver::step, read by the coupling
  /// (Huber et al. 2013 sec. 5 needs start and end positions). Kept here so sorting keeps it aligned.
  Vec3Array positions_t0;

  std::size_t size() const { return positions.size(); }
  bool empty() const { return positions.empty(); }

  /// Appends one particle with density and pressure zero. `id` must not be used by another particle.
  void add(const Vec3& position, const Vec3& velocity, Scalar mass, std::uint32_t id);

  /// Re-orders every array so that new entry k is old entry order[k]. `order` is a permutation of 0..N-1.
  void permute(const IndexArray& order);

  /// Removes the particles with remove[i] != 0, keeping the others in their order. Returns how many went.
  std::size_t remove_flagged(const std::vector<std::uint8_t>& remove);

  void reserve(std::size_t n);

  /// The mass every particle has (unit: kg), or 0 when the masses differ or there are no particles.
  Scalar common_mass() const;
};

}  // namespace drench
