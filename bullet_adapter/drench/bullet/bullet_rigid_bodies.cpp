#include <drench/bullet/bullet_rigid_bodies.hpp>

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletDynamics/Dynamics/btDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <drench/common/error.hpp>

namespace drench::bullet {

struct BulletRigidBodies::Tracked {
  const btCollisionShape* shape = nullptr;
  std::uint64_t signature = 0;  // shape_signature: a compound's children the game changes re-mesh it
  bool supported = false;
  TriangleMesh local;      // the shape's surface in the object's frame
  double volume = 0.0;     // inside `local` (unit: m^3; 0 for a surface without an inside)
  bool has_end = false;    // `end` and `world_end` hold the end of the last step the object took part in
  btTransform end;         // the object's transform then
  Vec3Array world_end;     // `local` placed by `end` (unit: m)
  std::uint64_t seen = 0;  // the last step (m_step) the object was in the world
  int proxy_id = -1;       // its broad-phase proxy's m_uniqueId: a new proxy is a new body at this address
  std::uint64_t instance = 0;
  // A btStaticPlaneShape (cover_plane): its grid, the chunks whose neighbourhood of `radius` chunks is
  // meshed, and whether a cover too large was reported.
  bool plane = false;
  PlaneFrame frame;
  std::unordered_set<PlaneCell, PlaneCellHash> safe;
  std::int64_t radius = 0;
  bool warned_too_large = false;
  std::uint64_t retry_step = 0;  // after a cover too large, the step (m_step) to try again
};

namespace {

/// A plane's grid cells are meshed in square chunks of this many cells a side: the unit in which the mesh
/// follows the water, so that it changes only when the water moves by a chunk.
constexpr std::int64_t kPlaneChunkCells = 4;

/// `local` placed by `transform`, in double whatever Bullet's precision.
Vec3Array place(const TriangleMesh& local, const btTransform& transform) {
  const Eigen::Matrix3d rotation = to_matrix3(transform.getBasis());
  const Vec3 origin = to_vec3(transform.getOrigin());
  Vec3Array world(local.positions.size());
  for (std::size_t i = 0; i < world.size(); ++i)
    world[i] = rotation * local.positions[i] + origin;
  return world;
}

bool same(const btTransform& a, const btTransform& b) {
  return a.getOrigin() == b.getOrigin() && a.getBasis()[0] == b.getBasis()[0] &&
         a.getBasis()[1] == b.getBasis()[1] && a.getBasis()[2] == b.getBasis()[2];
}

RigidMotion motion_of(const btCollisionObject& object) {
  if (object.isKinematicObject()) return RigidMotion::KINEMATIC;
  const btRigidBody* body = btRigidBody::upcast(&object);
  if (object.isStaticObject() || body == nullptr || body->getInvMass() == 0) return RigidMotion::STATIC;
  return RigidMotion::DYNAMIC;
}

/// Whether the water sees `object`, whose broad-phase proxy is `proxy`: Bullet's collision filter between the
/// water's group and mask and the object's, and the object's contact response. Bullet's solver lets every
/// rigid body pass an object with CF_NO_CONTACT_RESPONSE (a trigger, a sensor ghost), and so does the water
/// (RigidBodies.TriggersWithoutContactResponseLetTheWaterPass).
bool water_sees(const btCollisionObject& object, const btBroadphaseProxy& proxy,
                const RigidBodyOptions& options) {
  return object.hasContactResponse() && (proxy.m_collisionFilterGroup & options.water_mask) != 0 &&
         (options.water_group & proxy.m_collisionFilterMask) != 0;
}

/// Bullet's contact query of a small sphere, the probe, against the objects the water sees other than soft
/// bodies: the first object found that overlaps it by more than `limit` (a negative distance), and the depth
/// of the deepest contact. solid_holding and release_trapped ask it.
struct ProbeContacts : btCollisionWorld::ContactResultCallback {
  ProbeContacts(const btCollisionObject& sphere, const RigidBodyOptions& options)
      : probe(&sphere), water(&options) {}
  bool needsCollision(btBroadphaseProxy* proxy) const override {
    const auto* object = static_cast<const btCollisionObject*>(proxy->m_clientObject);
    return object != probe && water_sees(*object, *proxy, *water);
  }
  const btCollisionObject* probe;
  const RigidBodyOptions* water;
  btScalar limit = 0;
  const btCollisionObject* holder = nullptr;
  btScalar distance = 0;
  btScalar addSingleResult(btManifoldPoint& contact, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper* b, int, int) override {
    const bool probe_is_a = a->getCollisionObject() == probe;
    const btCollisionObject* other = probe_is_a ? b->getCollisionObject() : a->getCollisionObject();
    if (other->getInternalType() == btCollisionObject::CO_SOFT_BODY) return 0;
    if (holder == nullptr && contact.getDistance() < limit) holder = other;
    distance = std::min(distance, contact.getDistance());
    return 0;
  }
};

/// Bullet's ray query along a way out of a body that appeared: whether it meets another object the water sees
/// (not `body`, not a soft body: the cloths are the caller's CrossingTest).
struct OtherObjectsOnTheWay : btCollisionWorld::ClosestRayResultCallback {
  OtherObjectsOnTheWay(const btVector3& from, const btVector3& to) : ClosestRayResultCallback(from, to) {}
  const btCollisionObject* body = nullptr;
  const RigidBodyOptions* water = nullptr;
  bool needsCollision(btBroadphaseProxy* proxy) const override {
    const auto* object = static_cast<const btCollisionObject*>(proxy->m_clientObject);
    return object != body && object->getInternalType() != btCollisionObject::CO_SOFT_BODY &&
           water_sees(*object, *proxy, *water);
  }
};

std::string describe(const btCollisionObject& object, int index) {
  return "collision object " + std::to_string(index) + " (" + object.getCollisionShape()->getName() + ")";
}

/// Why `mesh` cannot be the surface of `shape`, or "": no face (but for a shape Bullet collides nothing
/// with: a btEmptyShape, an empty compound), or a vertex that is
/// not finite or lies outside the shape's own bounding box. Corrupt shape data does that (a heightfield built
/// with Bullet's legacy constructor, which takes PHY_FLOAT to mean btScalar, reads doubles from floats:
/// Bullet then culls every triangle, or hands out absurd vertices), and the coupling's broad phase must never
/// see such boxes: FCL's tree crashes on them.
std::string mesh_problem(const btCollisionShape& shape, const TriangleMesh& mesh) {
  if (mesh.triangles.empty() && !collides_with_nothing(shape))
    return "its mesh has no face: its data is corrupt or degenerate";
  btTransform identity;
  identity.setIdentity();
  btVector3 lo, hi;
  shape.getAabb(identity, lo, hi);
  const Vec3 low = to_vec3(lo), high = to_vec3(hi);
  const double slack = 1e-6 * (high - low).cwiseAbs().maxCoeff() + 1e-9;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vec3& x = mesh.positions[v];
    if (!x.allFinite() || (x.array() < low.array() - slack).any() ||
        (x.array() > high.array() + slack).any()) {
      return "vertex " + std::to_string(v) + " of its mesh (" + format_number(x.x()) + ", " +
             format_number(x.y()) + ", " + format_number(x.z()) +
             ") lies outside the shape's bounding box: its data is corrupt";
    }
  }
  return "";
}

void check_option(bool ok, const std::string& what, double value) {
  if (!ok) throw SceneError("rigid bodies: " + what + ", got " + format_number(value));
}

}  // namespace

