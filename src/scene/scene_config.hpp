#pragma once
/// Plain settings structs for a whole scene, filled from JSON by scene_loader.hpp or built in code by tests,
/// benchmarks and users. Every member states its unit and default; `docs/scenes.md` documents the same keys.
/// Settings are kept apart from runtime objects: a SceneConfig builds a Simulation (scene/simulation.hpp).

#include <optional>
#include <string>
#include <vector>

#include "common/types.hpp"
#include "coupling/cloth_engine.hpp"
#include "coupling/coupling_settings.hpp"

namespace drench {

/// Which pressure solver runs. Selected by name in the scene (`fluid.pressure_solver`).
enum class PressureSolverKind { WCSPH, PCISPH };

/// Weakly compressible SPH, Becker & Teschner 2007: Tait equation p = B ((rho / rho0)^gamma - 1).
struct WcsphSettings {
  /// Numerical speed of sound c (unit: m/s), B = rho0 c^2 / gamma. Unset: 10 x the scene's expected maximum
  /// speed (sqrt(2 g H) over the scene's height H plus the fastest emitter), i.e. Mach 0.1 and about 1%
  /// density variation (Monaghan 1994).
  std::optional<Scalar> speed_of_sound;
  Scalar exponent = 7.0;  ///< gamma of the Tait equation (dimensionless), >= 1
};

/// Floating-point precision of PCISPH's iterations: the density and pressure passes over neighbor pairs that
/// each iteration runs (fluid.pcisph.precision). Pressures, densities, velocities and positions are double
/// either way.
enum class IterationPrecision {
  SINGLE,  ///< the pair sums in float (sph_densities_float, pressure_accelerations_float)
  DOUBLE   ///< the pair sums in double (sph_densities, pressure_accelerations)
};

/// Predictive-corrective incompressible SPH, Solenthaler & Pajarola 2009.
struct PcisphSettings {
  Scalar eta = 0.001;      ///< target average density error (fraction of rest density), > 0
  int min_iterations = 3;  ///< at least this many correction iterations per sub-step, >= 1 (SPlisHSPlasH: 3)
  int max_iterations = 100;  ///< at most this many, >= min_iterations
  /// The largest compression (fraction of rest density, > 0) one iteration corrects for one particle; unset
  /// = none, as published. A drench addition: a compression made outside the fluid's forces (the
  /// coupling's position corrections, a hand-back, an emitter) is otherwise undone within one CFL sub-step,
  /// at a speed of about compression x spacing / sub-step that shrinks the next sub-step and feeds itself.
  /// With the limit it is undone over several iterations and sub-steps. A settled or smoothly moving fluid
  /// stays below it (its errors are near eta) and is not changed. Measured on the full jet_on_cloth scene
  /// (PCISPH, 0.5 s): cloth thickness 5 mm blew up at t = 0.245 s without it (172 m/s); with 0.05 the
  /// fastest particle is 8.1 m/s (0.1: 8.7 m/s; 0.2: 71 m/s). Source: none; docs/scenes.md has its cost.
  std::optional<Scalar> max_compression_per_iteration = 0.05;
  /// The largest compression (fraction of rest density, > 0) one sub-step relieves for one particle; unset
  /// = all of it, as published. A drench addition: a particle that enters a sub-step compressed by more
  /// (its density at the sub-step's start) is driven to that density minus this limit instead of the rest
  /// density, the rest left to the next sub-steps; the compression its motion within the sub-step would
  /// add is resisted in full, as published. What the fluid's own forces leave stays near eta; what the
  /// cloth coupling makes between the fluid's steps does not: stopping water against a moving cloth stacks
  /// particles (up to 2.1 x rest density at the start of a 4 ms step of the reduced Fig. 3 jet, 3.5 x in
  /// the 20 m/s jet), and undoing that inside one CFL sub-step threw particles at 15-17 m/s (82 m/s).
  /// Measured with 0.05 (PCISPH, 0.5 s of jet_on_cloth.json): dt 1 ms 6.4 m/s, dt 4 ms 7.5 m/s (without:
  /// blew up at t = 0.356 s). Source: none; docs/scenes.md has its cost.
  std::optional<Scalar> max_relief_per_substep = 0.05;
  /// Precision of the iterations' pair sums. Single (the default) agrees with double to about 1e-5 of a
  /// density and ran the 59K dam break's solve faster (docs/scenes.md has the measured cost of each). Double
  /// is also used, whatever this says, when particle masses differ.
  IterationPrecision precision = IterationPrecision::SINGLE;
};

/// Viscosity method. Constructed only when the scene's `effects` lists "viscosity".
enum class ViscosityKind {
  XSPH,       ///< velocity smoothing v_i += c sum_j m_j / rho_j (v_j - v_i) W_ij (Monaghan 1989)
  ARTIFICIAL  ///< Monaghan's artificial viscosity Pi_ij with coefficient alpha (Monaghan 1992)
};

struct ViscositySettings {
  ViscosityKind method = ViscosityKind::XSPH;
  /// Dimensionless coefficient (XSPH c or artificial alpha), >= 0. 0.01 is SPlisHSPlasH's standard value.
  Scalar coefficient = 0.01;
};

struct FluidSettings {
  Scalar rest_density = 1000.0;    ///< rho0 (unit: kg/m^3), > 0
  Scalar particle_spacing = 0.05;  ///< rest spacing of the particle lattice (unit: m), > 0; particle mass is
                                   ///< rho0 spacing^3 and the kernel support radius is 2 spacing
  PressureSolverKind pressure_solver = PressureSolverKind::PCISPH;
  WcsphSettings wcsph;
  PcisphSettings pcisph;
  ViscositySettings viscosity;
  /// CFL factor lambda (dimensionless), in (0, 1]: a fluid sub-step never exceeds lambda spacing / v_max,
  /// with v_max the fastest particle (plus the speed of sound for WCSPH).
  Scalar cfl = 0.4;
  /// Fluid sub-steps between re-sorting particles along a z-order curve for cache locality, >= 1.
  int sort_interval = 10;
};

/// A circular jet: particles leave a disc of `radius` around `center` along `direction` at `speed`, in layers
/// one spacing apart, from `start_time` until `max_particles` have been emitted.
struct NozzleEmitterSettings {
  Vec3 center = Vec3::Zero();             ///< (unit: m)
  Vec3 direction = Vec3(0.0, -1.0, 0.0);  ///< normalised on load, non-zero
  Scalar radius = 0.02;                   ///< (unit: m), > 0
  Scalar speed = 1.0;                     ///< (unit: m/s), > 0
  Scalar start_time = 0.0;                ///< (unit: s), >= 0
  std::int64_t max_particles = 10000;     ///< particle budget of this emitter, >= 0
};

/// A box of fluid at rest spacing, created at time 0 (dam-break columns, tanks).
struct BoxEmitterSettings {
  Vec3 min = Vec3::Zero();       ///< lower corner (unit: m)
  Vec3 max = Vec3::Ones();       ///< upper corner (unit: m), > min on every axis
  Vec3 velocity = Vec3::Zero();  ///< initial velocity (unit: m/s)
};

struct EmitterSettings {
  enum class Kind { NOZZLE, BOX } kind = Kind::BOX;
  NozzleEmitterSettings nozzle;
  BoxEmitterSettings box;
};

/// Static boundaries sampled with boundary particles (Akinci et al. 2012).
struct BoundarySettings {
  enum class Kind {
    BOX,   ///< a container: the fluid lives inside [min, max]; walls are sampled on its six faces
    PLANE  ///< a rectangle of size[0] x size[1] centred at `point`, fluid on the side `normal` points to
  } kind = Kind::BOX;
  Vec3 min = Vec3::Zero();            ///< BOX: inner lower corner (unit: m)
  Vec3 max = Vec3::Ones();            ///< BOX: inner upper corner (unit: m), > min
  bool open_top = false;              ///< BOX: no wall at max.y (the up axis is +y, against default gravity)
  Vec3 point = Vec3::Zero();          ///< PLANE: centre (unit: m)
  Vec3 normal = Vec3(0.0, 1.0, 0.0);  ///< PLANE: normalised on load, non-zero
  Scalar size[2] = {1.0, 1.0};        ///< PLANE: side lengths (unit: m), > 0
  int layers = 2;  ///< layers of boundary particles behind the surface, one spacing apart, >= 1
};

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
  Scalar dt = 0.005;      ///< step of the whole simulation (unit: s), > 0; the fluid may sub-step inside it
  Scalar duration = 1.0;  ///< simulated time (unit: s), > 0
  Scalar frame_rate = 30.0;  ///< frames written per simulated second (unit: 1/s), >= 0; 0 writes no frames
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
  /// Coupling of fluid and cloth; used when `effects` lists "coupling" (and "friction" for the tangential
  /// boundary conditions).
  CouplingSettings coupling;
  std::vector<std::string> effects;  ///< names from known_effects(), each at most once

  /// True when `effects` lists `name`, i.e. that optional physics is to be constructed.
  bool has_effect(const std::string& name) const;
};

/// The effect names a scene may list in `effects`: "viscosity", "coupling" (repulsion and continuous
/// handling, sec. 3.1-3.3), "friction" (tangential boundary conditions, sec. 3.4), "leak_audit" (counts
/// particles crossing the cloth): the one list the loader checks.
const std::vector<std::string>& known_effects();

}  // namespace drench
