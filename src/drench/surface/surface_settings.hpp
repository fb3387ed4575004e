#pragma once
/// Settings of the fluid surface reconstruction (Huber et al. 2013 sec. 4), the scene's `surface` section.

#include <drench/common/types.hpp>

namespace drench {

/// The scalar field whose zero level is the surface (docs/scenes.md, `surface.field`).
enum class SurfaceField {
  /// Zhu & Bridson 2005: distance to the weighted mean of the particles near a node, less the particle
  /// radius; weights divided by each particle's density, as Onderik et al. 2011 do against uneven particle
  /// distributions (a dense cluster no longer pulls the mean towards itself).
  ZHU_BRIDSON,
  /// Müller et al. 2003's colour field: the SPH sum of the particles' volumes, its surface where it is 1/2.
  DENSITY,
};

/// How the fluid's surface is reconstructed from its particles (docs/scenes.md, `surface`).
struct SurfaceSettings {
  SurfaceField field = SurfaceField::ZHU_BRIDSON;
  /// Grid spacing of the marching-cubes grid (unit: m), > 0; 0 means half the particle spacing. The paper
  /// used 0.004 m for 5 mm particles (sec. 5).
  Scalar cell_size = 0.0;
  /// Whether the reconstruction respects the cloth and obstacles (sec. 4): a particle counts for a grid node
  /// only if the segment between them crosses no triangle (Fig. 2a), and nodes nearer than contact_offset to
  /// a triangle are outside (Fig. 2b).
  bool contact_aware = true;
  /// The paper's delta (unit: m), >= 0; negative means half a cell.
  Scalar contact_offset = -1.0;
  /// Radius of the Zhu & Bridson kernel in particle spacings: a node sees the particles within it.
  Scalar kernel_radius_in_spacings = 2.0;
  /// Particle radius of the Zhu & Bridson field in particle spacings: the surface lies about this far out
  /// of the outermost particles.
  Scalar particle_radius_in_spacings = 0.5;

  /// cell_size, or half the particle spacing when it is 0 (unit: m).
  Scalar resolved_cell_size(Scalar particle_spacing) const {
    return cell_size > 0.0 ? cell_size : 0.5 * particle_spacing;
  }
  /// contact_offset, or half a cell when it is negative (unit: m).
  Scalar resolved_contact_offset(Scalar particle_spacing) const {
    return contact_offset >= 0.0 ? contact_offset : 0.5 * resolved_cell_size(particle_spacing);
  }
};

}  // namespace drench