BulletRigidBodies::BulletRigidBodies(btDynamicsWorld& world, RigidBodyOptions options)
    : m_world(world), m_options(options) {
  const ShapeMeshOptions& m = m_options.mesh;
  check_option(m.max_edge > 0.0 && std::isfinite(m.max_edge), "mesh.max_edge must be > 0", m.max_edge);
  check_option(m.plane_half_size > 0.0 && std::isfinite(m.plane_half_size),
               "mesh.plane_half_size must be > 0", m.plane_half_size);
  check_option(m.plane_cell > 0.0 && std::isfinite(m.plane_cell), "mesh.plane_cell must be > 0",
               m.plane_cell);
  // What the world holds now must all be usable: a shape the water would pass through is an error here,
  // where the game sets up its level, not a surprise in the first splash.
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject& object = *objects[i];
    if (object.getInternalType() == btCollisionObject::CO_SOFT_BODY || !sees(object)) continue;
    if (!object.getCollisionShape() || !is_supported_shape(*object.getCollisionShape())) {
      throw Error(describe(object, i) +
                  ": drench cannot hold water with this shape; give the water another collision filter group "
                  "(RigidBodyOptions::water_mask) to let the water pass it, or use a supported shape "
                  "(shape_mesh.hpp)");
    }
    track(object, i);
  }
}

BulletRigidBodies::~BulletRigidBodies() = default;

bool BulletRigidBodies::sees(const btCollisionObject& object) const {
  const btBroadphaseProxy* proxy = object.getBroadphaseHandle();
  if (proxy == nullptr) return false;  // not in a world's broad phase: Bullet collides nothing with it either
  return water_sees(object, *proxy, m_options);
}

