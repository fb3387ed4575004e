#pragma once
/// Settings of the cloth-fluid coupling (Huber et al. 2013 sec. 3). Plain values in SI units; the scene
/// loader fills them from the scene's `coupling` object (docs/scenes.md).

#include <cstdint>

namespace drench {

/// Tangential boundary condition at contact (sec. 3.4).
enum class SlipCondition : std::uint8_t {
  FRICTION = 0,  ///< eq. 8 with friction_coefficient; 0 is free slip (tangential velocity untouched)
  NO_SLIP = 1,   ///< eq. 7: zero relative tangential velocity at contact
};

/// Which broad phase finds particle-triangle candidates; both give the same pairs (tests check it).
enum class BroadPhaseKind : std::uint8_t {
  /// Triangles binned into a uniform grid, kept across steps: only a triangle whose box now covers other
  /// cells is binned again. The default: on issue 41's game frame (a static ground and table, cloths and
  /// bodies that move) PBF's frame took 17% fewer instructions than with FCL (callgrind, 70 frames), and on
  /// a whole moving cloth (bench/bench_coupling.cpp, coupler_step) it is within 7% of FCL's time.
  GRID = 0,
  /// FCL's DynamicAABBTreeCollisionManager of the triangles, refitted when the cloth moved.
  FCL = 1,
};

/// How the cloth takes the fluid's impulses.
enum class CouplingScheme : std::uint8_t {
  /// drench's scheme for a light cloth under heavy water (coupling/carried_water.hpp): the coupler and the
  /// sub-step obstacle correct the particles against the cloth as the cloth engine moved it; the cloth's
  /// share of every impulse reaches it at the start of its next step, and the particles that gave those
  /// impulses (the water in contact) move with it through the engine's step as node mass. The default: with
  /// the paper's scheme the reduced Fig. 3 jet throws the nodes at hundreds of m/s (the added-mass
  /// instability; tests/bullet_adapter/test_jet_on_cloth.cpp, NeverLeaksWithContinuousHandling).
  CARRIED_WATER = 0,
  /// The paper as written (sec. 3.2, 5): impulses move both sides' end positions within the step,
  /// mass-weighted. Right for a static mesh or a cloth as heavy as its water.
  IMPULSES = 1,
};

/// The largest work of adhesion a face may have (unit: N/m): Dupre's sigma (1 + cos theta) is at most 2
/// sigma, and mercury's sigma (0.49 N/m) is the largest of any liquid at room temperature. Far beyond it the
/// pull throws particles into CFL sub-steps (1e200 ran over 15 s for two steps of the jet on a cloth).
inline constexpr double kMaxWorkOfAdhesion = 1.0;

/// The thickest cloth relative to the fluid's particle spacing: the SPH kernel's support (2 spacings).
/// The pairs within the thickness grow as its square over the triangles' area: a thickness of 1 m (a typo
/// for 1 mm) ran over 30 s for one step of a dam break on a cloth. The paper's thickest is one spacing
/// (Table 1: 5 mm at 5 mm).
inline constexpr double kMaxClothThicknessPerSpacing = 2.0;

struct CouplingSettings {
  /// The paper's h: the layer around the cloth where particles are repelled (unit: m), > 0 and at most
  /// kMaxClothThicknessPerSpacing fluid particle spacings.
  double cloth_thickness = 0.001;
  /// k of eq. 4 (unit: N/m), >= 0. The elastic impulse k d dt is capped as in Bridson et al. 2002 so that it
  /// never pushes the pair apart faster than 0.1 d / dt.
  double repulsion_stiffness = 50.0;
  /// Gauss-Seidel sweeps over the contacts for the repulsion impulses (eq. 2-4), >= 1.
  int repulsion_sweeps = 2;
  /// Continuous intersection handling (sec. 3.3); off only to show leaks (the paper's Fig. 4, left).
  bool continuous = true;
  /// The cloth, at its start-of-step position, stops particles inside the fluid's sub-steps too
  /// (coupling/cloth_obstacle.hpp): needed at large steps, where one coupling per step piles layers up.
  bool substep_obstacle = true;
  CouplingScheme scheme = CouplingScheme::CARRIED_WATER;
  /// Rounds of CCD and impulses before the fail-safe takes the particles still colliding, >= 1.
  int max_ccd_iterations = 8;
  SlipCondition slip = SlipCondition::FRICTION;
  /// mu of eq. 8, >= 0; 0 = free slip. Ignored under NO_SLIP.
  double friction_coefficient = 0.0;
  BroadPhaseKind broad_phase = BroadPhaseKind::GRID;

  /// Whether these settings ask for a tangential boundary condition (sec. 3.4, eq. 7-8): the coupler builds
  /// one only when the scene lists the "friction" effect, so the loader and Simulation refuse the settings
  /// without it rather than ignore them.
  bool asks_tangential() const { return slip == SlipCondition::NO_SLIP || friction_coefficient > 0.0; }
};

}  // namespace drench
