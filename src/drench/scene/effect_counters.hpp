#pragma once
/// The counts of every optional effect of a run, by the names of the effect registry (effect_registry.hpp),
/// whose entries point at their counters here: what proves that an effect the scene does not list was never
/// built and never ran, and how often the coupling found nothing within reach. Filled by
/// Simulation::effect_counters() (the surface's by the run loop, scene_runner.hpp).

#include <string>

#include <drench/common/effect_counter.hpp>

namespace drench {

struct EffectCounters {
  /// The viscosity force (FluidSolver): a pass per fluid sub-step.
  EffectCounter viscosity;
  /// The surface tension force (FluidSolver): a pass per fluid sub-step.
  EffectCounter surface_tension;
  /// The coupler: a pass per step whose stages ran, a skip per step with no particle within reach of the
  /// cloth and obstacles. Its sub-step obstacle and carried water are built only with it.
  EffectCounter coupling;
  /// Part of "coupling": the cloth inside the fluid's sub-steps (coupling.substep_obstacle), a pass or a
  /// skip per fluid sub-step.
  EffectCounter substep_obstacle;
  /// The tangential boundary conditions inside the coupler: a pass per coupler step that ran.
  EffectCounter friction;
  /// Part of "coupling": the pull of the water towards the faces, a pass per coupler step that ran.
  EffectCounter adhesion;
  /// A pass per step audited, a skip per step with no particle within reach.
  EffectCounter leak_audit;
  /// A pass per frame reconstructed (counted by run_scene; zero in Simulation's).
  EffectCounter surface;
  /// A pass per step of absorbing, spreading and dripping.
  EffectCounter wetting;

  /// The counter of an effect named as in the effect registry, or nullptr for any other name.
  const EffectCounter* find(const std::string& name) const;
};

}  // namespace drench