BulletRigidBodies::Tracked* BulletRigidBodies::track(const btCollisionObject& object, int index) {
  std::unique_ptr<Tracked>& slot = m_tracked[&object];
  // A body removed, deleted and another added at its address between two steps is a new body: before, it
  // started where the old one had ended and swept the water from there (test
  // RigidBodies.ABodyRespawnedAtTheSameAddressStartsWhereItIsPlaced).
  const btBroadphaseProxy* proxy = object.getBroadphaseHandle();
  const int proxy_id = proxy ? proxy->m_uniqueId : -1;
  if (!slot || slot->proxy_id != proxy_id) {
    slot = std::make_unique<Tracked>();
    slot->proxy_id = proxy_id;
    slot->instance = ++m_instances;
  }
  Tracked& t = *slot;
  t.seen = m_step;
  const btCollisionShape* shape = object.getCollisionShape();
  const std::uint64_t signature = shape ? shape_signature(*shape) : 0;
  if (shape == t.shape && signature == t.signature) return t.supported ? &t : nullptr;
  t.shape = shape;
  t.signature = signature;
  // Other faces, maybe as many as before: the coupling lays its mesh out anew and sweeps nothing from the
  // old.
  t.instance = ++m_instances;
  t.has_end = false;
  t.supported = shape != nullptr && is_supported_shape(*shape);
  if (!t.supported) {
    m_warnings.push_back(describe(object, index) + ": not supported, it does not hold the water");
    t.local = TriangleMesh();
    return nullptr;
  }
  std::string problem;
  bool out_of_range = false;
  try {
    t.local = shape_mesh(*shape, m_options.mesh);
    problem = mesh_problem(*shape, t.local);
    // By the divergence theorem over the closed mesh of a convex shape or a compound of them.
    t.volume = 0.0;
    if (!shape->isConcave()) {
      for (const Triangle& f : t.local.triangles) {
        const Vec3Array& x = t.local.positions;
        t.volume += x[f[0]].dot(x[f[1]].cross(x[f[2]])) / 6.0;
      }
      t.volume = std::abs(t.volume);
    }
  } catch (const SceneError& e) {
    // A shape out of range (a scaling of 0, a sphere of 1e9 m) was reported without the object, and after
    // a caught throw the object's old mesh went on holding the water.
    problem = e.what();
    out_of_range = true;
  }
  if (!problem.empty()) {
    // At construction the game is setting its level up: an error. Later a warning, and the object is left
    // out.
    if (m_step == 0 && out_of_range) throw SceneError(describe(object, index) + ": " + problem);
    if (m_step == 0) throw Error(describe(object, index) + ": " + problem);
    m_warnings.push_back(describe(object, index) + ": " + problem + "; it does not hold the water");
    t.supported = false;
    t.local = TriangleMesh();
    return nullptr;
  }
  t.plane = shape->getShapeType() == STATIC_PLANE_PROXYTYPE;
  if (t.plane) {
    t.frame = plane_frame(static_cast<const btStaticPlaneShape&>(*shape));
    t.safe.clear();
    t.radius = 0;
  }
  return &t;
}

void BulletRigidBodies::expect_points(const std::vector<const Vec3Array*>& point_sets, double reach) {
  m_points = point_sets;
  m_reach = std::isfinite(reach) && reach > 0.0 ? reach : 0.0;
}

void BulletRigidBodies::cover_plane(Tracked& t, const btCollisionObject& object, int index,
                                    const std::vector<const Vec3Array*>& points) {
  const double cell = m_options.mesh.plane_cell;
  const double chunk = static_cast<double>(kPlaneChunkCells) * cell;
  // The most chunks a plane's mesh may have: kMaxShapeMeshTriangles, as for any shape.
  constexpr std::size_t kMaxChunks = kMaxShapeMeshTriangles / (2 * kPlaneChunkCells * kPlaneChunkCells);
  if (m_step < t.retry_step) return;
  const auto too_large = [&] {
    // Tried again 60 steps later: a cover that fails costs its whole attempt each time.
    t.retry_step = m_step + 60;
    if (t.warned_too_large) return;
    m_warnings.push_back(describe(object, index) +
                         ": the water and the cloths move over more of the plane than " +
                         std::to_string(kMaxShapeMeshTriangles) + " triangles of " + format_number(cell) +
                         " m cells cover (kMaxShapeMeshTriangles); it holds them only where it was meshed "
                         "before. Raise RigidBodyOptions::mesh.plane_cell");
    t.warned_too_large = true;
  };
  // A point this close to the plane may meet it within the step (the reach has the coupling's range), and a
  // cell of slack (test RigidBodies.AGroundPlaneHoldsWaterFarFromTheOriginAndSlidingAway).
  const double near = m_reach + cell;
  const double radius_chunks = std::max(1.0, std::ceil(near / chunk));
  // Every point's own neighbourhood of radius + 1 chunks is meshed: it alone must fit.
  if (!(std::pow(2.0 * radius_chunks + 3.0, 2.0) <= static_cast<double>(kMaxChunks))) {
    too_large();
    return;
  }
  const auto radius = static_cast<std::int64_t>(radius_chunks);
  const btTransform& transform = object.getWorldTransform();
  const Eigen::Matrix3d rotation = to_matrix3(transform.getBasis());
  const Vec3 origin = rotation * t.frame.origin + to_vec3(transform.getOrigin());
  const Vec3 normal = rotation * t.frame.normal;
  const Vec3 u_axis = rotation * t.frame.axis_u / chunk, v_axis = rotation * t.frame.axis_v / chunk;
  // Chunk coordinates beyond this are far outside kMaxCoordinate at any sensible plane_cell.
  constexpr double kFarthestChunk = 1e15;
  const auto for_each_near_chunk = [&](auto&& visit) {
    for (const Vec3Array* set : points) {
      for (const Vec3& x : *set) {
        const Vec3 r = x - origin;
        if (!(std::abs(normal.dot(r)) <= near)) continue;
        const double u = std::floor(u_axis.dot(r)), v = std::floor(v_axis.dot(r));
        if (!(std::abs(u) < kFarthestChunk && std::abs(v) < kFarthestChunk)) continue;
        if (!visit(PlaneCell{static_cast<std::int64_t>(u), static_cast<std::int64_t>(v)})) return;
      }
    }
  };
  // Most steps every point near the plane is in a chunk meshed around: one look-up per run of points in the
  // same chunk (the fluid keeps its particles in spatial order).
  bool covered = radius <= t.radius;
  PlaneCell last{std::numeric_limits<std::int64_t>::min(), 0};
  for_each_near_chunk([&](const PlaneCell& c) {
    if (c == last) return true;
    last = c;
    covered = covered && t.safe.count(c) > 0;
    return covered;
  });
  if (covered) return;
  using ChunkSet = std::unordered_set<PlaneCell, PlaneCellHash>;
  ChunkSet near_chunks;
  for_each_near_chunk([&](const PlaneCell& c) {
    near_chunks.insert(c);
    return near_chunks.size() <= kMaxChunks;
  });
  if (near_chunks.empty()) return;  // nothing near: what is meshed stays
  // `from` grown by `by` chunks along u (or v) into `to`; false once `to` holds more than kMaxChunks, which
  // bounds the work as well as the mesh.
  const auto grow = [](const ChunkSet& from, std::int64_t by, bool along_u, ChunkSet& to) {
    for (const PlaneCell& c : from) {
      for (std::int64_t d = -by; d <= by; ++d) {
        to.insert(along_u ? PlaneCell{c.first + d, c.second} : PlaneCell{c.first, c.second + d});
        if (to.size() > kMaxChunks) return false;
      }
    }
    return true;
  };
  // Meshed: every chunk within radius + 1 of a point's, so that a point may move a chunk before the mesh
  // must follow it. Safe: the chunks within 1 of a point's, whose neighbourhood of `radius` is all meshed.
  ChunkSet rows, meshed, safe_rows, safe;
  if (!grow(near_chunks, radius + 1, true, rows) || !grow(rows, radius + 1, false, meshed)) {
    too_large();
    return;
  }
  grow(near_chunks, 1, true, safe_rows);
  grow(safe_rows, 1, false, safe);  // within `meshed`, so within kMaxChunks
  // In order, so that the same points give the same mesh whatever the hash set's order.
  std::vector<PlaneCell> chunks(meshed.begin(), meshed.end());
  std::sort(chunks.begin(), chunks.end());
  std::vector<PlaneCell> cells;
  cells.reserve(chunks.size() * kPlaneChunkCells * kPlaneChunkCells);
  for (const PlaneCell& c : chunks)
    for (std::int64_t j = 0; j < kPlaneChunkCells; ++j)
      for (std::int64_t i = 0; i < kPlaneChunkCells; ++i)
        cells.push_back({c.first * kPlaneChunkCells + i, c.second * kPlaneChunkCells + j});
  t.local = plane_cells_mesh(t.frame, cell, cells);
  t.safe = std::move(safe);
  t.radius = radius;
  t.instance = ++m_instances;  // other faces: no sweep from the old mesh, no jump audit against it
  t.has_end = false;
}

