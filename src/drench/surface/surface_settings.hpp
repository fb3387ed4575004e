#pragma once
/// Settings of the fluid surface reconstruction (Huber et al. 2013 sec. 4), the scene's `surface` section.

#include <drench/common/types.hpp>

namespace drench {

/// Largest |coordinate| / cell size a surface grid node may have: OpenVDB's coordinates are int32, and the
/// dilation and the kernel's reach add a few nodes on either side.
inline constexpr double kMaxSurfaceGridCells = 0x1p30;

/// The scalar field whose zero level is the surface (docs/scenes.md, `surface.field`).
enum class SurfaceField {
  /// Zhu & Bridson 2005: distance to the weighted mean of the particles near a node, less the particle
  /// radius; weights divided by each particle's density, as Onderik et al. 2011 do against uneven particle
  /// distributions (a dense cluster no longer pulls the mean towards itself).
  ZHU_BRIDSON,
  /// Müller et al. 2003's colour field: the SPH sum of the particles' volumes, its surface where it is 1/2.
  DENSITY,
};

/// The kernel each particle spreads into the field (docs/scenes.md, `surface.kernel`).
enum class SurfaceKernel {
  /// A sphere of the kernel radius around every particle.
  ISOTROPIC,
  /// Yu & Turk 2013: an ellipsoid per particle from the weighted covariance of its neighbours, centred on
  /// its Laplacian-smoothed position, so that a sheet or a stream one particle thick stays whole. Only with
  /// the density field, which it is a kernel of.
  ANISOTROPIC,
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

  SurfaceKernel kernel = SurfaceKernel::ISOTROPIC;
  // Yu & Turk 2013's constants (ACM TOG 32(1), sec. 3-4), used with kernel ANISOTROPIC. Their neighbourhood
  // radius r_i is twice the kernel radius.
  /// lambda of the smoothed centres x_i' = (1 - lambda) x_i + lambda (weighted mean of the neighbours within
  /// the kernel radius), in [0, 1]; theirs 0.9 to 1.
  Scalar smoothing = 0.9;
  /// k_r: the longest axis of a kernel is at most this many times its shortest, >= 1; theirs 4.
  Scalar max_anisotropy = 4.0;
  /// k_s: the covariance's singular values, in units of r_i^2, times this are the kernel's axes in kernel
  /// radii, > 0. Yu & Turk choose it so that ||k_s C|| is about 1 for a full neighbourhood (their 1400 is in
  /// their scene's units); that is 6.64 here (1 / 0.1506, the weighted variance per axis of a cubic lattice's
  /// full neighbourhood). 10 (interior kernels 1.5 radii) lets the flattened kernels of a free surface reach
  /// far enough that a ball keeps its volume with a block near the isotropic one's (tests/surface).
  Scalar anisotropy_scale = 10.0;
  /// k_n: a particle with fewer than min_neighbours neighbours gets an isotropic kernel of this many kernel
  /// radii (its amplitude raised to keep its volume), > 0; theirs 0.5.
  Scalar isolated_scale = 0.5;
  /// N_eps: neighbours within r_i (the particle included) below which the kernel is isotropic, >= 1. A
  /// covariance of few points says little about the fluid's shape, but theirs, 25, left the one-layer sheets
  /// of the jet on a cloth and of the V as beads where 6 keeps them whole (measured: docs/scenes.md).
  int min_neighbours = 6;

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
