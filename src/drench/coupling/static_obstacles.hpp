#pragma once
/// Static triangle meshes that hold fluid: the paper's rigid objects, which sec. 5 treats as triangle meshes
/// (Fig. 8's "V-shaped rigid plane"). They are coupled exactly as the cloth is, as nodes of inverse mass 0:
/// the same repulsion (eq. 1-4), continuous handling (eq. 5-6), friction (eq. 7-8), sub-step obstacle and
/// leak audit, and the surface reconstruction respects them (sec. 4).

#include <memory>
#include <string>
#include <vector>

#include <drench/common/triangle_mesh.hpp>
#include <drench/coupling/cloth_engine.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/rigid_bodies.hpp>

namespace drench {

/// One element of a scene's `obstacles` (docs/scenes.md).
struct ObstacleSettings {
  /// "v_plane" (two planes meeting along a line parallel to z, opening upwards) or the path of an OBJ file.
  std::string mesh = "v_plane";
  /// v_plane: the middle of the line where the planes meet; OBJ: added to every vertex (unit: m).
  Vec3 center = Vec3::Zero();
  double scale = 1.0;           ///< OBJ: every vertex is multiplied by this before `center` is added; > 0
  double angle_deg = 90.0;      ///< v_plane: the angle between the planes (unit: degree), in (0, 180)
  double size = 0.25;           ///< v_plane: each plane's extent from the line where they meet (unit: m), > 0
  double width = 0.3;           ///< v_plane: the extent along z (unit: m), > 0
  double triangle_size = 0.02;  ///< v_plane: the largest edge of its grid's squares (unit: m), > 0
  /// Work of adhesion of water on the obstacle (unit: N/m), >= 0, used by the "adhesion" effect
  /// (AdhesionSettings): 0.072, a contact angle of 90 degrees (most plastics are near it).
  double adhesion = 0.072;
};

/// The most nodes a v_plane may have: far beyond what the coupling steps in a frame.
inline constexpr double kMaxVPlaneNodes = 1e7;

/// The V of ObstacleSettings: both planes on one grid of nodes, sharing the nodes where they meet (no crack
/// to leak through), triangles counter-clockwise seen from inside the V. Small triangles, not four large
/// ones, because the coupling's broad phase pairs particles with triangles by bounding box
/// (coupling/broad_phase.hpp): a large slanted face would be a candidate for every particle inside the V.
/// @throws SceneError naming `key` and the setting out of range, or triangle_size when the V would have more
///         than kMaxVPlaneNodes nodes
TriangleMesh v_plane_mesh(const ObstacleSettings& settings, const std::string& key = "obstacles[0]");

/// Throws drench::Error naming `what` and the first problem: no triangle, an index out of range, a repeated
/// index or zero area in a triangle, a vertex not finite.
void validate_triangle_mesh(const TriangleMesh& mesh, const std::string& what);

/// A cloth engine (or none), static obstacles and moving rigid bodies (or none) seen by the coupling as one
/// mesh: the cloth's M nodes first, then every static obstacle's, then every rigid body's surface as its
/// RigidBodySource gave it for this step, all of inverse mass 0 but the cloth's. Everything the coupled step
/// does to a ClothEngine passes to the cloth for its own nodes; obstacle nodes take no impulse and no carried
/// mass, and a dynamic body's nodes pass theirs to the body (apply_impulses, apply_body_impulses). The static
/// obstacles and static bodies hold the cloth as they hold the water: after the engine's step, the cloth's
/// nodes are coupled with their faces as particles are (sec. 3's repulsion and continuous handling, eq. 1-6,
/// free slip), so no node passes a face, and the engine takes the correction at end_step. Moving bodies meet
/// the cloth in the engine's own step (Bullet's soft-rigid contact), which gives the body the cloth's push.
class ClothWithObstacles final : public ClothEngine {
 public:
  /// @param cloth  the scene's cloth, or nullptr; borrowed, it must outlive this
  /// @param obstacles  static meshes, each valid (validate_triangle_mesh); may be empty when `bodies` is
  /// given
  /// @param clearance  the distance the obstacles keep the cloth's nodes at (unit: m), > 0 and finite: the
  ///        coupling's cloth thickness, which the water keeps too
  /// @param bodies  the world's rigid bodies, read at every step, or nullptr; borrowed, it must outlive this.
  ///        Without a cloth it also steps the world (RigidBodySource::step).
  /// @throws drench::Error when an obstacle is not valid, naming it (`obstacles[i]`), or there is neither an
  ///         obstacle nor `bodies`; SceneError for a clearance out of range
  ClothWithObstacles(ClothEngine* cloth, std::vector<TriangleMesh> obstacles, double clearance = 0.001,
                     RigidBodySource* bodies = nullptr);
  ~ClothWithObstacles() override;

