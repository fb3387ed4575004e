#pragma once
/// A cloth simulator seen from the coupled step (Huber et al. 2013 sec. 5): it advances alone, exposes start
/// and end positions as a ClothMesh, and takes the coupling's corrections back. The core knows no engine; the
/// Bullet adapter (bullet_adapter/) implements this for btSoftBody, and a scene runner receives engines from
/// a factory.

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/coupling/cloth_layout.hpp>
#include <drench/coupling/cloth_mesh.hpp>

namespace drench {

/// A rectangular patch of cloth or a mesh from an OBJ file, as a scene describes it (docs/scenes.md,
/// `cloth`).
/// The fewest position iterations Bullet's cloth may take: 1 blows the 57 x 57 patch up at dt = 1 ms
/// (../shared/notes/bullet-and-fcl.md).
inline constexpr int kMinClothPositionIterations = 4;

struct ClothSettings {
  std::string mesh = "patch";      ///< "patch" (a regular grid) or the path of an OBJ file (triangulated)
  Vec3 center = Vec3::Zero();      ///< patch centre (unit: m); the patch lies in the plane y = center.y
  double size_x = 0.6;             ///< patch extent along x (unit: m), > 0
  double size_z = 0.6;             ///< patch extent along z (unit: m), > 0
  int nodes_x = 57;                ///< patch nodes along x, >= 2
  int nodes_z = 57;                ///< patch nodes along z, >= 2
  double area_density = 0.2;       ///< mass per area (unit: kg/m^2), > 0
  std::string pinned = "corners";  ///< "corners", "none", or "corner" (one corner, x and z smallest)
  int position_iterations = 4;     ///< Bullet's piterations, in [kMinClothPositionIterations, 1000]
  int substeps = 1;  ///< cloth steps per simulation step, >= 1; the coupling still runs once per
                     ///< step. A position-based cloth stretches less under load with smaller steps
  double stretch_stiffness = 1.0;  ///< Bullet's linear stiffness kLST, in (0, 1]
  double bending_stiffness = 0.5;  ///< stiffness of the bending links (distance 2), in [0, 1]; 0 = none
  double damping = 0.0;            ///< Bullet's kDP, in [0, 1]
  /// Work of adhesion of water on the cloth (unit: N/m), >= 0, used by the "adhesion" effect
  /// (AdhesionSettings): Dupre's sigma (1 + cos theta); 0.144, water wets cotton fully (theta 0); about 0.05
  /// for a water-repellent fabric (theta 110 degrees).
  double adhesion = 0.144;
  /// A node faster than this at the end of a step stops the run with RUNAWAY_NODE (unit: m/s), > 0;
  /// nullopt: no limit. Far above any cloth under water, so only a blow-up reaches it (docs/scenes.md gives
  /// the demo scenes' fastest nodes).
  std::optional<double> max_speed = 100.0;
  /// An edge stretched beyond this strain, (length - rest length) / rest length with the rest length the
  /// edge's length when the simulation was built, stops the run with CLOTH_OVERSTRETCHED (dimensionless),
  /// > 0; nullopt: no limit. Far above the strains the demo scenes' cloths reach at their pins and hold, far
  /// below those of a jet that tears the cloth (docs/scenes.md gives both).
  std::optional<double> max_strain = 10.0;
};

/// One cloth in a coupled simulation.
class ClothEngine {
 public:
  virtual ~ClothEngine() = default;

  /// Records the node positions at the start of the step (mesh().positions_t0).
  virtual void begin_step() = 0;
  /// Adds impulses to the node velocities before step(): v += J / m per node, pinned nodes unchanged.
  /// `impulses` has M entries (unit: N s). The cloth solver then carries them through its own constraints
  /// within the step, so a load on a few nodes pulls the cloth around them along (drench's sub-step obstacle
  /// uses this).
  virtual void apply_impulses(const Vec3Array& impulses) = 0;
  /// For the next step() only, node i moves as if it weighed m_i + carried[i] (unit: kg, M entries, >= 0):
  /// the water resting on it (coupling/carried_water.hpp), which the engine's constraints must accelerate
  /// with the node. Nodes with inverse mass 0 stay pinned. After step() the node masses are the engine's own
  /// again, exactly, and nothing else about the cloth (rest lengths) has changed. The engine applies its
  /// gravity (the scene's) to the carried mass too; the caller removes that with an impulse, since the water
  /// fell in the fluid's step. Call between begin_step() and step(); an engine whose nodes are all pinned may
  /// ignore it.
  /// @throws std::invalid_argument if `carried` does not have one entry per node
  virtual void set_carried_masses(const ScalarArray& carried) = 0;
  /// From now on node i weighs its dry mass plus water[i] (unit: kg, M entries, >= 0, finite): the water the
  /// cloth holds (wetting/cloth_wetting.hpp), so a wet cloth sags more. The dry masses are the node masses
  /// at the first call; nodes with inverse mass 0 stay pinned. Rest lengths do not change. Call between
  /// steps (after end_step). An engine that cannot change its node masses keeps this default, which throws.
  /// @throws std::logic_error from such an engine; std::invalid_argument on a wrong size or a negative or
  ///         non-finite entry
  virtual void set_water_masses(const ScalarArray& water) {
    (void)water;
    throw std::logic_error("this cloth engine cannot change its node masses: it does not support wetting");
  }
  /// Advances the cloth alone by dt (unit: s); afterwards mesh().positions_t1 holds the predicted end
  /// positions.
  virtual void step(double dt) = 0;
  /// Start and end positions, inverse masses, triangles. The coupler corrects positions_t1 in place.
  virtual ClothMesh& mesh() = 0;
  /// The same mesh, read-only (output, statistics).
  const ClothMesh& mesh() const { return const_cast<ClothEngine*>(this)->mesh(); }
  /// Takes the corrected end positions back: positions = positions_t1, velocity += (corrected - predicted) /
  /// dt. Leaves in positions_t1 what the engine now holds (an engine that stores floats rounds), since the
  /// leak audit after it checks that cloth.
  virtual void end_step(double dt) = 0;
  /// The node masses of the dry cloth as the engine holds them (unit: kg), M entries, > 0 and finite, nodes
  /// the engine pins included (they hold water too: the engine gives them a mass of their own, and says
  /// how); empty when the engine cannot tell (this default). The wetting's capacities when the scene
  /// describes no cloth of its own (effect_registry.cpp, build_wetting).
  virtual ScalarArray dry_node_masses() const { return {}; }
  /// Where each of the engine's cloths lies in mesh(), as of construction or the last begin_step: back to
  /// back from node and face 0. A cloth torn, cut or refined between two steps has more nodes (appended to
  /// its own) and maybe more faces; the coupled step moves what it keeps per node and face along
  /// (cloth_layout.hpp). This default: one cloth, the whole mesh.
  virtual std::vector<ClothPiece> pieces() const {
    const ClothMesh& m = mesh();
    return {ClothPiece{0, m.node_count(), 0, m.triangle_count()}};
  }
  /// Current node velocities (unit: m/s), M entries; for output and statistics.
  virtual Vec3Array velocities() const = 0;
  /// Total mass of the cloth (unit: kg).
  virtual double total_mass() const = 0;
};

/// Builds the cloth engine of a scene. `gravity` in m/s^2. Throws SceneError for settings it cannot honour.
using ClothEngineFactory =
    std::function<std::unique_ptr<ClothEngine>(const ClothSettings& settings, const Vec3& gravity)>;

}  // namespace drench
