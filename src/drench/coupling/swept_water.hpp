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
/// inverse_mass > 0) and the water its motion over the step would sweep meet in one inelastic collision, eq.
/// 2 with both masses, as a lump: body and swept particles take their common velocity
/// V' = (M V + sum m_p v_p) / (M + sum m_p). A particle is swept when the body's faces, moved by their node
/// velocities over dt, meet it where it stands (the exact CCD, eq. 5-6). For a body far heavier than the
/// water it sweeps V' is V, and that water takes the body's velocity before the fluid's step rather than from
/// the coupler after it. Each particle's impulse m_p (V' - v_p) reaches the body, opposite, at the nodes of
/// the face it met, by the weights there. Linear momentum is conserved exactly; the body's spin is left to
/// the coupler (a share of the faces' point velocities along their normals let a light cube's spin grow to
/// 35 rad/s and its water sink it: the common velocity also drags the water along the faces, which damps it).
/// The coupler still holds the water out of the bodies where their engine then moves them.
/// @param surfaces  the step's rigid surfaces at its start: positions_t0, velocities_t0, inverse_mass and
///        velocity
/// @param first_node  per surface, its first node in the mesh (ClothWithObstacles::rigid_surface_first_node)
/// @param dt  the step (unit: s), > 0
/// @param rest_density  the water's (unit: kg/m^3): a body ten times heavier than the water its faces can
///        sweep in the step is left to the coupler, which gives it the same to within a tenth
/// @param positions  N particle positions (unit: m); masses N (unit: kg, > 0)
/// @param velocities  N particle velocities (unit: m/s): a swept particle's becomes V'
/// @param node_impulses  one per mesh node, added to (unit: N s): what each body takes, for
///        RigidBodySource::apply_impulses before its engine's step
/// @return how many particles were swept
std::size_t meet_swept_water(const std::vector<RigidSurface>& surfaces,
                             const std::vector<std::size_t>& first_node, double dt, double rest_density,
                             const Vec3Array& positions, const ScalarArray& masses, Vec3Array& velocities,
                             Vec3Array& node_impulses);

}  // namespace drench
