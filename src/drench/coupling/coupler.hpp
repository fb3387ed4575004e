#pragma once
/// Two-way coupling of fluid particles and a cloth mesh by impulses (Huber et al. 2013 sec. 3): repulsion
/// within the cloth thickness (eq. 1-4), tangential boundary conditions (eq. 7-8) and continuous intersection
/// handling (eq. 5-6) until the step is free of crossings. Knows nothing of Bullet or of the SPH solver: both
/// sides are given as start and end positions (sec. 5), and the coupler corrects the end positions and the
/// velocities.

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <drench/common/effect_counter.hpp>
#include <drench/common/types.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupling_settings.hpp>
#include <drench/coupling/impulse_link.hpp>

namespace drench {

/// The fluid side of one step: N particles.
struct FluidView {
  const Vec3Array* positions_t0 = nullptr;  ///< N, at the start of the step (unit: m)
  Vec3Array* positions_t1 = nullptr;        ///< N, predicted end positions, corrected in place (m)
  Vec3Array* velocities = nullptr;          ///< N, end-of-step velocities, changed by the impulses (m/s)
  const ScalarArray* masses = nullptr;      ///< N, > 0 (unit: kg)
  /// N particle ids, or null; given, the coupler reports each particle's largest impulse
  /// (Coupler::impulse_links)
  const std::vector<std::uint32_t>* ids = nullptr;
};

/// What one coupling step did; accumulated into the run's summary.json.
struct CouplingStepStats {
  std::uint64_t contacts = 0;        ///< particle-triangle pairs within the cloth thickness (sec. 3.1)
  std::uint64_t ccd_impacts = 0;     ///< impacts found by the continuous handling and stopped (sec. 3.3)
  std::uint64_t ccd_iterations = 0;  ///< rounds of CCD run
  std::uint64_t failsafe_activations = 0;  ///< particles the fail-safe moved with their triangle
  std::uint64_t obstacle_stops = 0;        ///< particles stopped by the cloth inside fluid sub-steps
  /// Particles and cloth nodes the last resort joined into impact zones for a step, where even the fail-safe
  /// left a collision (COUPLING_ZONES_STOPPED)
  std::uint64_t stopped_particles = 0;
  std::uint64_t stopped_nodes = 0;
  /// Carries of particles outside the impact zones by a zone's move of a face they hit, rather than joining
  /// them (move_impact_zones); a particle carried in two rounds counts twice
  std::uint64_t carried_by_zones = 0;
  /// What the last resorts (the fail-safe's and the impact zones' moves, StepContext::place) gave particles:
  /// the sum of |m dv| (unit: N s). Each is booked against its triangle's nodes as an impulse is.
  double last_resort_impulse = 0.0;
  /// The momentum those shifts give a carried-water cloth's own nodes when its engine takes them at
  /// end_step, sum of |shift / (im dt)| (unit: N s), im the node's own inverse mass
  /// (CouplingScheme::CARRIED_WATER; owe_zone_shifts counts it and books it back).
  double zone_cloth_momentum = 0.0;
  /// Sum of |shift| over nodes whose own inverse mass is 0 (a body's, a pin's, an obstacle's), whose
  /// engine ignores it (unit: m): the water there was moved against a face that stays where it was.
  double zone_ignored_shift = 0.0;
  /// Particles the impact zones removed, caught between fixed faces that move differently (a falling box
  /// and the ground), where no motion keeps them out of both: Coupler::squeezed_out names them for the
  /// caller to remove. Their mass (unit: kg) and momentum m v at removal (unit: N s) are booked here, so the
  /// water, cloth and bodies with these keep their momentum.
  std::uint64_t squeezed_out = 0;
  double squeezed_out_mass = 0.0;
  Vec3 squeezed_out_momentum = Vec3::Zero();
  /// Particles that a body new in the step held inside its solid, moved out of it before the water moved,
  /// and those it displaced (no room outside), removed; their mass (unit: kg) and momentum m v at removal
  /// (unit: N s) (RigidBodySource::release_trapped)
  std::uint64_t released_from_bodies = 0;
  std::uint64_t displaced_by_bodies = 0;
  double displaced_mass = 0.0;
  Vec3 displaced_momentum = Vec3::Zero();
  double slip_sum_mps = 0.0;  ///< sum over contacts of the relative tangential speed after coupling
  double vertical_impulse_on_cloth = 0.0;  ///< sum of the y components of the impulses on cloth nodes (N s)
  double seconds_repulsion = 0.0;          ///< wall time of proximity + repulsion + friction (unit: s)
  double seconds_ccd = 0.0;                ///< wall time of the continuous handling (unit: s)
};

/// Bit flags of a coupling step's trouble (Jolt-style status, never an exception inside a step).
enum CouplingStatus : std::uint32_t {
  COUPLING_OK = 0,
  /// The continuous handling needed the fail-safe; fine when rare. Raise max_ccd_iterations if frequent.
  COUPLING_FAILSAFE_USED = 1u << 0,
  /// A collision remained after every resolution (a node that cannot be stopped, such as a pinned node its
  /// engine moves, swept a particle); Coupler::unresolved() names it, the step reports LEAKED and the leak
  /// audit counts the crossing. Smaller dt helps.
  COUPLING_UNRESOLVED = 1u << 1,
  /// The fail-safe left collisions (a particle caught in a fold), so the particles and nodes involved were
  /// joined into impact zones, each moving by one motion for the step: that of its fixed nodes (a body's,
  /// a pin's: they end where their engine put them) when they share one, else one displacement (the mean of
  /// its members'); where its fixed nodes move differently its particles against their faces are squeezed
  /// out (CouplingStepStats::squeezed_out); no crossing. The particles' momentum is booked on their
  /// triangles' nodes; the moves of a carried-water cloth's nodes are not paid for (Coupler::node_shifts: the
  /// cloth owes them back, owe_zone_shifts). (CouplingStepStats::stopped_particles, stopped_nodes.) Lower dt
  /// if frequent.
  COUPLING_ZONES_STOPPED = 1u << 2,
};

/// What the "adhesion" stage of a Coupler needs (Coupler::set_adhesion).
struct AdhesionSettings {
  /// F values, one per triangle of the mesh Coupler::step is given: the work of adhesion of water on that
  /// face (unit: N/m = J/m^2), in [0, kMaxWorkOfAdhesion]; Dupre's sigma (1 + cos theta) with theta the
  /// contact angle: 0.144 for water on a face it wets fully (cotton), about 0.05 for a water-repellent one
  /// (theta 110 degrees), 0 none.
  ScalarArray work;
  /// Distance from a face within which water is pulled towards it (unit: m), > 0: the SPH support radius.
  double range = 0.0;
  double rest_density = 1000.0;  ///< of the water (unit: kg/m^3), > 0
};

class TriangleBroadPhase;

/// Couples one fluid and one cloth mesh, step after step. Not thread-safe; uses OpenMP inside.
class Coupler {
 public:
  /// @param with_friction  runs the tangential boundary conditions (eq. 7-8, the "friction" effect); false
  ///        leaves them out, which changes nothing only when the settings ask for none (slip FRICTION with
  ///        friction_coefficient 0), as the scene loader makes sure
  /// @throws SceneError for settings out of range (the message names the setting)
  explicit Coupler(const CouplingSettings& settings, bool with_friction = true);
  ~Coupler();
  Coupler(const Coupler&) = delete;
  Coupler& operator=(const Coupler&) = delete;

