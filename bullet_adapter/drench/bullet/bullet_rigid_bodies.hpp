#pragma once
/// A Bullet world's rigid bodies as drench's RigidBodySource (coupling/rigid_bodies.hpp): every collision
/// object that is not a soft body and that Bullet's collision filter lets the water see, as the triangle mesh
/// of its shape (shape_mesh.hpp) where the world puts it, read at every step. Static objects hold the water
/// (and the cloth); kinematic ones, moved by the game between steps, sweep it along; dynamic ones take the
/// water's impulses through btRigidBody::applyCentralImpulse and applyTorqueImpulse, so the water pushes,
/// turns and floats them (Huber et al. 2013 sec. 5: rigid objects as triangle meshes in the same coupling).

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include <LinearMath/btTransform.h>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/bullet/shape_mesh.hpp>
#include <drench/coupling/rigid_bodies.hpp>

class btCollisionObject;
class btCollisionShape;
class btDynamicsWorld;

namespace drench::bullet {

/// Which of the world's objects hold the water, and how finely.
struct RigidBodyOptions {
  /// How a shape becomes triangles: curved facets, a plane's square (shape_mesh.hpp).
  ShapeMeshOptions mesh;
  /// The water's collision filter group and mask, as a btCollisionObject's: an object holds the water when
  /// (its group & water_mask) and (water_group & its mask) are both non-zero, as Bullet decides for two
  /// objects, and it has a contact response (a trigger with CF_NO_CONTACT_RESPONSE lets the water pass, as
  /// Bullet's solver lets rigid bodies pass it; Bullet's cloth still rests on it). The defaults
  /// (btBroadphaseProxy::DefaultFilter, AllFilter) see every other object Bullet's defaults make.
  int water_group = 1;
  int water_mask = -1;
};

/// The rigid bodies of `world`, for Simulation and CoupledWorld.
class BulletRigidBodies final : public RigidBodySource {
 public:
  /// @param world  the caller's world; borrowed, it must outlive this
  /// @throws drench::Error naming the object (its index in getCollisionObjectArray) and its shape
  ///         (getName) when an object the water sees has a shape shape_mesh does not support; SceneError
  ///         for options out of range
  BulletRigidBodies(btDynamicsWorld& world, RigidBodyOptions options = {});
  ~BulletRigidBodies() override;

  /// Checks, reading only, every object the water sees: its place and velocities must be finite and within
  /// kMaxCoordinate of the origin. A NaN body was blamed on a cloth node, and one parked at 1e15 m took 2 GB
  /// of the leak audit's cells before it threw.
  /// @throws drench::Error naming the object (index and shape) and the value
  void check_bodies() const;
  /// Keeps the points for begin_step, which meshes every btStaticPlaneShape under those near it (see
  /// cover_plane).
  void expect_points(const std::vector<const Vec3Array*>& point_sets, double reach) override;
  void begin_step(std::vector<RigidSurface>& surfaces) override;
  /// One Bullet step of dt (stepSimulation(dt, 0)): only for a world without a cloth engine.
  void step(double dt) override;
  void end_positions(std::vector<RigidSurface>& surfaces) override;
  void apply_impulses(std::size_t index, const RigidSurface& surface, const Vec3* node_impulses) override;
  /// Takes the move of `object` since the last step as a teleport: the next step places it where the game
  /// put it, as a body just added (the water inside its solid there moves out, release_trapped), instead of
  /// sweeping the water from where the last step left it, which throws the water in its path at the
  /// teleport's speed. For a respawn or a reset, as PhysX's setGlobalPose beside setKinematicTarget and
  /// Jolt's SetPosition beside MoveKinematic. A kinematic body moved through its motion state is put there
  /// at once (its world and interpolation transforms), so that Bullet's step neither sweeps it nor gives it
  /// the jump's speed. Call it between steps, after moving the object; one the water does not see is
  /// ignored.
  void teleported(const btCollisionObject& object);
  /// A point lies inside a convex object, or a convex child of a compound, when it is behind every face plane
  /// of its mesh (the faces that hold the water; Bullet's own shape rounds a box's edges by its margin), and
  /// inside a plane when below it (a triangle mesh or a heightfield, or such a child, has no inside and holds
  /// none). The ways out tried cross each face plane of the piece that holds the point; an end inside an
  /// appeared piece, or inside a solid by Bullet's contact query of a sphere of radius gap / 2 (the water's
  /// collision filter), is rejected, as are a way through another object the water sees by Bullet's ray
  /// query (a ground of triangles has no inside to end in) and a way through a cloth by `crosses`. Runs on
  /// the calling thread, which must be the only one using the world.
  std::size_t release_trapped(Vec3Array& positions, Vec3Array& velocities, double gap,
                              const CrossingTest& crosses, std::vector<std::uint8_t>& displaced) override;

