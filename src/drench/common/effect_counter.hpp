#pragma once
/// How often an optional effect of a scene (viscosity, coupling, friction, leak audit, surface, wetting) was
/// built and run: the proof, by count rather than by timing, that an effect the scene does not list costs
/// nothing. Each module counts its own effect where the effect is built and where its work runs;
/// scene/effect_counters.hpp gathers them by name.

#include <cstdint>

namespace drench {

/// The counts of one effect over a whole run. A plain increment per construction and per pass, never per
/// particle or face.
struct EffectCounter {
  std::uint64_t constructed = 0;  ///< objects built for the effect
  /// Times its per-step work ran (per fluid sub-step, per step or per frame, as the effect's owner documents)
  std::uint64_t passes = 0;
  /// Times that work was due but had nothing within its reach (no particle, or one box test showed none),
  /// so it did nothing but find that out; not in `passes`
  std::uint64_t skipped = 0;
};

}  // namespace drench
