#pragma once
/// The optional effects a scene may list in `effects`, in one table (issue 28): each effect's name, what it
/// adds and the paper section it implements, what the scene must have for it, the scene section that holds
/// its settings and its counter in EffectCounters. The loader checks `effects` against this table, and
/// summary.json counts the effects by it.
/// A new effect is one entry here, one row in docs/scenes.md's effects table (a test compares the two) and
/// its counter in EffectCounters.

#include <string>
#include <vector>

#include <drench/common/effect_counter.hpp>
#include <drench/scene/effect_counters.hpp>

namespace drench {

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
};

/// The effects, in the order of the coupled step (sec. 5) as docs/scenes.md lists them:
/// viscosity, coupling, friction, leak_audit, surface, wetting. Errors and summary.json's `effects_ran` list
/// them in this order.
const std::vector<EffectEntry>& effect_registry();

/// The entry named `name`, or nullptr when no effect has that name.
const EffectEntry* find_effect(const std::string& name);

}  // namespace drench