  /// Notes the speed of every dynamic body the water sees, before a coupled step: what thrown_body compares
  /// with. CoupledWorld::step calls it.
  void note_speeds();
  /// The first dynamic body the water sees to which the water's impulses of the step (apply_impulses) gave
  /// more speed than water can, named with its speeds, or "": a blow-up of the body's coupling (a light or
  /// thin body thrown at tens of m/s) that no particle's or node's speed limit sees. The bound: twice the
  /// largest of the body's speed before the step (note_speeds) or as the water met it and the water's
  /// fastest particle (water can at most bring a body to its own speed), plus its
  /// weight's and its buoyancy's share over the step (g dt (1 + rest_density / the body's density, from its
  /// mesh's volume)), plus 1 m/s. Speeds are of the body's fastest point (centre and spin). What Bullet's own
  /// step gives a body (contacts, constraints, the game's forces) does not count.
  /// @param water_speed  the fastest particle over the step (unit: m/s)
  /// @param rest_density  the water's (unit: kg/m^3)
  /// @param gravity  (unit: m/s^2)
  /// @param dt  the step (unit: s)
  std::string thrown_body(double water_speed, double rest_density, const Vec3& gravity, double dt) const;
  /// The linear impulse the water gave the dynamic bodies, summed over all steps (unit: N s): with the
  /// fluid's momentum, what a test of momentum conservation adds up.
  const Vec3& impulse_given() const { return m_impulse_given; }
  /// The first object the water sees whose solid holds `point` deeper than `depth` (unit: m, > 0), named as
  /// in errors ("collision object 3 (Box)"), or "" when none does. Bullet's own contact query of a small
  /// sphere at the point: a shape with an inside (convex shapes, their compounds, a plane's lower side) can
  /// hold it; a triangle mesh or heightfield, with no inside, never does.
  std::string solid_holding(const Vec3& point, double depth) const;
  /// One line per finding since the last call, taken (cleared) by the call: an object added after
  /// construction whose shape is not supported (it does not hold the water, each object once), or a plane's
  /// mesh too wide.
  std::vector<std::string> take_warnings();

 private:
  struct Tracked;
  /// The cached state of `object`, its local mesh rebuilt when its shape, scaling or margin changed; null
  /// for an unsupported shape (warned about once).
  Tracked* track(const btCollisionObject& object, int index);
  bool sees(const btCollisionObject& object) const;
  /// A btStaticPlaneShape is unbounded: `t`'s mesh becomes the plane's grid cells, in chunks of
  /// kPlaneChunkCells, within a few chunks of every expected point near the plane, re-meshed when a point
  /// nears the edge of what is meshed; a new mesh is a new instance.
  void cover_plane(Tracked& t, const btCollisionObject& object, int index,
                   const std::vector<const Vec3Array*>& points);

  btDynamicsWorld& m_world;
  RigidBodyOptions m_options;
  std::unordered_map<const btCollisionObject*, std::unique_ptr<Tracked>> m_tracked;
  std::vector<Tracked*> m_current;  // per surface of the step, its object's state
  // The objects of the last begin_step that were not in the step before as they are now
  std::vector<std::pair<const btCollisionObject*, const Tracked*>> m_appeared;
  std::unordered_set<const btCollisionObject*> m_teleported;  // teleported() since the last begin_step
  std::vector<std::string> m_warnings;
  std::vector<const Vec3Array*> m_points;  // expect_points' arrays, until the next begin_step
  double m_reach = 0;
  Vec3 m_impulse_given = Vec3::Zero();
  /// A dynamic body's speed at note_speeds and the velocity changes the water's impulses gave it since
  /// (unit: m/s, rad/s): what thrown_body compares.
  struct Kick {
    double start = 0.0;  // its fastest point speed at note_speeds (unit: m/s)
    Vec3 linear = Vec3::Zero();
    Vec3 angular = Vec3::Zero();
    double met = 0.0;  // its fastest point speed without them, as the water met it (unit: m/s)
  };
  std::unordered_map<const btCollisionObject*, Kick> m_kicks;  // the bodies note_speeds found
  std::uint64_t m_step = 0;
  std::uint64_t m_instances = 0;  // bodies tracked so far: each new one's RigidSurface::instance
};

}  // namespace drench::bullet
