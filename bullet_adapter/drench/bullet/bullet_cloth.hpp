#pragma once
/// One Bullet btSoftBody as a drench::ClothEngine (Huber et al. 2013 sec. 5: the coupling needs only start
/// and end positions of the nodes). The adapter copies node positions out of Bullet around Bullet's step and
/// writes the coupling's corrections back as positions and velocities:
///
///   begin_step()   positions_t0 = m_x                       (and inverse masses, from m_im)
///   step(dt)       world->stepSimulation(dt / substeps, 0), substeps times (an owned cloth's
///                  ClothSettings::substeps, else 1); then capture_end()
///   capture_end()  positions_t1 = m_x, remembered as the predicted end positions
///   (the coupler corrects mesh().positions_t1 in place)
///   end_step(dt)   for every node that can move: m_x = corrected, m_v += (corrected - predicted) / dt,
///                  and positions_t1 = m_x (rounded to float with DRENCH_BULLET_PRECISION=single)
///
/// Why between steps: Bullet's next step starts from m_x and m_v (predictMotion: v += g dt, q = x, x += v
/// dt), so a change written there survives; one written inside Bullet's step after the soft-body solve would
/// be overwritten by v = (x - q) / dt. m_q (the step's start) is left alone: Bullet reads it only inside a
/// step and sets it to m_x at the start of the next one.
///
/// Bullet 3.24 advances soft bodies by dt rounded to float, even in its double build
/// (btSoftRigidDynamicsWorld::predictUnconstraintMotion passes float(timeStep)): 1 ms becomes 1 ms (1
/// + 4.7e-8). The adapter uses the caller's dt; the difference is far below anything the coupling resolves.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/coupling/cloth_engine.hpp>
#include <drench/coupling/cloth_mesh.hpp>

class btSoftBody;
class btSoftRigidDynamicsWorld;

namespace drench::bullet {

/// Throws std::invalid_argument "<where>: dt must be > 0 and finite, got <dt> s" unless dt (unit: s) is
/// both: the check of every adapter call that takes a step's length.
void check_time_step(const std::string& where, double dt);

class BulletCloth final : public ClothEngine {
 public:
  /// Attaches to a soft body the caller owns and keeps alive for this object's lifetime (it is not copied).
  /// Nothing of the body is changed here: its margin, iterations and masses stay the caller's.
  /// @param world  the world the body lives in, stepped by step(dt); or nullptr when the caller steps the
  ///        world itself between begin_step() and capture_end() (then step(dt) only captures). Several
  ///        cloths in one world: BulletClothSet (bullet_cloth_set.hpp) steps the world once for all of them.
  explicit BulletCloth(btSoftBody& body, btSoftRigidDynamicsWorld* world = nullptr);

  /// Builds its own btSoftRigidDynamicsWorld (collision configuration, dispatcher, broadphase, solver) with
  /// soft-body and rigid gravity `gravity` (unit: m/s^2), and the cloth of `settings` in it (see
  /// create_cloth_body in bullet_adapter/drench/bullet/soft_body_builder.hpp). Deactivation is off: the cloth
  /// never sleeps.
  /// @throws SceneError for settings out of range (the message names the setting) or an unusable OBJ file
  /// (the
  ///         message names the file), or a non-finite gravity
  BulletCloth(const ClothSettings& settings, const Vec3& gravity);

  ~BulletCloth() override;
  BulletCloth(const BulletCloth&) = delete;
  BulletCloth& operator=(const BulletCloth&) = delete;

  /// positions_t0 = current node positions; inverse masses re-read from Bullet (the caller may pin or unpin
  /// nodes between steps: with set_node_masses, not btSoftBody::setMass, which resets the rest lengths of a
  /// stretched cloth; soft_body_builder.hpp), triangles re-read when the body's node or face count changed.
  void begin_step() override;

  /// node.m_v += J m_im for every node: Bullet's next step integrates them with the cloth's links. Call
  /// between begin_step() and the world's step.
  /// @throws std::invalid_argument if `impulses` does not have one entry per node
  void apply_impulses(const Vec3Array& impulses) override;

  /// node.m_im = 1 / (m + carried) for every node with m_im > 0, until capture_end() puts the saved m_im
  /// back bit for bit. updateLinkConstants() follows both changes: the links' m_c0 depend on m_im. Never
  /// setMass, whose flag makes Bullet's next step reset every rest length to the current length
  /// (set_node_masses in soft_body_builder.hpp). Call between begin_step() and the world's step.
  /// @throws std::invalid_argument if `carried` does not have one entry per node
  void set_carried_masses(const ScalarArray& carried) override;

  /// node.m_im = 1 / (dry mass + water[i]) for every node with m_im > 0, the dry masses being the nodes' at
  /// the first call; a tear since (begin_step finding more nodes or other faces) moves them as Bullet moved
  /// the masses: an old node's scales with its whole mass, a new node's is its mass less the share of water
  /// that came with it, so the cloth's dry mass stays what it was. And updateLinkConstants() (never setMass:
  /// see set_carried_masses). Pinning or unpinning nodes after the first call is not supported: their dry
  /// mass is not re-read.
  /// @throws std::invalid_argument on a wrong size or a negative or non-finite entry
  void set_water_masses(const ScalarArray& water) override;

