#include <drench/scene/effect_registry.hpp>

#include <algorithm>

namespace drench {

const std::vector<EffectEntry>& effect_registry() {
  // Each entry: name, description, needs {mesh, effect, why}, settings {section, what}, counter.
  static const std::vector<EffectEntry> registry = {
      {"viscosity",
       "the viscosity force of fluid.viscosity in every fluid sub-step (XSPH, Monaghan 1989; artificial "
       "viscosity, Monaghan 1992), built by the FluidSolver",
       {},
       {},
       &EffectCounters::viscosity},
      {"coupling",
       "two-way coupling with the cloth and the obstacles: repulsion (sec. 3.1-3.2, eq. 1-4) and continuous "
       "handling (sec. 3.3, eq. 5-6)",
       {EffectMesh::CLOTH_OR_OBSTACLES},
       {},
       &EffectCounters::coupling},
      {"friction",
       "tangential boundary conditions at contact, no-slip or Coulomb friction (sec. 3.4, eq. 7-8): a stage "
       "of the coupler, built by \"coupling\"",
       {EffectMesh::NONE, "coupling"},
       {},
       &EffectCounters::friction},
      {"leak_audit",
       "counts the particles that cross the cloth or an obstacle in a step, by exact predicates (a drench "
       "addition that checks sec. 3.3's claim)",
       {EffectMesh::CLOTH_OR_OBSTACLES},
       {},
       &EffectCounters::leak_audit},
      {"surface",
       "the fluid's surface at every frame, kept off the cloth (sec. 4), built by the run loop",
       {},
       {"surface", "the surface reconstruction"},
       &EffectCounters::surface},
      {"wetting",
       "the cloth absorbs, spreads and drips water (sec. 5, Fig. 9)",
       {EffectMesh::CLOTH, "coupling", ", whose contacts give the cloth its water"},
       {"wetting", "the wetting"},
       &EffectCounters::wetting},
  };
  return registry;
}

const EffectEntry* find_effect(const std::string& name) {
  const std::vector<EffectEntry>& registry = effect_registry();
  const auto it = std::find_if(registry.begin(), registry.end(),
                               [&](const EffectEntry& entry) { return name == entry.name; });
  return it == registry.end() ? nullptr : &*it;
}

}  // namespace drench
