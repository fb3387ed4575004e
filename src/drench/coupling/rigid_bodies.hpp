#pragma once
/// Rigid bodies that move: a game's boxes, balls and paddles seen by the coupling. Huber et al. 2013 sec. 5
/// treats rigid objects as triangle meshes in the same coupling as the cloth; here those meshes move between
/// the start and the end of a step as their bodies do, so the same repulsion (eq. 1-4), continuous handling
/// (eq. 5-6), friction (eq. 7-8) and leak audit hold the water against them. The coupler sees their nodes
/// with inverse mass 0 (a body does not deform); what the water gives those nodes goes to the body as one
/// impulse and one angular impulse, so momentum passes between water and body exactly. The core knows no
/// engine: the Bullet adapter (bullet_adapter/drench/bullet/bullet_rigid_bodies.hpp) implements
/// RigidBodySource.

#include <cstdint>
#include <functional>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// How a rigid body moves (Bullet's and Jolt's three kinds).
enum class RigidMotion {
  STATIC,     ///< never moves; also holds the cloth off (ClothWithObstacles)
  KINEMATIC,  ///< moved by the game; the water cannot push it
  DYNAMIC,    ///< moved by its engine; takes the water's impulses
};

/// One rigid body's surface over one step.
struct RigidSurface {
  std::uint64_t key = 0;  ///< the same body has the same key at every step (the adapter: its address)
  /// Changes when `key` names a new body: a game that removes a body and adds another may get the same
  /// address back, and the new body must not start where the old one ended.
  std::uint64_t instance = 0;
  RigidMotion motion = RigidMotion::STATIC;
  std::vector<Triangle> triangles;  ///< F, indices < M, counter-clockwise seen from outside
  Vec3Array positions_t0;           ///< M nodes at the start of the step (unit: m)
  Vec3Array positions_t1;           ///< M nodes at the end of the engine's step (unit: m)
  Vec3Array velocities_t0;          ///< M node velocities at the start of the step (unit: m/s)
  /// A DYNAMIC body's inverse mass (unit: 1/kg), its centre of mass and that centre's velocity at the start
  /// of the step (unit: m, m/s): what it and the water it sweeps share (meet_swept_water). 0, the default,
  /// for every static or kinematic body, which the coupling treats as infinitely heavy.
  double inverse_mass = 0.0;
  Vec3 centre = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
};

/// The rigid bodies of a world, read at every step so that bodies the game adds, removes or moves are
/// followed. The coupled step calls begin_step, then (unless a cloth engine steps the same world) step,
/// then end_positions, then apply_impulses for the water's impulses of that step.
class RigidBodySource {
 public:
  virtual ~RigidBodySource() = default;
  /// Where the water and the cloths may be during the next step: the points of `point_sets` (unit: m; the
  /// particles, the cloths' nodes) and how near to them a face may meet one within it, `reach` (unit: m,
  /// >= 0: their motion over the step and the coupling's range). A source
  /// with an unbounded surface (a game's ground plane) meshes it under these points, wherever they are. The
  /// arrays must stay valid until the next begin_step returns; the coupled step calls this just before it.
  /// The default ignores them.
  virtual void expect_points(const std::vector<const Vec3Array*>& point_sets, double reach) {
    (void)point_sets;
    (void)reach;
  }
  /// The bodies now: fills `surfaces` (replacing what it held) with every body that holds water, its
  /// triangles, positions_t0 and velocities_t0, positions_t1 = positions_t0, and a dynamic body's
  /// inverse_mass, centre and velocity (a source may leave them 0).
  virtual void begin_step(std::vector<RigidSurface>& surfaces) = 0;
  /// Advances the bodies alone by dt (unit: s): used when no cloth engine steps the world they are in.
  virtual void step(double dt) = 0;
  /// After the world's step: positions_t1 of every surface begin_step gave, in the same order.
  virtual void end_positions(std::vector<RigidSurface>& surfaces) = 0;
  /// The impulses the water gave the nodes of surface `index` (unit: N s, one per node of surfaces[index]),
  /// to be applied to its body at the nodes' end positions: the sum as a linear impulse, the sum of moments
  /// about the centre of mass as an angular impulse. Static and kinematic bodies take nothing.
  virtual void apply_impulses(std::size_t index, const RigidSurface& surface, const Vec3* node_impulses) = 0;
  /// Which straight moves of points, each from from[k] to to[k] (unit: m, N each), pass through or end on a
  /// face the water stays on one side of (a cloth's, where it starts the step): crosses[k] (output, N flags)
  /// nonzero. release_trapped's ways out must not; it asks once for all of them (moves_crossing_cloth).
  using CrossingTest =
      std::function<void(const Vec3Array& from, const Vec3Array& to, std::vector<std::uint8_t>& crosses)>;

  /// Called after begin_step, before the water moves: moves every point that a body new in that step (added,
  /// replaced or re-meshed since the step before) holds inside its solid out of it, by the shortest way the
  /// source finds that ends `gap` outside the body, inside no other solid, no nearer than `gap` to any other
  /// point and without crossing a cloth (`crosses`), and gives it the body's velocity there; flags the points
  /// with no such way in `displaced` (the water the body displaces, which the caller removes). The body's
  /// faces close around the water it appears in, and the coupling, which keeps every particle on its side of
  /// a face, would keep that water inside for good; moved into the water about it, it would be squeezed. Not
  /// a physical motion: the water's momentum changes by what the move gives it.
  /// @param positions, velocities  N points and their velocities (unit: m, m/s), changed in place
  /// @param gap  how far outside the face a moved point ends, and the least distance to another (unit: m),
  ///        > 0: half a particle spacing
  /// @param crosses  which ways cross a cloth (a way under a body's face into water pooled on a cloth goes
  ///        through it: RigidBodies.WaterMovedOutOfAnAddedBodyStaysOnItsSideOfTheCloth); empty: none do
  /// @param displaced  output: empty when no point is displaced, else N flags
  /// @return how many points moved. The default moves none: a source whose bodies have no inside.
  virtual std::size_t release_trapped(Vec3Array& positions, Vec3Array& velocities, double gap,
                                      const CrossingTest& crosses, std::vector<std::uint8_t>& displaced) {
    (void)positions;
    (void)velocities;
    (void)gap;
    (void)crosses;
    displaced.clear();
    return 0;
  }
};

}  // namespace drench