void BulletRigidBodies::check_bodies() const {
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject& object = *objects[i];
    if (object.getInternalType() == btCollisionObject::CO_SOFT_BODY || !sees(object)) continue;
    const Vec3 origin = to_vec3(object.getWorldTransform().getOrigin());
    const Eigen::Matrix3d basis = to_matrix3(object.getWorldTransform().getBasis());
    // allFinite first: Eigen's maxCoeff passes over a NaN.
    if (!origin.allFinite() || !(origin.cwiseAbs().maxCoeff() <= kMaxCoordinate) || !basis.allFinite()) {
      throw Error(describe(object, i) + " is at " + format_vec3(origin) +
                  (basis.allFinite() ? "" : " with a non-finite rotation") + ": the water's world reaches " +
                  format_number(kMaxCoordinate) +
                  " m from the origin; move it back, or remove it from the world");
    }
    if (const btRigidBody* body = btRigidBody::upcast(&object)) {
      const Vec3 v = to_vec3(body->getLinearVelocity()), w = to_vec3(body->getAngularVelocity());
      if (!v.allFinite() || !w.allFinite()) {
        throw Error(describe(object, i) + " has a non-finite velocity " + format_vec3(v) + ", angular " +
                    format_vec3(w));
      }
    }
  }
}

void BulletRigidBodies::begin_step(std::vector<RigidSurface>& surfaces) {
  ++m_step;
  // Taken, so that no later step reads them, even one after a throw below.
  std::vector<const Vec3Array*> points;
  points.swap(m_points);
  surfaces.clear();
  m_current.clear();
  m_appeared.clear();
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject& object = *objects[i];
    if (object.getInternalType() == btCollisionObject::CO_SOFT_BODY || !sees(object)) continue;
    const auto before = m_tracked.find(&object);
    const std::uint64_t instance_before = before != m_tracked.end() ? before->second->instance : 0;
    const bool seen_last_step = before != m_tracked.end() && before->second->seen + 1 == m_step;
    Tracked* t = track(object, i);
    if (t != nullptr && m_teleported.count(&object) > 0) {
      // Placed anew, as another body: its faces have no start to sweep from, nor an end to audit for a jump.
      t->instance = ++m_instances;
      t->has_end = false;
      // A kinematic body's new place is in its motion state until Bullet's step reads it, which would then
      // sweep it there after all and give it the jump's speed (btRigidBody::saveKinematicState): it is
      // there now, and was there before.
      btRigidBody* body = btRigidBody::upcast(objects[i]);
      if (body != nullptr && body->isKinematicObject() && body->getMotionState() != nullptr) {
        btTransform place;
        body->getMotionState()->getWorldTransform(place);
        body->setWorldTransform(place);
        body->setInterpolationWorldTransform(place);
      }
    }
    // Before a plane's new cover, which is the same plane.
    const bool appeared = !(seen_last_step && t != nullptr && t->instance == instance_before);
    if (t != nullptr && t->plane && !points.empty()) cover_plane(*t, object, i, points);
    const bool was_there = seen_last_step && t != nullptr && t->instance == instance_before;
    if (t == nullptr || t->local.triangles.empty()) continue;
    // A body the game adds after construction (or replaces, or re-meshes) may close its faces around water:
    // release_trapped looks inside it. Another concave shape (a triangle mesh, a heightfield) has no inside
    // to look in, only a query per particle in its box.
    if (appeared && (t->plane || !object.getCollisionShape()->isConcave()))
      m_appeared.emplace_back(&object, t);
    RigidSurface s;
    s.key = reinterpret_cast<std::uintptr_t>(&object);
    s.instance = t->instance;
    s.motion = motion_of(object);
    s.triangles = t->local.triangles;
    // A body the game moved between steps (a kinematic paddle, a teleport) moves within this step, from
    // where the last step left it: the coupling sweeps the water along that motion instead of letting the
    // body appear around particles.
    const btTransform& now = object.getWorldTransform();
    if (was_there && t->has_end) {
      s.positions_t0 = t->world_end;
    } else {
      s.positions_t0 = place(t->local, now);
      t->end = now;
      t->world_end = s.positions_t0;
      t->has_end = true;
    }
    s.positions_t1 = s.positions_t0;
    s.velocities_t0.assign(s.positions_t0.size(), Vec3::Zero());
    if (const btRigidBody* body = btRigidBody::upcast(&object)) {
      const Vec3 v = to_vec3(body->getLinearVelocity());
      const Vec3 w = to_vec3(body->getAngularVelocity());
      const Vec3 centre = to_vec3(body->getCenterOfMassPosition());
      if (s.motion == RigidMotion::DYNAMIC) {
        // What it and the water it sweeps share (meet_swept_water).
        s.inverse_mass = static_cast<double>(body->getInvMass());
        s.centre = centre;
        s.velocity = v;
      }
      for (std::size_t k = 0; k < s.positions_t0.size(); ++k)
        s.velocities_t0[k] = v + w.cross(s.positions_t0[k] - centre);
    }
    surfaces.push_back(std::move(s));
    m_current.push_back(t);
  }
  m_teleported.clear();
  // Objects no longer in the world: a body deleted and another allocated at its address must start afresh.
  for (auto it = m_tracked.begin(); it != m_tracked.end();) {
    if (it->second->seen != m_step) {
      it = m_tracked.erase(it);
    } else {
      ++it;
    }
  }
}

