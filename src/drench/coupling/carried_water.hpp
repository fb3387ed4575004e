#pragma once
/// Water in contact with the cloth moves with it through the cloth engine's step: a drench addition to Huber
/// et al. 2013, part of CouplingScheme::CARRIED_WATER. The paper steps fluid and cloth apart and couples them
/// by impulses afterwards (sec. 5). With a light cloth under heavy water (the paper's Fig. 3 cloth: 4.1e-5 kg
/// per node of the 57 x 57 patch, a 5 mm particle 1.25e-4 kg) that splitting is unstable on a position-based
/// cloth (the added-mass instability of partitioned fluid-structure coupling): the coupling moves a wet node
/// with its water, the cloth's links snap it back at tens of m/s, and the oscillation grows every step.
/// Here the particles see the cloth as kinematic (they are stopped against it in full), and the cloth takes
/// their impulses at its next step with those particles' mass on its nodes: node and water then share each
/// impulse as eq. 2 between them would, and the links accelerate both together; afterwards the water gets its
/// share of what the links did.
///
/// What is carried is the contact set: the particles whose impulse the cloth takes in this step (the
/// coupler's of the previous step, the sub-step obstacle's of this one). Water that is only near the cloth
/// is not: carried, it would lend a node its mass at the node's velocity, not its own, and a node moving
/// through water would push its neighbours with momentum no water has (a cloth swinging through a pool:
/// tests/bullet_adapter/test_jet_on_cloth.cpp, ClothSwingingThroughAPool, bounds its nodes' speed).
///
/// Per step: attach() after the fluid step, ClothEngine::set_carried_masses(carried_masses()), the impulses
/// and the engine's step, then hand_back().

#include <cstdint>
#include <vector>

#include <drench/common/key_index_table.hpp>
#include <drench/common/types.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/impulse_link.hpp>

namespace drench {

class CarriedWater {
 public:
  /// Carries every particle of `links` by its link's triangle and weights (the largest impulse when a
  /// particle has several), on the nodes with inverse mass > 0 and weight > 0; a particle whose link weighs
  /// only on pinned nodes is not carried. Links to particles not present (removed by a kill region) or to
  /// triangles out of range (the mesh changed) are ignored: their impulse meets the bare node.
  /// @param cloth  validated mesh (inverse masses, triangles)
  /// @param masses  N particle masses (unit: kg), > 0
  /// @param ids  N particle ids (ParticleSet::ids), unique
  /// @param links  in any order, repeats allowed
  void attach(const ClothMesh& cloth, const ScalarArray& masses, const std::vector<std::uint32_t>& ids,
              const ImpulseLinks& links);

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
  std::vector<Link> m_links;
  ScalarArray m_carried;
  KeyIndexTable m_ids;                     // scratch of attach: each particle id's index
  std::vector<const ImpulseLink*> m_best;  // scratch of attach: N, each particle's link, null none
};

/// Settles what the coupler's impact zones did to a carried-water cloth (the last resort of sec. 3.3's
/// continuous handling, continuous_handling.cpp). The coupler sees the cloth's nodes as kinematic, so a zone
/// that holds water caught between the cloth and another face moves those nodes off their end positions
/// (Coupler::node_shifts) without an impulse; the engine's end_step then gives node i the velocity shift_i /
/// dt, momentum that neither the water nor a body gave. Owing node i -shift_i / (im_i dt) at its next step,
/// as every other impulse of the scheme is owed, cancels it: the node keeps the corrected position, and
/// water, cloth and bodies keep their momentum. A node of own inverse mass 0 (a pin, a body's, an
/// obstacle's) is not moved by its engine, so nothing is owed for it.
/// @param shifts  M node shifts (unit: m), Coupler::node_shifts
/// @param inverse_masses  M own inverse masses as the engine holds them (unit: 1/kg), >= 0
/// @param dt  the step (unit: s), > 0
/// @param owed  M impulses owed to the nodes at their next step (unit: N s), added to
/// @param stats  adds sum |shift_i / (im_i dt)| to zone_cloth_momentum, and sum |shift_i| over the nodes of
///        inverse mass 0 to zone_ignored_shift
void owe_zone_shifts(const Vec3Array& shifts, const ScalarArray& inverse_masses, double dt, Vec3Array& owed,
                     CouplingStepStats& stats);

}  // namespace drench
