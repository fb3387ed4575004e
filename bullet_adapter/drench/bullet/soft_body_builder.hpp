#pragma once
/// Builds a Bullet soft body for cloth from ClothSettings (docs/scenes.md, `cloth`): a regular patch from
/// btSoftBodyHelpers::CreatePatch or a triangle mesh from an OBJ file, with node masses from the area
/// density, pinned nodes, stretch stiffness, bending links, damping and a small collision margin.

#include <BulletSoftBody/btSoftBody.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/coupling/cloth_engine.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/io/obj_reader.hpp>

namespace drench::bullet {

/// Collision margin of the soft bodies the adapter builds (unit: m). Bullet's default, 0.25 m, is almost the
/// size of the default patch: rigid bodies would be stopped a quarter metre from the cloth. The fluid never
/// sees this margin; the coupling has its own thickness (CouplingSettings::cloth_thickness).
inline constexpr double CLOTH_COLLISION_MARGIN = 0.005;

/// The mesh type and OBJ reader of the core, also under the adapter's name.
using drench::TriangleMesh;

/// Throws SceneError naming the first field of `settings` out of its range (the ranges are those documented
/// in coupling/cloth_engine.hpp), as `cloth.<field> must be <range>, got <value>`.
void validate_cloth_settings(const ClothSettings& settings);

/// load_obj_mesh (io/obj_reader.hpp) for a cloth: also throws SceneError when the mesh has more vertices
/// than Bullet counts in int.
TriangleMesh load_cloth_obj_mesh(const std::string& path);

/// A soft body with one node per vertex (mass 1 each, to be set), one face per triangle and one link per
/// edge, built exactly as btSoftBodyHelpers::CreateFromTriMesh(world_info, ..., randomizeConstraints = true)
/// builds it (the tests compare them link by link). That helper keeps a vertices x vertices table of booleans
/// (2.5 GB for 50K vertices); this one keeps a hash set of edges.
/// @param mesh  valid: indices < M, no repeated index in a triangle
std::unique_ptr<btSoftBody> create_from_triangles(btSoftBodyWorldInfo& world_info, const TriangleMesh& mesh);

/// Appends a bending link, made of `material`, between every two nodes two links apart; the same links in the
/// same order as btSoftBody::generateBendingConstraints(2, material), which fills a nodes x nodes table of
/// distances first (42 MB for the 57 x 57 patch, 683 MB for 113 x 113, 10 GB for 225 x 225). This one visits
/// the neighbours of neighbours: O(nodes x degree^2).
/// @return the number of links appended
int append_bending_links(btSoftBody& body, btSoftBody::Material* material);

/// Node masses of a cloth of uniform `area_density` (unit: kg/m^2): each triangle's mass, density x area,
/// split equally among its three nodes (unit: kg). M entries; a node in no face gets 0.
ScalarArray node_masses_from_area(const btSoftBody& body, double area_density);

/// The nodes ClothSettings::pinned names: "none" (none), "corner" (the node with the smallest x + z) or
/// "corners" (the nodes with the largest -x-z, x-z, -x+z and x+z: the four corners of a patch in the xz
/// plane). Ties go to the lowest index. Sorted, without repeats.
std::vector<int> pinned_nodes(const btSoftBody& body, const std::string& pinned);

/// The soft body ClothSettings describes, in `world_info` (which must outlive it; it is not added to a
/// world): patch or OBJ mesh, node masses from area density with the pinned nodes at mass 0, stretch
/// stiffness kLST on the default material, bending links (when bending_stiffness > 0) on a second material,
/// piterations, kDP, collision margin CLOTH_COLLISION_MARGIN, rigid-soft collision only (no self collision).
/// The patch spans [center.x -+ size_x / 2] x [center.z -+ size_z / 2] at y = center.y, node (i, k) at index
/// k nodes_x + i (i along x, k along z), with diagonal shear links; 2 (nodes_x - 1)(nodes_z - 1) triangles.
/// @throws SceneError as validate_cloth_settings and load_obj_mesh
std::unique_ptr<btSoftBody> create_cloth_body(btSoftBodyWorldInfo& world_info, const ClothSettings& settings);

/// Sets node masses of a body that may already have moved, keeping every link's rest length. Use it instead
/// of btSoftBody::setMass on a cloth that has stepped: setMass flags the body's constants for an update, and
/// at its next step Bullet 3.24 (btSoftBody::updateConstants) resets every link's rest length to its current
/// length (test_bullet_cloth, SetNodeMassesKeepsRestLengthsWhereSetMassResetsThem), so a sagging cloth keeps
/// its stretch for good, and a cloth whose masses change every step (a wetting cloth) creeps without bound.
/// Here only the link constants that depend on the masses (Link::m_c0) are recomputed.
/// @param masses  (node index, mass) pairs; mass in kg, >= 0 and finite; 0 pins the node where it is (its
///        velocity is set to zero: Bullet moves a node by its velocity whatever its mass)
/// @throws std::invalid_argument naming the first pair whose index is out of range or whose mass is negative
///         or not finite; nothing is changed then
void set_node_masses(btSoftBody& body, const std::vector<std::pair<int, double>>& masses);

/// Index of a node of `body` from a pointer into its node array (Node::index is never set by Bullet).
inline int node_index(const btSoftBody& body, const btSoftBody::Node* node) {
  return static_cast<int>(node - &body.m_nodes[0]);
}

}  // namespace drench::bullet
