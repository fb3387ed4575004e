#pragma once
/// The settings of a whole scene, filled from JSON by scene_loader.hpp or built in code by tests, benchmarks
/// and users. It composes the settings each module keeps beside its code (sph/fluid_settings.hpp,
/// sph/emitter_settings.hpp, sph/boundary_settings.hpp, coupling/coupling_settings.hpp, ClothSettings in
/// coupling/cloth_engine.hpp) with the scene's own: time, kill regions, effects. Every member states its
/// unit and default; `docs/scenes.md` documents the same keys. A SceneConfig builds a Simulation
/// (scene/simulation.hpp).

#include <optional>
#include <string>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/coupling/cloth_engine.hpp>
#include <drench/coupling/coupling_settings.hpp>
#include <drench/coupling/static_obstacles.hpp>
#include <drench/sph/boundary_settings.hpp>
#include <drench/sph/emitter_settings.hpp>
#include <drench/sph/fluid_settings.hpp>
#include <drench/surface/surface_settings.hpp>
#include <drench/wetting/wetting_settings.hpp>

namespace drench {

/// Removes particles that leave the region of interest; the summary counts them as `removed`.
struct KillRegionSettings {
  enum class Kind {
    PLANE,  ///< removes particles with (x - point) . normal < 0
    BOX     ///< removes particles outside [min, max]
  } kind = Kind::PLANE;
  Vec3 point = Vec3::Zero();          ///< PLANE (unit: m)
  Vec3 normal = Vec3(0.0, 1.0, 0.0);  ///< PLANE: normalised on load, non-zero; points into the kept region
  Vec3 min = Vec3::Zero();            ///< BOX (unit: m)
  Vec3 max = Vec3::Ones();            ///< BOX (unit: m)
};

struct TimeSettings {
  /// Step of the whole simulation (unit: s), > 0; the fluid may sub-step inside it. With `adaptive`, the
  /// largest step.
  Scalar dt = 0.005;
  /// Each step is the fluid's CFL step (FluidSolver::cfl_step, FluidSettings::cfl), within [dt_min, dt], cut
  /// to land on every frame's time and on the duration: no fluid sub-steps unless a step is at dt_min. The
  /// cloth and the coupling take the same steps; the fluid's step stays a sub-step of the scene's.
  bool adaptive = false;
  Scalar dt_min = 1e-5;      ///< with `adaptive`: the smallest step (unit: s), > 0, <= dt
  Scalar duration = 1.0;     ///< simulated time (unit: s), > 0
  Scalar frame_rate = 30.0;  ///< frames written per simulated second (unit: 1/s), >= 0; 0 writes no frames
};

/// The camera's field of view (unit: degree) lies in [kMinFovDeg, kMaxFovDeg]: narrower than a tenth of a
/// degree, or 180 and wider, the projection draws nothing.
inline constexpr double kMinFovDeg = 0.1;
inline constexpr double kMaxFovDeg = 179.0;
/// The camera's eye is at least this far from its target (unit: m): closer, the view direction is lost.
inline constexpr double kMinCameraDistance = 1e-6;

/// Where `drench render` (and the viewer) looks from, so that renders of a scene are repeatable. The
/// simulation ignores it. Without a position and target the renderer frames the scene's bounds itself.
struct CameraSettings {
  /// Eye (unit: m), within kMaxCoordinate; given together with `target`, kMinCameraDistance or more from it.
  std::optional<Vec3> position;
  std::optional<Vec3> target;  ///< the point looked at, drawn at the image's centre (unit: m)
  Scalar fov_deg = 45.0;       ///< vertical field of view (unit: degree), in [kMinFovDeg, kMaxFovDeg]
};

/// What a program gives a scene beside its own keys: a CoupledWorld's cloths and rigid bodies are Bullet's,
/// not the scene's `cloth` and `obstacles`.
struct SuppliedMeshes {
  bool cloth = false;   ///< a cloth engine (one or more cloths) not built from `config.cloth`
  bool meshes = false;  ///< any mesh the coupling can act on: that cloth, static meshes or rigid bodies
};

/// A complete scene. The effects named in `effects` are the only optional physics that get constructed.
struct SceneConfig {
  std::string source = "<code>";         ///< file the scene came from, used in error messages
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);  ///< (unit: m/s^2); +y is up
  FluidSettings fluid;
  std::vector<EmitterSettings> emitters;
  std::vector<BoundarySettings> boundaries;
  std::vector<KillRegionSettings> kill_regions;
  TimeSettings time;
  /// The cloth (Bullet soft body through the adapter); absent: a fluid-only scene.
  std::optional<ClothSettings> cloth;
  /// Static triangle meshes that hold the fluid, coupled as the cloth is with inverse mass 0.
  std::vector<ObstacleSettings> obstacles;
  /// Coupling of fluid and cloth; used when `effects` lists "coupling" (and "friction" for the tangential
  /// boundary conditions).
  CouplingSettings coupling;
  /// Reconstruction of the fluid's surface at every frame (sec. 4); used when `effects` lists "surface".
  SurfaceSettings surface;
  /// Water absorbed, spread and dripped by the cloth (Fig. 9); used when `effects` lists "wetting".
  WettingSettings wetting;
  /// Surface tension of the water (the paper's future work, sec. 6); used when `effects` lists
  /// "surface_tension".
  SurfaceTensionSettings surface_tension;
  std::vector<std::string> effects;  ///< names from known_effects(), each at most once
  /// The camera of renders (`drench render`); absent: framed to the scene's bounds.
  std::optional<CameraSettings> camera;

  /// True when `effects` lists `name`, i.e. that optional physics is to be constructed.
  bool has_effect(const std::string& name) const;
};

/// The names a scene may list in `effects`, in the order of the effect registry (scene/effect_registry.hpp),
/// which says what each adds and needs.
const std::vector<std::string>& known_effects();

}  // namespace drench
