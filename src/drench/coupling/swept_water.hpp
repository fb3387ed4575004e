#pragma once
/// A dynamic body's mass against the water it sweeps. The coupler (Huber et al. 2013 sec. 3) sees a rigid
/// body's nodes with inverse mass 0: within the step the body moves as its engine moved it, every particle it
/// meets is stopped against it as against a wall (eq. 2 without the body's term), and the body takes the sum
/// afterwards. For a body far heavier than the water it sweeps, that is eq. 2; for a light one it is not: a
/// 4 cm cube of 100 kg/m^3 falling at 1.3 m/s into a tank stopped 0.036 N s of water, six times its momentum,
/// and was thrown back out at 5.5 m/s (RigidBodies.ALightBodyFallingIntoWaterFloats).

#include <cstddef>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/coupling/rigid_bodies.hpp>

namespace drench {

/// Before the fluid and the bodies move in a step: each dynamic body with a mass (RigidSurface::
/// inverse_mass > 0) and the water its translation over the step would sweep meet in one inelastic
/// collision, eq. 2 with both masses, as a lump: body and swept particles take their common velocity
/// V' = (M V + sum m_p v_p) / (M + sum m_p). A particle is swept when a face, moved by V dt, meets it moving
/// by its own v dt (the exact CCD, eq. 5-6). The body takes the water's impulses at its centre, so the
/// collision only loses energy; its spin is left to the coupler. For a body far heavier than the water it
/// can sweep, V' is V to within a tenth of what the coupler's stops take from it, and it is left to them.
/// Linear momentum is conserved exactly between the water and a free body; a body a joint, a contact or a
/// locked axis holds gives part of its share to what holds it, as it does the coupler's.
/// @param surfaces  the step's rigid surfaces at its start, in mesh order: positions_t0, velocities_t0,
///        inverse_mass, velocity and centre; a swept body's velocity and velocities_t0 become V' (plus its
///        spin), so that the rest of the step sees it as it will move
/// @param first_node  per surface, its first node in the mesh (ClothWithObstacles::rigid_surface_first_nodes)
/// @param node_count  the mesh's nodes
/// @param dt  the step (unit: s), > 0
/// @param rest_density  the water's (unit: kg/m^3): what a body's faces can sweep holds at most that
/// @param positions  N particle positions (unit: m); masses N (unit: kg, > 0)
/// @param velocities  N particle velocities (unit: m/s): a swept particle's becomes V'; a particle whose
///        position or velocity is not finite is never swept
/// @param node_impulses  output: empty when no body took an impulse, else one per mesh node (unit: N s),
///        each body's at its nodes with no torque about its centre, for RigidBodySource::apply_impulses
///        before its engine's step
/// @return how many particles were swept
/// @throws std::invalid_argument when the sizes disagree or a surface's nodes run past node_count
std::size_t meet_swept_water(std::vector<RigidSurface>& surfaces, const std::vector<std::size_t>& first_node,
                             std::size_t node_count, double dt, double rest_density,
                             const Vec3Array& positions, const ScalarArray& masses, Vec3Array& velocities,
                             Vec3Array& node_impulses);

}  // namespace drench
