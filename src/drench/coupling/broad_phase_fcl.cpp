// The FCL broad phase: the cloth's triangles in an fcl::DynamicAABBTreeCollisionManager, refitted when the
// cloth changed (bare boxes: the margin grows the query), queried with each particle's swept, grown box. FCL
// only proposes candidates; the same exact box test as the grid (Box3::overlaps) decides, so the pairs are
// exactly the brute-force set. FCL stays inside this file.

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/narrowphase/collision_object.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include <drench/coupling/broad_phase.hpp>

namespace drench {
namespace {

/// A collision object whose world AABB is exactly `box`. The geometry's local AABB is set by hand and the
/// transform is the identity, so computeAABB() copies it (it adds a zero translation): no rounding from a
/// centre and half-extents, hence no pair lost at touching boxes. The Box shape itself is never used.
class BoxObject {
 public:
  BoxObject() : m_shape(std::make_shared<fcl::Boxd>(1.0, 1.0, 1.0)), m_object(m_shape) {}

  void set(const Box3& box) {
    m_shape->aabb_local.min_ = box.lo;
    m_shape->aabb_local.max_ = box.hi;
    m_object.computeAABB();
  }
  fcl::CollisionObjectd* object() { return &m_object; }

 private:
  std::shared_ptr<fcl::Boxd> m_shape;
  fcl::CollisionObjectd m_object;
};

/// Triangle indices of the tree's leaves whose AABB overlaps the query's (FCL's test is inclusive, like
/// Box3::overlaps). The triangle's index is the leaf's user data.
bool collect_triangle(fcl::CollisionObjectd* leaf, fcl::CollisionObjectd* /*query*/, void* data) {
  auto* candidates = static_cast<std::vector<Index>*>(data);
  candidates->push_back(static_cast<Index>(reinterpret_cast<std::uintptr_t>(leaf->getUserData())));
  return false;  // never stop early
}

/// One query per particle, in parallel: the tree is only read during the queries. A second tree of the
/// particles, queried tree against tree, is slower on bench_coupling's cases: the particles move every step,
/// building their tree takes longer than all the per-particle queries, and FCL's recursion runs on one
/// thread. Refitting the triangles' tree (update()) costs a fraction of rebuilding it.
class FclBroadPhase final : public TriangleBroadPhase {
 public:
  void find_pairs(const Vec3Array& particles_t0, const Vec3Array& particles_t1, const ClothMesh& cloth,
                  double margin, const std::vector<std::uint8_t>* only,
                  std::vector<std::pair<Index, Index>>& pairs) override {
    pairs.clear();
    const std::size_t f = cloth.triangles.size();
    const std::size_t n = particles_t0.size();
    if (f == 0 || n == 0) return;
    if (!m_built_for.same_as_last(cloth)) update_tree(cloth);

    collect_pairs(
        particles_t0, particles_t1, margin, only,
        [&](const Box3& box, std::vector<Index>& hits) {
          thread_local BoxObject query;  // one FCL object per thread, reused
          thread_local std::vector<Index> candidates;
          query.set(box);
          candidates.clear();
          m_manager.collide(query.object(), &candidates, collect_triangle);
          // FCL only proposes: the same exact test as the grid decides.
          for (Index t : candidates) {
            if (box.overlaps(m_boxes[t])) hits.push_back(t);
          }
        },
        pairs);
  }

 private:
  /// Sets every triangle's object to its swept (bare) box. The first call (or a mesh with another triangle
  /// count) builds the tree top-down; later calls refit it and let FCL rebalance (manager update()).
  void update_tree(const ClothMesh& cloth) {
    const std::size_t f = cloth.triangles.size();
    const bool rebuild = m_objects.size() != f;
    if (rebuild) {
      m_manager.clear();
      m_objects.clear();
      m_objects.reserve(f);
      for (std::size_t t = 0; t < f; ++t) {
        m_objects.push_back(std::make_unique<BoxObject>());
        m_objects.back()->object()->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(t)));
      }
    }
    m_boxes.resize(f);
    for (std::size_t t = 0; t < f; ++t) {
      m_boxes[t] = triangle_box(cloth, cloth.triangles[t], 0.0);
      m_objects[t]->set(m_boxes[t]);
    }
    if (rebuild) {
      std::vector<fcl::CollisionObjectd*> objects(f);
      for (std::size_t t = 0; t < f; ++t)
        objects[t] = m_objects[t]->object();
      m_manager.registerObjects(objects);
      m_manager.setup();
    } else {
      m_manager.update();
    }
  }

  std::vector<std::unique_ptr<BoxObject>> m_objects;  // F, triangle t's object (outlives the manager)
  std::vector<Box3> m_boxes;                          // F, triangle t's swept (bare) box
  fcl::DynamicAABBTreeCollisionManagerd m_manager;    // leaves point into m_objects
  TriangleBoxKey m_built_for;
};

}  // namespace

std::unique_ptr<TriangleBroadPhase> make_broad_phase_fcl() {
  return std::make_unique<FclBroadPhase>();
}

}  // namespace drench
