#pragma once
/// Any Bullet collision shape as a triangle mesh in its own local frame: Huber et al. 2013 sec. 5 couples
/// rigid objects with the fluid as triangle meshes, so every shape of a game's world becomes one.
///
/// The surface is the one Bullet collides with. For a convex shape that is the surface whose support
/// function is the shape's localGetSupportingVertex (local scaling and collision margin included):
///   btBoxShape          its box of getHalfExtentsWithMargin() (the margin lies inside the given extents)
///   btSphereShape       radius getRadius() (the margin is the radius)
///   btCapsuleShape      the segment of half length getHalfHeight() grown by getRadius()
///   btCylinderShape     the cylinder shrunk by the margin, grown back by it: the given extents, with edges
///                       rounded to the margin's radius
///   btConeShape         the cone of getRadius(), getHeight() grown outward by the margin (rounded apex, rim)
///   btConvexHullShape,  the hull of the scaled points grown outward by the margin (default 0.04 m): flat
///   faces btConvexPointCloud- moved out by it, edges and corners rounded Shape, btConvexTriangleMeshShape
///   btMultiSphereShape  the hull of its spheres, sampled through Bullet's support mapping
///   btUniformScalingShape  its child's mesh, scaled
/// Bullet's GJK-based pairs (and btSphereBoxCollisionAlgorithm) round a box's corners by its margin as well;
/// the mesh keeps the sharp box of localGetSupportingVertex, which differs from that at edges and corners by
/// at most (sqrt(3) - 1) times the margin.
/// A concave shape gives its triangles as stored (btBvhTriangleMeshShape, btMultimaterialTriangleMeshShape,
/// btScaledBvhTriangleMeshShape, btHeightfieldTerrainShape), a btStaticPlaneShape a finite square of it, a
/// btEmptyShape no triangle, a btCompoundShape its children's meshes.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/common/triangle_mesh.hpp>

class btCollisionShape;
class btStaticPlaneShape;

namespace drench::bullet {

/// How finely curved and unbounded shapes become triangles.
struct ShapeMeshOptions {
  double max_edge = 0.02;        ///< longest facet edge on curved surfaces (sphere, capsule, cylinder, cone,
                                 ///< rounded margins) (unit: m), > 0
  double plane_half_size = 2.0;  ///< a btStaticPlaneShape becomes a square of this half side (unit: m), > 0,
                                 ///< centred where the plane is closest to the shape's local origin
                                 ///< (BulletRigidBodies: until water or a cloth comes near the plane)
  double plane_cell = 0.1;  ///< the plane square's grid cell (unit: m), > 0 (small faces keep the coupling's
                            ///< bounding-box broad phase tight on tilted planes)
};

/// The most triangles shape_mesh builds for one curved or unbounded shape (about 150 MB of mesh), so that a
/// max_edge or plane_cell far too small for the shape is an error instead of an exhausted memory. Triangle
/// meshes and heightfields are the game's own data and are not limited.
inline constexpr std::size_t kMaxShapeMeshTriangles = 4'000'000;

/// The surface of `shape` in its own local frame (the frame a btCollisionObject's world transform maps to
/// world), as Bullet collides with it: local scaling and collision margin included. Closed shapes give a
/// closed, consistently outward-oriented mesh (counter-clockwise seen from outside); a btCompoundShape gives
/// its children's meshes (recursively) in the compound's frame, concatenated; a triangle mesh or heightfield
/// gives its triangles (faces that repeat a vertex or have no area dropped), sharing vertices as the shape
/// does.
///
/// Curved surfaces (spheres, capsules, cylinders, cones and every rounded margin) have vertices on Bullet's
/// surface to rounding and edges of at most options.max_edge, also along a cylinder's or cone's side. Flat
/// faces (a box's, a cylinder's caps, a cone's base, a hull's faces) and, on a hull with a margin, the
/// strips rounding its edges keep their own size. A concave shape's collision margin (Bullet thickens each
/// of its triangles by it, default 0) is not applied; a triangle mesh keeps its stored winding, a
/// heightfield Bullet's.
/// @param shape  any Bullet collision shape; the mesh is in its local frame (unit: m)
/// @param options  fineness of curved and unbounded shapes, each > 0 and finite
/// @return M vertices and F triangles (counter-clockwise seen from outside for closed shapes)
/// @throws drench::SceneError naming the shape (shape.getName(), and the child index path for compounds, e.g.
///         "btCompoundShape child 2: SoftBody ...") when the shape type is not supported, its dimensions
///         are not positive and finite, options are out of range, or the mesh would exceed
///         kMaxShapeMeshTriangles
TriangleMesh shape_mesh(const btCollisionShape& shape, const ShapeMeshOptions& options = {});

/// True when shape_mesh supports `shape` (recursively for compounds), without building it.
bool is_supported_shape(const btCollisionShape& shape);

/// True when Bullet collides nothing with `shape`: a btEmptyShape, or a compound whose children all are
/// (recursively; an empty compound too). Its mesh has no triangle, and that is no corruption.
bool collides_with_nothing(const btCollisionShape& shape);

/// A digest of what a game may change in place of `shape` that shape_mesh reads: its type, local scaling,
/// margin and local bounding box and, for a compound or a btUniformScalingShape (recursively), its children,
/// their transforms and their own digests. A cache of shape_mesh keyed by the shape's address and this
/// follows a compound whose children the game adds, removes or moves. Not in it: the vertices of a triangle
/// mesh or heightfield, the game's own data.
std::uint64_t shape_signature(const btCollisionShape& shape);

/// A btStaticPlaneShape's plane n . x = c in the shape's local frame, with a grid on it: the plane is
/// unbounded, so that a caller can mesh the part of it the water comes near (BulletRigidBodies does) instead
/// of shape_mesh's fixed square.
struct PlaneFrame {
  Vec3 origin;  ///< c n / |n|^2, the plane's point nearest the local origin (unit: m)
  Vec3 normal;  ///< n / |n|: the side the water stays on (the solid is the other side)
  Vec3 axis_u;  ///< a unit vector in the plane
  Vec3 axis_v;  ///< normal x axis_u, so that axis_u x axis_v = normal
};

/// @throws drench::SceneError naming the shape when its normal is zero or not finite or its constant is not
///         finite
PlaneFrame plane_frame(const btStaticPlaneShape& plane);

/// One square cell of a plane's grid of side `cell` (unit: m): cell (i, j) spans origin + [i, i + 1] cell
/// axis_u + [j, j + 1] cell axis_v.
using PlaneCell = std::pair<std::int64_t, std::int64_t>;

/// For unordered containers of PlaneCell.
struct PlaneCellHash {
  std::size_t operator()(const PlaneCell& c) const {
    return static_cast<std::size_t>(static_cast<std::uint64_t>(c.first) * 0x9E3779B97F4A7C15ull ^
                                    static_cast<std::uint64_t>(c.second));
  }
};

/// The cells `cells` of `frame`'s grid as triangles, counter-clockwise seen from the normal's side, with
/// the vertices of neighbouring cells shared (no crack between cells). Each vertex is computed from its grid
/// coordinates alone, so that the same grid node is the same point in every mesh built on the same grid.
/// @param cell  the grid's side (unit: m), > 0 and finite
/// @param cells  distinct cells, at most kMaxShapeMeshTriangles / 2
/// @throws drench::SceneError when cell is out of range or there are too many cells
TriangleMesh plane_cells_mesh(const PlaneFrame& frame, double cell, const std::vector<PlaneCell>& cells);

}  // namespace drench::bullet