  /// One coupling step of length dt (unit: s, > 0): adhesion when set, repulsion (eq. 1-4), friction (eq.
  /// 7-8), then continuous handling (eq. 5-6) on the corrected motion until no particle crosses a triangle.
  /// Impulses go to both sides, mass-weighted, the triangle's share to its nodes by barycentric weights, so
  /// the total linear momentum is conserved exactly (up to rounding); pinned nodes (inverse mass 0) never
  /// move. When no particle is within reach of the cloth (no particle's box over the step, grown by the cloth
  /// thickness, meets the mesh's box over the step), the step is skipped after that one test: it would change
  /// nothing, and its outputs are those of a step without contacts (counter().skipped).
  /// @param fluid  N particles; positions_t1 and velocities are changed
  /// @param cloth  validated mesh; positions_t1 are changed (the engine adds (change / dt) to its velocities)
  /// @param engine_inverse_masses  M inverse masses as the nodes' engines hold them (unit: 1/kg), or null for
  ///        cloth.inverse_masses: a caller that shows the coupler a cloth as kinematic (carried water) gives
  ///        the cloth's own, so the impact zones may move its nodes; a node of 0 is never moved
  /// @return COUPLING_* flags
  std::uint32_t step(const FluidView& fluid, ClothMesh& cloth, double dt, CouplingStepStats& stats,
                     const ScalarArray* engine_inverse_masses = nullptr);

