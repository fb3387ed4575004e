#pragma once
/// Static boundaries as boundary particles, Akinci et al. 2012 ("Versatile rigid-fluid coupling for
/// incompressible SPH"): a boundary particle b adds Psi_b W_ib to a fluid particle's density (eq. 6) and
/// pushes it with -Psi_b p_i / rho_i^2 grad W_ib (eq. 10), Psi_b = rho0 V_b.
///
/// Walls here are regular lattices that continue the fluid's lattice, so V_b is the lattice cell volume,
/// which gives exactly rest density to fluid at rest spacing, at walls and in corners alike. Akinci's eq. 4,
/// V_b = 1 / sum_k W_bk over boundary neighbours, is made for irregular single-layer samplings; on these
/// two-layer walls it overestimates V_b (it misses the fluid side), putting the corner particles of a tank at
/// +4% density, where PCISPH's pressure grew without bound in the first step.

#include <drench/common/types.hpp>
#include <drench/sph/boundary_settings.hpp>

namespace drench {

/// Boundary particles: positions and the volume each one stands for.
struct BoundaryParticles {
  Vec3Array positions;  ///< N (unit: m)
  ScalarArray volumes;  ///< N (unit: m^3), > 0

  std::size_t size() const { return positions.size(); }
  void append(const BoundaryParticles& other);
};

/// Samples the walls of a box container whose inside is [min, max] (unit: m). The wall surface lies half a
/// spacing in front of the first particle layer, so a fluid lattice that starts half a spacing inside the
/// wall (as box emitters place it) sits one spacing from the boundary particles and fills exactly the box's
/// volume. Each axis is divided into round(extent / spacing) cells (at least 1), so faces land exactly on min
/// and max.
/// @param spacing  boundary particle spacing (unit: m), > 0
/// @param layers  particle layers behind each wall, >= 1
/// @param open_top  no wall above max.y
BoundaryParticles sample_box_container(const Vec3& min, const Vec3& max, Scalar spacing, int layers,
                                       bool open_top);

/// Samples a rectangle of size[0] x size[1] (unit: m) centred at `point`, with the fluid on the side `normal`
/// points to. The surface lies half a spacing in front of the first layer. The rectangle's first side runs
/// along normalize(normal x a), a the coordinate axis least aligned with the normal; its second along
/// normal x first.
/// @param normal  unit vector
BoundaryParticles sample_plane(const Vec3& point, const Vec3& normal, const Scalar size[2], Scalar spacing,
                               int layers);

/// The in-plane axes of a plane boundary: `first` = normalize(normal x a), a the coordinate axis least
/// aligned with the normal, and `second` = normal x first.
void plane_axes(const Vec3& normal, Vec3& first, Vec3& second);

/// Last guard of a boundary, after the boundary particles' pressure has done its work: a particle moving from
/// x_t0 to x_t1 that would end behind the boundary's surface is put back on the surface and loses the
/// velocity component into it. Boundary particles repel only through pressure, and a lone fast droplet has
/// none (its density is below rest density), so without this guard 180 of 8,000 dam-break particles left the
/// box within 1 s (test_dam_break checks that they stay inside). A BOX guards only particles that start
/// inside it; a PLANE only those crossing its rectangle from the side its normal points to.
/// @return true when the particle was moved
bool enforce_boundary(const BoundarySettings& boundary, const Vec3& x_t0, Vec3& x_t1, Vec3& velocity);

}  // namespace drench
