#pragma once
/// The optional effects a scene may list in `effects`, in one table (issue 28): each effect's name, what it
/// adds and the paper section it implements, what the scene must have for it, the scene section that holds
/// its settings, its counter in EffectCounters, and how a Simulation builds it. The loader checks `effects`
/// against this table, Simulation builds the listed effects through it, and summary.json counts them by it.
/// A new effect is one entry here, one row in docs/scenes.md's effects table (a test compares the two) and
/// its counter in EffectCounters.

#include <memory>
#include <string>
#include <vector>

#include <drench/common/effect_counter.hpp>
#include <drench/coupling/carried_water.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/cloth_obstacle.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/static_obstacles.hpp>
#include <drench/scene/effect_counters.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/wetting/cloth_wetting.hpp>

namespace drench {

/// What a Simulation has built when it builds its effects: read by the effects' build functions.
struct EffectSite {
  const SceneConfig& config;
  /// The cloth and the obstacles as the coupling and the leak audit see them, or nullptr when the scene has
  /// neither (Simulation::contact_mesh). Validated.
  const ClothMesh* contact_mesh = nullptr;
  /// The cloth alone (its nodes at rest), or nullptr for a scene without one.
  const ClothMesh* cloth_mesh = nullptr;
  /// The cloth's engine, or nullptr: its dry node masses (ClothEngine::dry_node_masses).
  const ClothEngine* cloth = nullptr;
  /// The static obstacles in contact_mesh's order after the cloth's triangles (config.obstacles' first, then
  /// a program's own), or nullptr for none.
  const std::vector<TriangleMesh>* obstacles = nullptr;
};

/// The optional parts of one Simulation, filled by the build functions of the effects its scene lists and
/// empty (or false) for every other: what Simulation steps when they are there.
struct EffectParts {
  /// "viscosity": the FluidSolver, built after the effects, builds its viscosity force.
  bool viscosity = false;
  /// "surface_tension": the FluidSolver builds its surface tension force, of config.surface_tension.
  bool surface_tension = false;
  /// "coupling": the coupler (with the "friction" stage when the scene lists it), the cloth inside the
  /// fluid's sub-steps (coupling.continuous and coupling.substep_obstacle) and the carried water
  /// (coupling.scheme "carried_water").
  std::unique_ptr<Coupler> coupler;
  std::unique_ptr<ClothObstacle> obstacle;
  std::unique_ptr<CarriedWater> carried;
  /// "leak_audit": audits every step's final motion; its counter is Simulation's to keep.
  bool leak_audit = false;
  EffectCounter leak_counter;
  /// "wetting": the water in the cloth; its counter is Simulation's to keep.
  std::unique_ptr<ClothWetting> wetting;
  EffectCounter wetting_counter;
};

/// The mesh an effect acts on, which the scene must have for the effect to be listed.
enum class EffectMesh {
  NONE,                ///< needs no mesh
  CLOTH_OR_OBSTACLES,  ///< a `cloth` or `obstacles`
  CLOTH                ///< a `cloth` (obstacles do not do)
};

/// What a scene must have for an effect to be listed, besides its name; the loader checks it.
struct EffectNeeds {
  EffectMesh mesh = EffectMesh::NONE;
  const char* effect = nullptr;  ///< another effect that must be listed too, or nullptr
  /// Completes the loader's error "needs the \"<effect>\" effect": empty, or starting with ", ".
  const char* why = "";
};

/// The scene's top-level section read only by one effect; the section without the effect is an error (it
/// would be ignored).
struct EffectSection {
  const char* key = nullptr;  ///< "surface", "wetting"; nullptr: the effect has no section of its own
  /// What the section sets, for the loader's error "sets <what>, but effects does not list ...".
  const char* what = nullptr;
};

/// One effect of the registry.
struct EffectEntry {
  const char* name;         ///< as a scene lists it in `effects`
  const char* description;  ///< one line: what it adds, and the paper section it implements
  EffectNeeds needs;
  EffectSection settings;
  /// Its counts in EffectCounters.
  EffectCounter EffectCounters::*counter;
  /// Builds it into a Simulation's parts; called once, only when the scene lists it, in the registry's
  /// order, before the fluid is built. nullptr where another object builds it (the description says which).
  /// @throws SceneError or drench::Error as the parts' constructors do (settings out of range)
  void (*build)(const EffectSite& site, EffectParts& parts);
};

/// The effects, in the order of the coupled step (sec. 5) as docs/scenes.md lists them:
/// viscosity, surface_tension, coupling, friction, adhesion, leak_audit, surface, wetting. An effect comes
/// after those it needs, so that they are built first. Errors and summary.json's `effects_ran` list them in
/// this order.
const std::vector<EffectEntry>& effect_registry();

/// The entry named `name`, or nullptr when no effect has that name.
const EffectEntry* find_effect(const std::string& name);

/// The dry node masses of the cloth that the wetting's capacities are made of (unit: kg), one per node of
/// `cloth`, pinned nodes included (they hold water too). A scene that describes its cloth (a `cloth`
/// section) sets them: its area_density over each node's third of its faces' area (positions_t0). Without
/// one (a game's cloths, embedded) they are the engine's own (ClothEngine::dry_node_masses), or, from an
/// engine that cannot tell, the default area density's.
ScalarArray cloth_dry_masses(const SceneConfig& config, const ClothEngine* engine, const ClothMesh& cloth);

/// Builds the effects `site.config.effects` lists, each by its entry, in the registry's order; an effect not
/// listed is never built.
/// @throws SceneError or drench::Error as the entries' build functions do
EffectParts build_effects(const EffectSite& site);

}  // namespace drench
