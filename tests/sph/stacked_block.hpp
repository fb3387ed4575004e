#pragma once
// The compression the cloth coupling makes, in miniature: a resting block with one particle stacked onto
// another, for the tests of the pressure solvers' limits (test_pcisph.cpp, test_wcsph.cpp).

#include <cstdint>

#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench::testing {

/// Fills `fluid` with an 8 x 8 x 8 block at `spacing` (unit: m) from the origin and adds one more particle
/// 0.1 spacing from the one nearest the block's centre, as the coupling stacks them. Returns its id.
inline std::uint32_t stack_in_block(FluidSolver& fluid, double spacing) {
  BoxEmitterSettings box;
  box.max = Vec3::Constant(8 * spacing);
  std::uint32_t next_id = 0;
  const double mass = fluid.settings().rest_density * spacing * spacing * spacing;
  emit_box(box, spacing, mass, fluid.particles(), next_id);
  ParticleSet& p = fluid.particles();
  const Vec3 centre = Vec3::Constant(4.5 * spacing);
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if ((p.positions[i] - centre).norm() < (p.positions[nearest] - centre).norm()) nearest = i;
  }
  p.add(p.positions[nearest] + Vec3(0.1 * spacing, 0, 0), Vec3::Zero(), p.masses[nearest], next_id);
  return next_id;
}

/// The density above rest (fraction of rest density) of the particle with `id`, as of the last sub-step.
inline double compression_of(const FluidSolver& fluid, std::uint32_t id) {
  const ParticleSet& p = fluid.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.ids[i] == id) return p.densities[i] / fluid.settings().rest_density - 1.0;
  }
  return 0.0;
}

}  // namespace drench::testing
