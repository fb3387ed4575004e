#pragma once
/// Settings of the wet cloth (Huber et al. 2013 sec. 5, Fig. 9, after the absorption and diffusion model of
/// Huber, Pabst & Straßer 2011): how much water the cloth holds, how fast it takes water from the particles
/// touching it, and how the water spreads and runs down inside it. Used when the scene's `effects` lists
/// "wetting" (docs/scenes.md, `wetting`).

namespace drench {

struct WettingSettings {
  /// Water a node holds when saturated, per mass of dry cloth (unit: kg/kg), > 0. Woven cotton holds
  /// roughly its own weight of water after dripping stops; synthetics far less. Above it a node drips.
  double max_saturation = 1.0;
  /// Fraction of a touching particle's mass a dry cloth takes per second (unit: 1/s), >= 0; it falls
  /// linearly to 0 as the touched nodes fill. With the default a particle resting on a dry cloth is gone in
  /// about 0.1 s.
  double absorption_rate = 10.0;
  /// Capillary spreading along the cloth (unit: m^2/s), in [0, kMaxWettingDiffusion]: Fick's law on the
  /// saturation (water held over capacity), so water moves from wetter to drier nodes. A wet front travels
  /// about sqrt(diffusion * t): 1 cm in 1 s with the default.
  double diffusion = 1e-4;
  /// Gravity drainage (unit: m/s), in [0, kMaxGravityFlow]: the speed at which water runs down inside a
  /// cloth hanging vertically; along an edge it is scaled by the edge's slope. Water held by a node drains at
  /// this speed whatever its saturation, so a hanging cloth wetted at its top ends wetter at its bottom, and
  /// drips there.
  double gravity_flow = 0.05;
};

/// The fastest spreading and drainage a scene may ask for. The spread is explicit, in sub-steps of at most
/// half a node's rate (ClothWetting::spread), so their count grows with these rates without bound (and past
/// a 64-bit count it overflows). 1 m^2/s (a front a metre from its source in a second) and 10 m/s (free fall
/// over 5 m) are far beyond any cloth's wicking and drainage.
inline constexpr double kMaxWettingDiffusion = 1.0;
inline constexpr double kMaxGravityFlow = 10.0;

/// Throws SceneError naming the first field of `settings` outside its range ("wetting.diffusion must be in
/// [0, 1], got 1000000"), as the scene loader does for a file: for settings built in code.
void check_wetting_settings(const WettingSettings& settings);

}  // namespace drench