void BulletRigidBodies::step(double dt) {
  // maxSubSteps 0: exactly one step of dt, as BulletCloth steps the world.
  m_world.stepSimulation(static_cast<btScalar>(dt), 0);
}

void BulletRigidBodies::end_positions(std::vector<RigidSurface>& surfaces) {
  for (std::size_t i = 0; i < surfaces.size() && i < m_current.size(); ++i) {
    Tracked& t = *m_current[i];
    const auto* object =
        reinterpret_cast<const btCollisionObject*>(static_cast<std::uintptr_t>(surfaces[i].key));
    const btTransform& now = object->getWorldTransform();
    if (!(t.has_end && same(now, t.end))) {
      t.world_end = place(t.local, now);
      t.end = now;
      t.has_end = true;
    }
    surfaces[i].positions_t1 = t.world_end;
  }
}

namespace {

/// The radius about the centre of mass within which `body`'s shape lies (unit: m): its bounding sphere's.
double reach(const btRigidBody& body) {
  btVector3 centre;
  btScalar radius = 0;
  body.getCollisionShape()->getBoundingSphere(centre, radius);
  return static_cast<double>(radius + centre.length());
}

/// The speed of the fastest point of `body` (unit: m/s): its centre's, and its spin times its reach.
double point_speed(const btRigidBody& body) {
  return static_cast<double>(body.getLinearVelocity().length()) +
         static_cast<double>(body.getAngularVelocity().length()) * reach(body);
}

}  // namespace

void BulletRigidBodies::apply_impulses(std::size_t index, const RigidSurface& surface,
                                       const Vec3* node_impulses) {
  auto* object = reinterpret_cast<btCollisionObject*>(static_cast<std::uintptr_t>(surface.key));
  btRigidBody* body = btRigidBody::upcast(object);
  if (index >= m_current.size() || body == nullptr || body->getInvMass() == 0) return;
  const Vec3 centre = to_vec3(body->getCenterOfMassPosition());
  Vec3 linear = Vec3::Zero(), angular = Vec3::Zero();
  for (std::size_t k = 0; k < surface.positions_t1.size(); ++k) {
    linear += node_impulses[k];
    angular += (surface.positions_t1[k] - centre).cross(node_impulses[k]);
  }
  const btVector3 impulse = to_bt(linear);
  // What the water gives the body this step, apart from what Bullet's own step gives it, and the body's
  // fastest speed without it as the water meets it (thrown_body).
  const auto noted = m_kicks.find(body);
  if (noted != m_kicks.end()) {
    Kick& kick = noted->second;
    const Vec3 own_linear = to_vec3(body->getLinearVelocity()) - kick.linear;
    const Vec3 own_angular = to_vec3(body->getAngularVelocity()) - kick.angular;
    kick.met = std::max(kick.met, own_linear.norm() + own_angular.norm() * reach(*body));
    kick.linear += to_vec3(impulse * body->getLinearFactor() * body->getInvMass());
    kick.angular += to_vec3(body->getInvInertiaTensorWorld() * to_bt(angular) * body->getAngularFactor());
  }
  body->applyCentralImpulse(impulse);
  body->applyTorqueImpulse(to_bt(angular));
  // A body Bullet put to sleep would ignore the water that now lifts or pushes it.
  body->activate(true);
  m_impulse_given += to_vec3(impulse);
}

