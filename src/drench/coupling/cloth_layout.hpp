#pragma once
/// Where each cloth of an engine lies in its mesh, and how a mesh's indices move when a game tears, cuts or
/// refines a cloth between two steps. Bullet's btSoftBody::cutLink and refine append nodes and faces to the
/// cloth's own (and rewire some of its faces to the new nodes); the nodes and faces of the cloths after it,
/// and of the obstacles and bodies after the cloths, move up by as many. What drench keeps from one step to
/// the next per node or face (owed impulses, the wetting's water, the strain limit's rest lengths, the jump
/// audit's end positions) follows its node or face through these maps instead of being lost.

#include <cstddef>
#include <utility>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// One cloth's nodes [first_node, first_node + nodes) and faces [first_triangle, first_triangle + triangles)
/// in an engine's mesh (ClothEngine::pieces).
struct ClothPiece {
  std::size_t first_node = 0;
  std::size_t nodes = 0;
  std::size_t first_triangle = 0;
  std::size_t triangles = 0;
};

/// All four fields equal: the same cloth in the same place.
bool operator==(const ClothPiece& a, const ClothPiece& b);
inline bool operator!=(const ClothPiece& a, const ClothPiece& b) {
  return !(a == b);
}

/// The maps from a mesh laid out as `before` (its cloths' pieces first, in order and back to back, then any
/// other nodes and faces) to the same mesh laid out as `after`. A cloth's existing nodes keep their place
/// in it (an engine appends nodes, never removes them). A torn cloth's faces are not followed: Bullet rewires
/// some of them to the new nodes and turns their corners (refine), so an old face's index no longer names
/// its nodes, and what is kept per face of it (a particle's barycentric weights) would land on other nodes.
class ClothLayoutChange {
 public:
  /// What an old face of a cloth that changed (other node or face counts) maps to.
  static constexpr std::size_t kGone = static_cast<std::size_t>(-1);

  /// @param before, after  the pieces of the two layouts, each starting at node and face 0, back to back
  /// @throws Error naming the cloth (its index) when the number of cloths differs or a cloth has fewer
  ///         nodes than before; std::invalid_argument when pieces are not back to back from 0
  ClothLayoutChange(std::vector<ClothPiece> before, std::vector<ClothPiece> after);

  /// The index now of node `old` of the old layout (a cloth's, or one after the cloths': moved up by the
  /// nodes the cloths gained). Precondition: `old` is a node of the old mesh (not checked).
  std::size_t node(std::size_t old) const;
  /// The index now of face `old` of the old layout: a face of a cloth whose node and face counts are as
  /// before keeps its place in it, one after the cloths' moves by the faces they gained or lost; kGone for
  /// a face of a cloth that changed. Precondition: `old` is a face of the old mesh (not checked).
  std::size_t triangle(std::size_t old) const;
  /// Whether node `now` of the new layout is one a cloth gained.
  bool is_new_node(std::size_t now) const;

  /// The cloths' nodes and faces, before and after (unit: count).
  std::size_t cloth_nodes_before() const { return m_nodes_before; }
  std::size_t cloth_nodes_after() const { return m_nodes_after; }
  std::size_t cloth_triangles_before() const { return m_triangles_before; }
  std::size_t cloth_triangles_after() const { return m_triangles_after; }

  /// The rest lengths of the cloths' edges now (unit: m), one per entry of `edges`: an edge that was one of
  /// `old_edges` (its nodes moved to their new indices) keeps its old rest length; another, around a node a
  /// tear added or drawn by a refinement, takes its length in `positions`.
  /// @param old_edges, old_lengths  the edges of the old layout (any order) and their rest lengths (m)
  /// @param edges  the edges now, each (lower, higher node index) of the new layout
  /// @param positions  the nodes now (unit: m)
  ScalarArray rest_lengths(const std::vector<std::pair<Index, Index>>& old_edges,
                           const ScalarArray& old_lengths, const std::vector<std::pair<Index, Index>>& edges,
                           const Vec3Array& positions) const;

  /// `old` (an array with one entry per node of the old layout, cloths' and others') in the new layout:
  /// each entry at its node's new index, `fill` at the nodes the cloths gained.
  template <class T>
  std::vector<T> nodes_moved(const std::vector<T>& old, const T& fill) const {
    std::vector<T> now(old.size() + m_nodes_after - m_nodes_before, fill);
    for (std::size_t i = 0; i < old.size(); ++i)
      now[node(i)] = old[i];
    return now;
  }

 private:
  /// The piece of `before` (or `after` for a new index) holding node `i`; pieces.size() past them.
  static std::size_t piece_of_node(const std::vector<ClothPiece>& pieces, std::size_t i);
  static std::size_t piece_of_triangle(const std::vector<ClothPiece>& pieces, std::size_t t);

  std::vector<ClothPiece> m_before, m_after;
  std::size_t m_nodes_before = 0, m_nodes_after = 0;
  std::size_t m_triangles_before = 0, m_triangles_after = 0;
};

}  // namespace drench
