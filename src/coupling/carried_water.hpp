#pragma once
/// Water resting on the cloth moves with it through the cloth engine's step: a drench addition to Huber et
/// al. 2013, part of CouplingScheme::CARRIED_WATER. The paper steps fluid and cloth apart and couples them by
/// impulses afterwards (sec. 5). With a light cloth under heavy water (the paper's Fig. 3 cloth: 4.1e-5 kg
/// per node of the 57 x 57 patch, a 5 mm particle 1.25e-4 kg) that splitting is unstable on a position-based
/// cloth (the added-mass instability of partitioned fluid-structure coupling): the coupling moves a wet node
/// with its water, the cloth's links snap it back at tens of m/s, and the oscillation grows every step.
/// Here, for the cloth's step only, each node weighs its own mass plus the water resting on it, so the
/// links accelerate node and water together; afterwards the water gets its share of what the links did.
///
/// Per step: attach() after the fluid step, ClothEngine::set_carried_masses(carried_masses()), the impulses
/// and the engine's step, then hand_back().

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "common/types.hpp"
#include "coupling/broad_phase.hpp"
#include "coupling/cloth_mesh.hpp"

namespace drench {

class CarriedWater {
 public:
  /// @param carry_distance  a particle within this distance (unit: m, > 0) of the cloth is carried by its
  ///        closest triangle. drench uses cloth thickness + half a particle spacing: the water's bottom
  ///        layer, which rests about one thickness above the cloth.
  /// @param broad_phase  which broad phase finds the particles near the cloth (kept across steps)
  CarriedWater(double carry_distance, BroadPhaseKind broad_phase);
  /// As above with a broad phase shared with the sub-step obstacle (ClothObstacle), which queries the same
  /// start-of-step cloth: one refit of its triangle boxes per step serves both. @param broad_phase not null
  CarriedWater(double carry_distance, std::shared_ptr<TriangleBroadPhase> broad_phase);
  ~CarriedWater();
  CarriedWater(const CarriedWater&) = delete;
  CarriedWater& operator=(const CarriedWater&) = delete;

  /// Finds the carried particles: every particle within the carry distance of the cloth at its start
  /// positions (positions_t0), with the barycentric weights of its closest point on the closest triangle
  /// (the first in triangle order when two are equally close). Only nodes with inverse mass > 0 carry water;
  /// a particle whose closest point has weight only on pinned nodes is not carried.
  /// @param cloth  validated mesh (positions_t0, inverse masses, triangles)
  /// @param positions  N particle positions (unit: m)
  /// @param masses  N particle masses (unit: kg), > 0
  void attach(const ClothMesh& cloth, const Vec3Array& positions, const ScalarArray& masses);

  /// Carried mass per node after attach() (unit: kg), M entries: the sum over carried particles of weight
  /// times mass.
  const ScalarArray& carried_masses() const { return m_carried; }
  /// Particles carried in this step.
  std::size_t carried_count() const { return m_links.size(); }

  /// Gives the carried particles their share of what happened to node and water together in the engine's
  /// step: particle p on triangle (i, j, k) with weights w gets dv = sum over its nodes with inverse mass > 0
  /// of w_i (v_end_i - v_before_i), on its velocity and on its position (dv dt). The engine moved node i as
  /// mass m_i + carried_i, and the water holds carried_i (v_end_i - v_before_i) of that momentum change;
  /// handing exactly that to the particles that make up carried_i conserves linear momentum (up to rounding).
  /// The water's gravity is the fluid's: the caller removes it from the engine's step (an impulse of
  /// -carried_i g dt per node), and the particles' share of that removal comes back to them here.
  /// @param velocities_before  M node velocities at the start of the step, before any of its impulses (m/s)
  /// @param velocities_end  M node velocities after the engine's step (unit: m/s)
  /// @param cloth  the mesh attach() saw (triangles, inverse masses)
  /// @param dt  the step (unit: s), > 0
  /// @param positions, particle_velocities  N particle positions (m) and velocities (m/s), changed
  /// @param masses  N (unit: kg)
  /// @return the total impulse the particles received (unit: N s)
  Vec3 hand_back(const Vec3Array& velocities_before, const Vec3Array& velocities_end, const ClothMesh& cloth,
                 double dt, Vec3Array& positions, Vec3Array& particle_velocities,
                 const ScalarArray& masses) const;

 private:
  struct Link {
    Index particle;
    Index triangle;
    Vec3 weights;
  };
  double m_distance;
  std::shared_ptr<TriangleBroadPhase> m_broad_phase;
  ClothMesh m_static;  // the cloth at its start positions, not moving (what the broad phase sees)
  std::vector<std::pair<Index, Index>> m_pairs;
  std::vector<Link> m_links;
  ScalarArray m_carried;
};

}  // namespace drench