  const CouplingSettings& settings() const { return m_settings; }

  /// The "coupling" effect's counts: constructed 1; a pass per step() that ran its stages, a skip per step()
  /// with no particle within reach (or no particle or triangle at all).
  const EffectCounter& counter() const { return m_counter; }
  /// The "friction" effect's counts: constructed 1 when built with friction; a pass per step that ran the
  /// tangential boundary conditions on its contacts.
  const EffectCounter& friction_counter() const { return m_friction_counter; }
  /// Turns on the adhesion stage (coupler_stages.hpp, adhere): a pull of the water towards the faces within
  /// settings.range, after friction, before the continuous handling (which keeps it from pulling water
  /// through a face). Its counts are adhesion_counter()'s.
  /// @throws SceneError when a work is negative or not finite (naming the triangle), or the range or the
  ///         rest density is not positive and finite
  void set_adhesion(AdhesionSettings settings);
  /// What set_adhesion last set, or nullopt without the adhesion stage.
  const std::optional<AdhesionSettings>& adhesion() const { return m_adhesion; }
  /// The "adhesion" effect's counts: constructed 1 after set_adhesion; a pass per step() that ran its stages.
  const EffectCounter& adhesion_counter() const { return m_adhesion_counter; }

  /// The impulse each cloth node received in the last step() (unit: N s), M entries, nodes with inverse
  /// mass 0 included: a caller that stepped a moving cloth as kinematic (inverse masses 0) hands these to
  /// the cloth itself (CouplingScheme::CARRIED_WATER), so momentum is still exchanged.
  const Vec3Array& node_impulses() const { return m_node_impulses; }

  /// How far the last step()'s impact zones moved each node with inverse mass 0 off the end position it was
  /// given (unit: m), M entries, 0 elsewhere. No impulse of the coupler pays for it: an engine that takes
  /// it as a velocity (a carried-water cloth's end_step) must have its momentum booked by the caller.
  const Vec3Array& node_shifts() const { return m_node_shifts; }

  /// What the last step()'s fail-safe gave the nodes of inverse mass > 0 without moving them (unit: N s), M
  /// entries, 0 elsewhere: it moves a particle with its triangle's contact point and leaves the triangle
  /// where it is, since moving it too could let it cross the particle. A caller whose nodes took the other
  /// impulses as moves (CouplingScheme::IMPULSES) hands these to the cloth at its next step, so momentum is
  /// exchanged here too (JetOnCloth.ImpulsesConserveLinearMomentumThroughTheFailSafe).
  const Vec3Array& owed_impulses() const { return m_owed_impulses; }

  /// For every particle that received an impulse in the last step() (in particle order), the triangle, the
  /// weights and the size of its largest one; empty unless FluidView::ids was given. With node_impulses(),
  /// what CarriedWater::attach needs to carry each particle with the nodes its impulse goes to.
  const ImpulseLinks& impulse_links() const { return m_impulse_links; }

  /// N flags of the particles the last step() squeezed out (CouplingStepStats::squeezed_out), which the
  /// caller removes, their positions and velocities meaning nothing; empty when none was.
  const std::vector<std::uint8_t>& squeezed_out() const { return m_squeezed; }

  /// After a step() that returned COUPLING_UNRESOLVED, the particle (index in that step's arrays) and the
  /// triangle of a collision left; (-1, -1) otherwise.
  std::pair<std::int64_t, std::int64_t> unresolved() const { return m_unresolved; }

 private:
  /// step() after its set-up: the stages of sec. 3 in the paper's order (coupler_stages.hpp).
  std::uint32_t correct(const FluidView& fluid, ClothMesh& cloth, double dt, CouplingStepStats& stats,
                        const ScalarArray* engine_inverse_masses);

  CouplingSettings m_settings;
  bool m_with_friction;
  EffectCounter m_counter;
  EffectCounter m_friction_counter;
  std::optional<AdhesionSettings> m_adhesion;
  EffectCounter m_adhesion_counter;
  Vec3Array m_node_impulses;
  Vec3Array m_node_shifts;
  Vec3Array m_owed_impulses;
  std::vector<std::uint8_t> m_squeezed;
  ImpulseLinks m_largest;  // N, scratch of step()
  ImpulseLinks m_impulse_links;
  std::pair<std::int64_t, std::int64_t> m_unresolved{-1, -1};
  std::unique_ptr<TriangleBroadPhase> m_broad_phase;
};

}  // namespace drench