void BulletRigidBodies::note_speeds() {
  m_kicks.clear();
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btRigidBody* body = btRigidBody::upcast(objects[i]);
    if (body != nullptr && body->getInvMass() > 0 && sees(*body)) m_kicks[body].start = point_speed(*body);
  }
}

std::string BulletRigidBodies::thrown_body(double water_speed, double rest_density, const Vec3& gravity,
                                           double dt) const {
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btRigidBody* body = btRigidBody::upcast(objects[i]);
    const auto kick = body != nullptr ? m_kicks.find(body) : m_kicks.end();
    if (kick == m_kicks.end() || !sees(*body)) continue;
    // Water drags a body towards its own speed and lifts it by buoyancy, at most (rest density / body's)
    // g, and holds its weight, g. Twice the larger speed and a metre a second more leave room for the
    // water's pressure; a 2 mm plank the water threw up at 3.4 m/s from 1.3 m/s down is beyond
    // (RigidBodies.AWaterLaunchedBodyEndsTheStepThatThrewIt). Only the water's own impulses count: Bullet's
    // contacts, constraints and the game's forces are the game's (a rocket in the water).
    const auto t = m_tracked.find(body);
    const double volume = t != m_tracked.end() ? t->second->volume : 0.0;
    const double density = volume > 0.0 ? 1.0 / (static_cast<double>(body->getInvMass()) * volume) : 0.0;
    const double lift = density > 0.0 ? rest_density / density : 1.0;
    const double body_speed = std::max(kick->second.start, kick->second.met);
    const double bound = 2.0 * std::max(body_speed, water_speed) + (1.0 + lift) * gravity.norm() * dt + 1.0;
    const double given = kick->second.linear.norm() + kick->second.angular.norm() * reach(*body);
    if (!(given <= bound)) {
      return describe(*body, i) + " was given " + format_number(given) +
             " m/s by the water in the step, at " + format_number(body_speed) + " m/s, where water at most " +
             format_number(water_speed) + " m/s fast could give it " + format_number(bound) + " m/s";
    }
  }
  return "";
}

void BulletRigidBodies::teleported(const btCollisionObject& object) {
  m_teleported.insert(&object);
}