  void begin_step() override;
  /// The cloth's part to the cloth; a dynamic body's part to its body (RigidBodySource::apply_impulses).
  void apply_impulses(const Vec3Array& impulses) override;
  void set_carried_masses(const ScalarArray& carried) override;
  void step(double dt) override;
  ClothMesh& mesh() override { return m_mesh; }
  void end_step(double dt) override;
  /// The cloth's velocities, 0 for static obstacles, each body's node velocities at the start of the step.
  Vec3Array velocities() const override;
  /// The cloth's pieces (its engine's), first in mesh(); none without a cloth. The obstacles and bodies
  /// follow them.
  std::vector<ClothPiece> pieces() const override;
  double total_mass() const override;

  /// Gives each dynamic body the impulses the water gave its nodes in this step (unit: N s, one per node of
  /// mesh(), e.g. Coupler::node_impulses); the other entries are ignored. Call after begin_step(), before
  /// the next one: before step() the bodies move with them in it.
  /// @throws std::invalid_argument if `node_impulses` does not have one entry per node of mesh()
  void apply_body_impulses(const Vec3Array& node_impulses);

  /// Meets the dynamic bodies and the water they would sweep in a step of dt (coupling/swept_water.hpp):
  /// changes the swept particles' `velocities` and gives the bodies their share before they move; their
  /// velocities() follow. Call after begin_step(), before the water moves.
  /// @param rest_density  the water's (unit: kg/m^3)
  /// @param positions, masses, velocities  N particles (unit: m, kg, m/s)
  /// @return how many particles were swept
  std::size_t meet_swept_water(double dt, double rest_density, const Vec3Array& positions,
                               const ScalarArray& masses, Vec3Array& velocities);

  /// Nodes of the cloth, the first of mesh()'s (0 without a cloth).
  std::size_t cloth_nodes() const { return m_cloth ? m_cloth->mesh().node_count() : 0; }
  const std::vector<TriangleMesh>& obstacles() const { return m_obstacles; }
  /// The rigid bodies' surfaces of the current step, in mesh() order after the static obstacles.
  const std::vector<RigidSurface>& rigid_surfaces() const { return m_surfaces; }
  /// Per surface of rigid_surfaces(), its first node in mesh().
  const std::vector<std::size_t>& rigid_surface_first_nodes() const { return m_surface_first; }
  /// What holding the cloth off the obstacles did, summed over steps: `contacts` node-face pairs within the
  /// clearance, `ccd_impacts` nodes stopped before a face.
  const CouplingStepStats& cloth_contact_stats() const { return m_hold_stats; }
  /// Wall time spent in the bodies' own calls, summed over steps (unit: s): RigidBodySource::begin_step,
  /// end_positions (with the copy of their end positions into mesh()) and apply_impulses. A caller that
  /// times step() or apply_body_impulses as another stage takes this share out of it (Simulation's rigid
  /// stage).
  double body_seconds() const { return m_body_seconds; }

 private:
  /// Copies the cloth's and the bodies' parts of mesh(); rebuilds the whole mesh if its layout changed.
  void pull();
  /// Lays out mesh() and the cloth holder's mesh anew for the current cloth and bodies.
  void rebuild();
  /// The cloth's predicted motion corrected so that no node passes an obstacle's face (see the class).
  void hold_cloth_off_obstacles(double dt);
  /// Passes the bodies' part of `impulses` (one per node of mesh()) to the dynamic bodies.
  void give_bodies(const Vec3Array& impulses);

  ClothEngine* m_cloth;
  std::vector<TriangleMesh> m_obstacles;
  RigidBodySource* m_bodies;
  std::vector<RigidSurface> m_surfaces;
  std::vector<std::size_t> m_surface_first;  // per surface, its first node in m_mesh
  std::vector<std::size_t> m_rigid_first;    // per surface, its first node in m_rigid, or SIZE_MAX
  std::vector<std::uint64_t> m_layout;       // what m_mesh was built for
  ClothMesh m_mesh;
  bool m_built = false;
  ClothMesh m_rigid;                  // the static obstacles and bodies, for the cloth's nodes to meet
  std::unique_ptr<Coupler> m_holder;  // couples the cloth's nodes, as particles, with m_rigid
  CouplingStepStats m_hold_stats;
  double m_body_seconds = 0;
};

}  // namespace drench
