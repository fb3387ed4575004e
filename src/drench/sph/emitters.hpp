#pragma once
/// Sources of fluid particles: a box of fluid at rest spacing, and a circular nozzle (jet).

#include <cstdint>

#include <drench/sph/emitter_settings.hpp>
#include <drench/sph/particle_set.hpp>

namespace drench {

/// Fills [min, max] with a cubic lattice of spacing s, particles at min + (i + 1/2) s, so that the particles'
/// volumes s^3 tile the box. Each axis holds floor(extent / s + 1e-9) particles (at least one).
/// @param mass  per particle (unit: kg);  @param next_id  in/out: id of the next particle created
/// @return particles added
std::size_t emit_box(const BoxEmitterSettings& box, Scalar spacing, Scalar mass, ParticleSet& particles,
                     std::uint32_t& next_id);

/// A circular jet. Each time the fluid leaving the nozzle has advanced one spacing s, a disc of
/// round(pi r^2 / s^2) particles (at least one) is released at the nozzle, moving at `speed` along
/// `direction`: the points nearest the axis of a hexagonal lattice with one point per s^2 (neighbours 1.075 s
/// apart), so that the jet carries rho pi r^2 v. A disc released at time r inside the step (t, t + dt] is
/// placed at centre + (t - r) v, upstream of the nozzle, so that the step's integration carries it to
/// centre + (t + dt - r) v: layers stay one spacing apart whatever dt is.
///
/// The fluid does not fly freely, though: pressure slows the jet's last layer a little, and a disc placed on
/// schedule would then sit closer than s to it. Stiff WCSPH turns that into speed: at dt 4 ms, with two or
/// three discs per step, the Fig. 3 jet threw a particle at 65 m/s before it reached anything. So a disc is
/// never placed closer than s behind the rearmost particle of the disc before it. A disc that would have to
/// go further upstream than one step's travel plus s (the outlet is blocked) waits, and the schedule slips
/// with it: a blocked nozzle emits less instead of stacking fluid upstream. Emission stops at the particle
/// budget, mid-disc if need be.
class NozzleEmitter {
 public:
  NozzleEmitter(const NozzleEmitterSettings& settings, Scalar spacing);

  /// Emits the layers due in the step (t, t + dt] (unit: s), placed for the start of the step; returns
  /// particles added. Call before the fluid advances by dt. `particles` must hold this nozzle's last disc
  /// as the fluid moved it (or none of it, if it was removed), so that the next disc keeps its distance.
  std::size_t emit(Scalar t, Scalar dt, Scalar mass, ParticleSet& particles, std::uint32_t& next_id);

  std::int64_t emitted() const { return m_emitted; }
  /// Particles in one disc layer.
  std::size_t disc_size() const { return m_disc.size(); }

 private:
  NozzleEmitterSettings m_settings;
  Scalar m_spacing;
  Vec3Array m_disc;  // offsets from the centre in the nozzle's plane
  std::int64_t m_emitted = 0;
  std::int64_t m_layers = 0;
  Scalar m_delay = 0.0;  // how far the schedule has slipped behind blocked discs (unit: s)
  std::uint32_t m_last_disc_begin = 0, m_last_disc_end = 0;  // ids of the last disc released
};

}  // namespace drench
