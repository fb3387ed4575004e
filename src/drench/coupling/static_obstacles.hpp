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
};

/// The V of ObstacleSettings: both planes on one grid of nodes, sharing the nodes where they meet (no crack
/// to leak through), triangles counter-clockwise seen from inside the V. Small triangles, not four large
/// ones, because the coupling's broad phase pairs particles with triangles by bounding box
/// (coupling/broad_phase.hpp): a large slanted face would be a candidate for every particle inside the V.
/// @throws SceneError naming `key` and the setting out of range
TriangleMesh v_plane_mesh(const ObstacleSettings& settings, const std::string& key = "obstacles[0]");

/// Throws drench::Error naming `what` and the first problem: no triangle, an index out of range, a repeated
/// index or zero area in a triangle, a vertex not finite.
void validate_triangle_mesh(const TriangleMesh& mesh, const std::string& what);

/// A cloth engine (or none) and static obstacles seen by the coupling as one mesh: the cloth's M nodes
/// first, then every obstacle's, of inverse mass 0 and never moving. Everything the coupled step does to a
/// ClothEngine passes to the cloth for its own nodes; obstacle nodes take no impulse and no carried mass.
/// The obstacles hold the cloth as they hold the water: after the engine's step, the cloth's nodes are
/// coupled with the obstacles' faces as particles are (sec. 3's repulsion and continuous handling, eq. 1-6,
/// free slip), so no node passes a face, and the engine takes the correction at end_step.
class ClothWithObstacles final : public ClothEngine {
 public:
  /// @param cloth  the scene's cloth, or nullptr; borrowed, it must outlive this
  /// @param obstacles  one or more meshes, each valid (validate_triangle_mesh)
  /// @param clearance  the distance the obstacles keep the cloth's nodes at (unit: m), > 0 and finite: the
  ///        coupling's cloth thickness, which the water keeps too
  /// @throws drench::Error when an obstacle is not valid, naming it (`obstacles[i]`); SceneError for a
  ///         clearance out of range
  ClothWithObstacles(ClothEngine* cloth, std::vector<TriangleMesh> obstacles, double clearance = 0.001);
  ~ClothWithObstacles() override;

  void begin_step() override;
  void apply_impulses(const Vec3Array& impulses) override;
  void set_carried_masses(const ScalarArray& carried) override;
  void step(double dt) override;
  ClothMesh& mesh() override { return m_mesh; }
  void end_step(double dt) override;
  Vec3Array velocities() const override;
  double total_mass() const override;

  /// Nodes of the cloth, the first of mesh()'s (0 without a cloth).
  std::size_t cloth_nodes() const { return m_cloth ? m_cloth->mesh().node_count() : 0; }
  const std::vector<TriangleMesh>& obstacles() const { return m_obstacles; }
  /// What holding the cloth off the obstacles did, summed over steps: `contacts` node-face pairs within the
  /// clearance, `ccd_impacts` nodes stopped before a face.
  const CouplingStepStats& cloth_contact_stats() const { return m_hold_stats; }

 private:
  /// Copies the cloth's part of mesh() from the engine; rebuilds the whole mesh if its size changed.
  void pull_cloth();
  /// The cloth's predicted motion corrected so that no node passes an obstacle's face (see the class).
  void hold_cloth_off_obstacles(double dt);

  ClothEngine* m_cloth;
  std::vector<TriangleMesh> m_obstacles;
  ClothMesh m_mesh;
  std::size_t m_cloth_nodes = 0, m_cloth_triangles = 0;
  bool m_built = false;
  ClothMesh m_rigid;                  // the obstacles alone, for the cloth's nodes to be coupled with
  std::unique_ptr<Coupler> m_holder;  // couples the cloth's nodes, as particles, with m_rigid
  CouplingStepStats m_hold_stats;
};

}  // namespace drench
