#pragma once
/// Every cloth of a Bullet world as one drench::ClothEngine: the cloths' nodes and faces one after the other
/// in one ClothMesh (cloth 0's nodes first, then cloth 1's, ...; each face's indices moved by its cloth's
/// first node), so that the coupler, the leak audit and the wetting see one mesh, as ClothWithObstacles
/// (coupling/static_obstacles.hpp) puts a cloth and its obstacles in one. The world is stepped once per
/// step() whatever the number of cloths: one BulletCloth per soft body, none of them given the world, and
/// the set steps it (stepSimulation(dt, 0)) before each cloth captures its end positions.
///
/// A face or node of the mesh is found back in its cloth with locate_triangle and locate_node, so that a
/// report names the cloth and its own face (btSoftBody::m_faces index) or node (m_nodes index).

#include <cstdint>
#include <memory>
#include <vector>

#include <drench/bullet/bullet_cloth.hpp>

class btSoftBody;
class btSoftRigidDynamicsWorld;

namespace drench::bullet {

/// A node or face of one cloth of a set.
struct ClothElement {
  std::int64_t cloth = -1;  ///< the cloth's index in the set; -1: none (not a cloth's)
  std::int64_t index = -1;  ///< the node's index in its body's m_nodes, or the face's in m_faces
};

class BulletClothSet final : public ClothEngine {
 public:
  /// Couples the soft bodies `bodies` of `world`, in that order (cloth i is bodies[i]). The caller owns
  /// both and keeps them alive; nothing of them is changed here.
  /// @throws SceneError naming the index i: an empty list, bodies[i] null, repeated (also naming the
  ///         first), not in the world (world.getSoftBodyArray()), or without faces (a rope: drench couples
  ///         the water with faces only, and a rope let through would be passed through by the water);
  ///         drench::Error "soft body i: ..." when its mesh is not valid (ClothMesh::validate)
  BulletClothSet(btSoftRigidDynamicsWorld& world, const std::vector<btSoftBody*>& bodies);

  /// One cloth that owns its world (BulletCloth(settings, gravity)) and steps it itself, in its
  /// ClothSettings::substeps.
  /// @throws std::invalid_argument when `owned` is null or does not own its world
  explicit BulletClothSet(std::unique_ptr<BulletCloth> owned);

  ~BulletClothSet() override;
  BulletClothSet(const BulletClothSet&) = delete;
  BulletClothSet& operator=(const BulletClothSet&) = delete;

  /// Every cloth's begin_step, then their start positions and inverse masses into mesh(). A cloth whose
  /// node or face count changed (torn, cut, refined) rebuilds the mesh, and pieces() tells the new layout.
  void begin_step() override;
  /// Each cloth takes its nodes' share. @throws std::invalid_argument unless one entry per node of the set
  void apply_impulses(const Vec3Array& impulses) override;
  /// Each cloth takes its nodes' share. @throws std::invalid_argument unless one entry per node of the set
  void set_carried_masses(const ScalarArray& carried) override;
  /// Each cloth takes its nodes' water (BulletCloth::set_water_masses): node i of cloth c then weighs its
  /// dry mass plus water[first_node(c) + i] in Bullet, a pinned node staying pinned.
  /// @throws std::invalid_argument on a wrong size or a negative or non-finite entry (naming the node of
  ///         the set), before any cloth is changed
  void set_water_masses(const ScalarArray& water) override;
  /// One world step of dt (stepSimulation(dt, 0); an owned cloth steps its own world in its substeps),
  /// then every cloth's end positions into mesh().positions_t1.
  /// @param dt  (unit: s), > 0 and finite; @throws std::invalid_argument naming it otherwise
  void step(double dt) override;
  ClothMesh& mesh() override { return m_mesh; }
  const ClothMesh& mesh() const { return m_mesh; }
  /// The corrected end positions back into each cloth (BulletCloth::end_step), and what Bullet holds then
  /// back into mesh().positions_t1.
  /// @param dt  (unit: s), > 0 and finite; @throws std::invalid_argument naming it otherwise
  void end_step(double dt) override;
  /// m_v of every node of every cloth (unit: m/s), in the mesh's order.
  Vec3Array velocities() const override;
  /// The sum of the cloths' BulletCloth::total_mass (unit: kg): pinned nodes count 0.
  double total_mass() const override;
  /// Every cloth's BulletCloth::dry_node_masses, in the mesh's order: Bullet's own masses, each cloth's
  /// pinned nodes from its own mean area density.
  ScalarArray dry_node_masses() const override;

  /// Each cloth's nodes and faces in mesh(), cloth i the i-th (first_node, node_count, ...).
  std::vector<ClothPiece> pieces() const override;
  std::size_t cloth_count() const { return m_cloths.size(); }
  /// Cloth i. @throws std::out_of_range naming i and the count
  BulletCloth& cloth(std::size_t i);
  const BulletCloth& cloth(std::size_t i) const;
  /// The first node and face of cloth i in mesh(), and its counts (as of the last begin_step).
  /// @throws std::out_of_range naming i and the count
  std::size_t first_node(std::size_t i) const;
  std::size_t first_triangle(std::size_t i) const;
  std::size_t node_count(std::size_t i) const;
  std::size_t triangle_count(std::size_t i) const;
  /// The cloth of node `node` of mesh() and its index there; {-1, -1} for an index past the cloths' nodes.
  ClothElement locate_node(std::int64_t node) const;
  /// The cloth of face `triangle` of mesh() and its index in the body's m_faces; {-1, -1} for an index
  /// past the cloths' faces (an obstacle's face, in a mesh that appends obstacles after the cloths').
  ClothElement locate_triangle(std::int64_t triangle) const;

  /// The world the cloths live in.
  btSoftRigidDynamicsWorld& world() { return *m_world; }
  const btSoftRigidDynamicsWorld& world() const { return *m_world; }

 private:
  /// Offsets and mesh from the cloths' own meshes (their topology, inverse masses and positions).
  void rebuild();
  /// The cloths' start and end positions and inverse masses into mesh().
  void pull();
  std::size_t check_index(std::size_t i) const;

  std::vector<std::unique_ptr<BulletCloth>> m_cloths;
  btSoftRigidDynamicsWorld* m_world = nullptr;
  bool m_steps_world = false;  // false: the one (owned) cloth steps its own world
  std::vector<std::size_t>
      m_first_node;  // cloth count + 1 entries: cloth i's nodes are [first[i], first[i+1])
  std::vector<std::size_t> m_first_triangle;  // the same for faces
  ClothMesh m_mesh;
};

}  // namespace drench::bullet