  /// With a world (owned, or given at attach): stepSimulation(dt / substeps, 0) `substeps` times (an owned
  /// cloth's ClothSettings::substeps, an attached one 1), which steps every body in
  /// that world, then capture_end(). Without one: capture_end() only; the caller has stepped the world by dt
  /// since begin_step().
  /// @param dt  (unit: s), > 0 and finite
  /// @throws std::invalid_argument naming dt otherwise, before anything is changed
  void step(double dt) override;

  /// positions_t1 = current node positions, remembered as Bullet's prediction for end_step; the node masses
  /// set_carried_masses changed are the body's own again.
  void capture_end();

  ClothMesh& mesh() override { return m_mesh; }
  const ClothMesh& mesh() const { return m_mesh; }

  /// Takes the coupling's corrections back into Bullet, node by node:
  /// - unchanged positions_t1 (bitwise): nothing is written, m_x and m_v stay bit-identical;
  /// - a node that can move (m_im > 0): m_x = positions_t1, m_v += (positions_t1 - predicted) / dt;
  /// - a pinned node (m_im == 0): the change is ignored (counted in ignored_pinned_corrections()) and
  ///   positions_t1 is reset to the predicted position, so the mesh shows where Bullet keeps the node. The
  ///   coupler never moves such nodes; this guards other callers and keeps kinematic nodes under the user's
  ///   control (Bullet moves a pinned node only through a raw m_v write);
  /// - a non-finite positions_t1: ignored the same way and counted in non_finite_corrections(); NaN never
  ///   reaches Bullet.
  /// Normals are recomputed when a node moved (Bullet updates them only at the end of its step).
  /// @param dt  the step's length (unit: s), > 0 and finite
  /// @throws std::invalid_argument naming dt otherwise, before anything is changed
  void end_step(double dt) override;

  /// The dry cloth's node masses (unit: kg), M entries, > 0: Bullet's, 1 / m_im, for the nodes it moves (as
  /// they were before the first set_water_masses); a pinned node (m_im = 0) gets the mass its faces' area
  /// would have at the cloth's mean area density (the moving nodes' mass over their share of the faces'
  /// area, a third of each face's area to each of its nodes, at the current positions). A cloth whose every
  /// node is pinned takes ClothSettings' default density (0.2 kg/m^2); a pinned node in no face (it can
  /// take no water) the cloth's mean node mass.
  ScalarArray dry_node_masses() const override;

  /// m_v of every node (unit: m/s), M entries.
  Vec3Array velocities() const override;
  /// Sum of the masses of the nodes Bullet moves (unit: kg), btSoftBody::getTotalMass: pinned nodes count 0.
  double total_mass() const override;

  btSoftBody& body() { return *m_body; }
  const btSoftBody& body() const { return *m_body; }
  /// The world step(dt) steps: the owned one, the one given at attach, or nullptr.
  btSoftRigidDynamicsWorld* world() { return m_world; }
  bool owns_world() const { return m_owned != nullptr; }

  /// Corrections of pinned nodes that end_step ignored, over this object's life.
  std::int64_t ignored_pinned_corrections() const { return m_ignored_pinned; }
  /// Non-finite corrections that end_step ignored, over this object's life.
  std::int64_t non_finite_corrections() const { return m_non_finite; }

 private:
  struct OwnedWorld;

  void read_topology();
  /// Before read_topology of a cloth a game tore since the last step (more nodes or other faces): the dry
  /// masses of its old and new nodes, as Bullet moved its masses about (see the .cpp).
  void follow_dry_masses();
  void read_inverse_masses();
  void restore_masses();

  std::unique_ptr<OwnedWorld> m_owned;  // first: destroyed last, after nothing else points into it
  btSoftBody* m_body = nullptr;
  int m_substeps = 1;  // owned cloth: ClothSettings::substeps; attached: 1
  std::vector<std::pair<int, double>> m_saved_inverse_masses;  // node, its own m_im, while carrying water
  ScalarArray m_dry_inverse_masses;   // m_im of every node before the first set_water_masses
  ScalarArray m_last_water;           // what the last set_water_masses weighed each node with (unit: kg)
  ScalarArray m_left_inverse_masses;  // m_im as drench last left it (set_water_masses, follow_dry_masses)
  btSoftRigidDynamicsWorld* m_world = nullptr;
  ClothMesh m_mesh;
  Vec3Array m_predicted;  // M, Bullet's end positions before the coupling
  std::int64_t m_ignored_pinned = 0;
  std::int64_t m_non_finite = 0;
};

/// An owned BulletCloth (see its constructor), as the ClothEngineFactory of coupling/cloth_engine.hpp builds
/// it.
/// @throws SceneError as BulletCloth(settings, gravity)
std::unique_ptr<ClothEngine> make_bullet_cloth_engine(const ClothSettings& settings, const Vec3& gravity);

/// The factory a scene runner takes to build Bullet cloth: make_bullet_cloth_engine.
ClothEngineFactory cloth_engine_factory();

}  // namespace drench::bullet