std::size_t BulletRigidBodies::release_trapped(Vec3Array& positions, Vec3Array& velocities, double gap,
                                               const CrossingTest& crosses,
                                               std::vector<std::uint8_t>& displaced) {
  displaced.clear();
  if (m_appeared.empty()) return 0;
  // The probe's centre lies inside a solid when a contact overlaps it by more than its radius.
  const btScalar radius = static_cast<btScalar>(0.5 * gap);
  btSphereShape sphere(radius);
  btCollisionObject probe;
  probe.setCollisionShape(&sphere);
  // Whether x lies inside a solid the water sees: the probe's contacts with the whole world.
  const auto in_a_solid = [&](const Vec3& x) {
    probe.setWorldTransform(btTransform(btQuaternion::getIdentity(), to_bt(x)));
    ProbeContacts c(probe, m_options);
    m_world.contactTest(&probe, c);
    return c.distance < -radius;
  };

  // The appeared objects' convex pieces, each the meet of its face planes: a convex shape, a plane (the half
  // space away from the water), or each convex child of a compound, nested ones too. The planes are those of
  // the faces that hold the water, where Bullet's own shapes round a box's edges by its margin and would
  // leave the water there inside (the large crate and the large compound crate of
  // RigidBodies.ABodyAddedInsideWaterMovesTheWaterOutOfIt). A concave child (a triangle mesh) has no inside.
  // The concave children of the appeared compounds (a floor of triangles in a prefab): no inside, but a way
  // out through one would end under it, and the ray query below leaves out the appeared object whole.
  struct Wall {
    btCollisionObject* object;
    const btCollisionShape* shape;
    btTransform at;
  };
  std::vector<Wall> walls;
  struct Piece {
    btCollisionObject* object;
    Vec3 low, high;
    std::vector<Vec3> normals;  // outward, unit
    std::vector<double> offsets;
    bool holds(const Vec3& x) const {
      if ((x.array() < low.array()).any() || (x.array() > high.array()).any() || normals.empty())
        return false;
      for (std::size_t f = 0; f < normals.size(); ++f) {
        if (!(offsets[f] - normals[f].dot(x) > 0.0)) return false;
      }
      return true;
    }
  };
  std::vector<Piece> bodies;
  const auto add_convex = [&](btCollisionObject* object, const TriangleMesh& local, const btTransform& at) {
    const Vec3Array world = place(local, at);
    Piece a;
    a.object = object;
    a.low = Vec3::Constant(std::numeric_limits<double>::infinity());
    a.high = -a.low;
    for (const Vec3& v : world) {
      a.low = a.low.cwiseMin(v);
      a.high = a.high.cwiseMax(v);
    }
    for (const Triangle& f : local.triangles) {
      const Vec3 n = (world[f[1]] - world[f[0]]).cross(world[f[2]] - world[f[0]]);
      if (!(n.norm() > 0.0)) continue;
      a.normals.push_back(n.normalized());
      a.offsets.push_back(a.normals.back().dot(world[f[0]]));
    }
    bodies.push_back(std::move(a));
  };
  std::function<void(btCollisionObject*, const btCompoundShape&, const btTransform&)> add_children =
      [&](btCollisionObject* object, const btCompoundShape& compound, const btTransform& at) {
        for (int i = 0; i < compound.getNumChildShapes(); ++i) {
          const btCollisionShape& child = *compound.getChildShape(i);
          const btTransform child_at = at * compound.getChildTransform(i);
          if (child.getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
            add_children(object, static_cast<const btCompoundShape&>(child), child_at);
          } else if (child.isConvex()) {
            add_convex(object, shape_mesh(child, m_options.mesh), child_at);
          } else {
            walls.push_back({object, &child, child_at});
          }
        }
      };
  for (const auto& [object, tracked] : m_appeared) {
    auto* o = const_cast<btCollisionObject*>(object);
    const btCollisionShape& shape = *object->getCollisionShape();
    const btTransform& at = object->getWorldTransform();
    if (tracked->plane) {
      // The solid is the side away from the water (PlaneFrame::normal), all of it.
      Piece a;
      a.object = o;
      const Vec3 normal = to_matrix3(at.getBasis()) * tracked->frame.normal;
      a.normals.push_back(normal);
      a.offsets.push_back(normal.dot(to_vec3(at(to_bt(tracked->frame.origin)))));
      a.low = Vec3::Constant(-std::numeric_limits<double>::infinity());
      a.high = -a.low;
      bodies.push_back(std::move(a));
    } else if (shape.isConvex()) {
      add_convex(o, tracked->local, at);
    } else if (shape.getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
      add_children(o, static_cast<const btCompoundShape&>(shape), at);
    }
  }
  m_appeared.clear();  // once per appearance, and never with objects the game may delete before a next call
  const auto in_a_piece = [&](const Vec3& x) {
    return std::any_of(bodies.begin(), bodies.end(), [&](const Piece& a) { return a.holds(x); });
  };

  // Which piece holds each point (its index + 1; 0: none), the first that does.
  std::vector<std::uint32_t> holder(positions.size(), 0);
  std::size_t trapped = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    for (std::size_t k = 0; k < positions.size(); ++k) {
      if (holder[k] != 0 || !positions[k].allFinite() || !bodies[b].holds(positions[k])) continue;
      holder[k] = static_cast<std::uint32_t>(b + 1);
      ++trapped;
    }
  }
  if (trapped == 0) return 0;
  // The queries below find objects by their broad-phase boxes, which Bullet updates in its step: a body the
  // game moved or teleported since would be looked for where it was. Only with water to move: a plane's new
  // cover appears often, and Bullet's step would otherwise see its broad phase as it left it.
  m_world.updateAabbs();

  // The points outside every appeared body, hashed in cells of 2 room (a key may stand for several far
  // apart: only the distance decides); `room` (unit: m) is the least distance a way out must end from any
  // of them or from a point moved before: ending nearer, it would squeeze the water there into one layer,
  // which the pressure throws (the large crate of RigidBodies.ABodyAddedInsideWaterMovesTheWaterOutOfIt).
  const double room = gap;
  const auto cell_of = [&](const Vec3& x) {
    return Eigen::Vector3i((x / (2.0 * room)).array().floor().cast<int>());
  };
  const auto key_of = [](const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x()) & 0x1fffff) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y()) & 0x1fffff) << 21) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z()) & 0x1fffff));
  };
  std::unordered_map<std::uint64_t, std::vector<Vec3>> cells;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    if (holder[k] == 0 && positions[k].allFinite())
      cells[key_of(cell_of(positions[k]))].push_back(positions[k]);
  }
  const auto has_room = [&](const Vec3& x) {
    const Eigen::Vector3i c = cell_of(x);
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        for (int l = -1; l <= 1; ++l) {
          const auto it = cells.find(key_of(c + Eigen::Vector3i(i, j, l)));
          if (it == cells.end()) continue;
          for (const Vec3& y : it->second) {
            if ((y - x).squaredNorm() < room * room) return false;
          }
        }
      }
    }
    return true;
  };

  // Every trapped point's ways out, shortest first, up to kMaxWay gaps long, so that the water leaves by a
  // near face, not a large body's far faces or top (the cases of
  // RigidBodies.ABodyAddedInsideWaterMovesTheWaterOutOfIt): those of trapped[i] are ways[first[i],
  // first[i+1]).
  constexpr double kMaxWay = 4.0;
  std::vector<std::size_t> trapped_points, first;
  std::vector<std::pair<double, Vec3>> ways;  // (length, end)
  std::vector<std::pair<double, Vec3>> own;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    if (holder[k] == 0) continue;
    const Piece& a = bodies[holder[k] - 1];
    const Vec3& x = positions[k];
    own.clear();
    // A way out crosses one face plane, to `gap` beyond it.
    for (std::size_t f = 0; f < a.normals.size(); ++f) {
      const double below = a.offsets[f] - a.normals[f].dot(x);
      own.emplace_back(below + gap, x + (below + gap) * a.normals[f]);
    }
    std::sort(own.begin(), own.end(), [](const auto& u, const auto& v) { return u.first < v.first; });
    trapped_points.push_back(k);
    first.push_back(ways.size());
    // The few shortest distinct ways: a box's face is two triangles in one plane, and a ball's facets near
    // a point are hundreds of planes whose ways end within a few spacings of each other.
    constexpr std::size_t kMostWays = 8;
    const std::size_t from = ways.size();
    for (const auto& way : own) {
      if (!(way.first <= kMaxWay * gap) || ways.size() - from == kMostWays) break;
      if (ways.size() > from && (ways.back().second - way.second).squaredNorm() <= 1e-24) continue;
      ways.push_back(way);
    }
  }
  first.push_back(ways.size());

  // Which ways cross a cloth, all asked at once (the caller's test of every cloth face).
  std::vector<std::uint8_t> crossing(ways.size(), 0);
  if (crosses && !ways.empty()) {
    Vec3Array from(ways.size()), to(ways.size());
    for (std::size_t i = 0; i + 1 < first.size(); ++i) {
      for (std::size_t w = first[i]; w < first[i + 1]; ++w) {
        from[w] = positions[trapped_points[i]];
        to[w] = ways[w].second;
      }
    }
    crosses(from, to, crossing);
  }
  // Whether a way passes through another object the water sees: a triangle mesh or a heightfield has no
  // inside, so a way down through a ground of triangles would end in no solid, under it
  // (RigidBodies.WaterMovedOutOfAnAddedBodyStaysOnItsSideOfTheGround).
  const auto through_another = [&](const Vec3& from, const Vec3& to, const btCollisionObject* body) {
    OtherObjectsOnTheWay hit(to_bt(from), to_bt(to));
    hit.body = body;
    hit.water = &m_options;
    m_world.rayTest(to_bt(from), to_bt(to), hit);
    if (hit.hasHit()) return true;
    const btTransform start(btQuaternion::getIdentity(), to_bt(from)),
        end(btQuaternion::getIdentity(), to_bt(to));
    for (const Wall& w : walls) {
      if (w.object != body) continue;
      btCollisionWorld::ClosestRayResultCallback own_wall(to_bt(from), to_bt(to));
      btCollisionWorld::rayTestSingle(start, end, w.object, w.shape, w.at, own_wall);
      if (own_wall.hasHit()) return true;
    }
    return false;
  };

  // The shortest way that ends with room and in no solid (a crate standing on the ground would otherwise
  // put its water into the ground), crosses no cloth (a box dropped into water pooled on a hammock:
  // RigidBodies.WaterMovedOutOfAnAddedBodyStaysOnItsSideOfTheCloth) and passes through no other object; with
  // none, the body displaces the point.
  std::size_t released = 0;
  for (std::size_t i = 0; i + 1 < first.size(); ++i) {
    const std::size_t k = trapped_points[i];
    const Piece& a = bodies[holder[k] - 1];
    Vec3& x = positions[k];
    std::size_t free = first[i + 1];
    for (std::size_t w = first[i]; w < first[i + 1] && free == first[i + 1]; ++w) {
      const Vec3& end = ways[w].second;
      if (!crossing[w] && has_room(end) && !in_a_piece(end) && !in_a_solid(end) &&
          !through_another(x, end, a.object))
        free = w;
    }
    if (free == first[i + 1]) {
      if (displaced.empty()) displaced.assign(positions.size(), 0);
      displaced[k] = 1;
      continue;
    }
    x = ways[free].second;
    cells[key_of(cell_of(x))].push_back(x);
    const btRigidBody* rigid = btRigidBody::upcast(a.object);
    velocities[k] = rigid
                        ? to_vec3(rigid->getVelocityInLocalPoint(to_bt(x) - rigid->getCenterOfMassPosition()))
                        : Vec3::Zero();
    ++released;
  }
  return released;
}

std::string BulletRigidBodies::solid_holding(const Vec3& point, double depth) const {
  const double radius = 0.5 * depth;
  btSphereShape sphere(static_cast<btScalar>(radius));
  btCollisionObject probe;
  probe.setCollisionShape(&sphere);
  probe.setWorldTransform(btTransform(btQuaternion::getIdentity(), to_bt(point)));
  ProbeContacts result(probe, m_options);
  // A sphere whose centre lies outside overlaps a face by less than its radius; one whose centre lies
  // deeper than `depth`, by more than depth + radius.
  result.limit = static_cast<btScalar>(-(depth + radius));
  m_world.contactTest(&probe, result);
  if (result.holder == nullptr) return "";
  const btCollisionObjectArray& objects = m_world.getCollisionObjectArray();
  return describe(*result.holder, objects.findLinearSearch(const_cast<btCollisionObject*>(result.holder)));
}

std::vector<std::string> BulletRigidBodies::take_warnings() {
  std::vector<std::string> w;
  w.swap(m_warnings);
  return w;
}

}  // namespace drench::bullet
