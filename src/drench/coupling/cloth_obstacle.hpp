#pragma once
/// The cloth as an obstacle inside the fluid's sub-steps: a drench addition to Huber et al. 2013, whose
/// coupling acts once per step. At large steps (a 3 m/s jet moves 2.4 particle spacings per 4 ms step)
/// stopping particles only after the fluid step puts whole layers on top of each other, and the compressed
/// fluid splashes at several times the jet speed. Here, after each fluid sub-step, a particle whose sub-step
/// motion crosses the cloth (at its start-of-step position, static during the fluid step) loses its approach
/// velocity, as the inelastic impulse of eq. 2 would give it, so the fluid's pressure decelerates the
/// particles behind it within the same step. The impulses are kept per cloth node and handed to the cloth
/// before the coupler runs, so momentum is exchanged, not lost.

#include <cstdint>
#include <memory>
#include <vector>

#include <drench/common/effect_counter.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/impulse_link.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench {

class ClothObstacle final : public SubstepConstraint {
 public:
  /// @param thickness  the cloth thickness (unit: m), > 0: a stopped particle that started more than 1% of
  ///        it off the cloth's plane ends no closer than that
  /// @param broad_phase  which broad phase finds the particles near the cloth (kept across steps, so
  ///        FCL's tree is refitted rather than rebuilt)
  /// @param kinematic_cloth  true: particles are stopped against the cloth's start velocity, which their
  ///        impulses do not change within the step (CouplingScheme::CARRIED_WATER: one heavy particle would
  ///        otherwise throw a light node within a single sub-step); false: eq. 2 mass-weighted on both sides
  ClothObstacle(double thickness, BroadPhaseKind broad_phase, bool kinematic_cloth = false);

  /// Starts a step: the cloth's positions_t0 become the obstacle (copied); its inverse masses (unless
  /// kinematic) and triangles are used; `velocities` are the node velocities at the start of the step (unit:
  /// m/s), M entries. Clears the impulses and the counts of the previous step.
  void begin_step(const ClothMesh& cloth, const Vec3Array& velocities);

  /// Stops the particles whose sub-step motion crosses the cloth. When no particle's box over the sub-step
  /// meets the cloth's box, that one test is all it costs (counter().skipped): the broad phase would find no
  /// pair.
  void apply(const Vec3Array& positions_before, ParticleSet& particles, Scalar dt) override;

  /// The impulses the particles gave the cloth in this step, one per node (unit: N s), for
  /// ClothEngine::apply_impulses before the cloth steps.
  const Vec3Array& impulses() const { return m_node_impulses; }

  /// Every stop of this step, in the order made (a particle stopped in several sub-steps appears once per
  /// stop), for CarriedWater::attach.
  const ImpulseLinks& impulse_links() const { return m_impulse_links; }

  /// Particles stopped in this step (summed over its sub-steps).
  std::uint64_t stops() const { return m_stops; }
  /// Sum of the y components of this step's impulses on the cloth (unit: N s).
  double vertical_impulse() const;
  /// Counts over its life, part of the "coupling" effect: constructed 1; a pass per fluid sub-step that
  /// looked for crossings, a skip per sub-step with no particle near the cloth.
  const EffectCounter& counter() const { return m_counter; }

 private:
  ClothMesh m_static;  // the cloth at its start positions, not moving
  Box3 m_box;          // of m_static
  ScalarArray m_inverse_masses;
  double m_thickness;
  bool m_kinematic_cloth;
  Vec3Array m_node_velocities;  // start velocity plus the impulses so far, over the mass
  Vec3Array m_node_impulses;
  ImpulseLinks m_impulse_links;
  std::uint64_t m_stops = 0;
  EffectCounter m_counter;
  std::unique_ptr<TriangleBroadPhase> m_broad_phase;
  std::vector<std::pair<Index, Index>> m_pairs;
};

/// Which straight moves cross a cloth at rest: crosses[k] is 1 when a point moving from from[k] to to[k]
/// passes through or ends on a face of `cloth` at its positions_t0, by the exact CCD of a point against a
/// static triangle (eq. 5-6), else 0. Moves a game makes outside the fluid's step (water moved out of a body
/// that appeared, RigidBodySource::release_trapped) must keep it on its side of the cloth. A move or a face
/// with a non-finite coordinate crosses nothing here (the cloth's and the fluid's own checks report them).
/// One broad-phase pass over all moves, so that many moves against a large cloth cost about one query each.
/// @param cloth  its triangles and positions_t0 (unit: m); positions_t1 is not read
/// @param from, to  N points each (unit: m)
/// @param crosses  output, N flags
void moves_crossing_cloth(const ClothMesh& cloth, const Vec3Array& from, const Vec3Array& to,
                          std::vector<std::uint8_t>& crosses);

}  // namespace drench
