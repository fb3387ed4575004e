#include <drench/coupling/cloth_layout.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include <drench/common/error.hpp>

namespace drench {

bool operator==(const ClothPiece& a, const ClothPiece& b) {
  return a.first_node == b.first_node && a.nodes == b.nodes && a.first_triangle == b.first_triangle &&
         a.triangles == b.triangles;
}

namespace {

/// The nodes and faces of back-to-back pieces; throws when they are not back to back from 0.
std::pair<std::size_t, std::size_t> totals(const std::vector<ClothPiece>& pieces, const char* which) {
  std::size_t nodes = 0, triangles = 0;
  for (std::size_t c = 0; c < pieces.size(); ++c) {
    if (pieces[c].first_node != nodes || pieces[c].first_triangle != triangles) {
      throw std::invalid_argument(std::string("ClothLayoutChange: cloth ") + std::to_string(c) + " of the " +
                                  which + " layout does not start where cloth " + std::to_string(c) +
                                  " - 1 ends");
    }
    nodes += pieces[c].nodes;
    triangles += pieces[c].triangles;
  }
  return {nodes, triangles};
}

}  // namespace

ClothLayoutChange::ClothLayoutChange(std::vector<ClothPiece> before, std::vector<ClothPiece> after)
    : m_before(std::move(before)), m_after(std::move(after)) {
  if (m_before.size() != m_after.size()) {
    throw Error("the engine had " + std::to_string(m_before.size()) + " cloths and now has " +
                std::to_string(m_after.size()) +
                ": drench follows a cloth's new nodes and faces, not a new cloth");
  }
  std::tie(m_nodes_before, m_triangles_before) = totals(m_before, "old");
  std::tie(m_nodes_after, m_triangles_after) = totals(m_after, "new");
  for (std::size_t c = 0; c < m_before.size(); ++c) {
    if (m_after[c].nodes < m_before[c].nodes) {
      throw Error("cloth " + std::to_string(c) + " has " + std::to_string(m_after[c].nodes) + " nodes, " +
                  std::to_string(m_before[c].nodes) +
                  " before: drench follows nodes added to a cloth (torn, cut, refined), not removed");
    }
  }
}

std::size_t ClothLayoutChange::piece_of_node(const std::vector<ClothPiece>& pieces, std::size_t i) {
  for (std::size_t c = 0; c < pieces.size(); ++c) {
    if (i < pieces[c].first_node + pieces[c].nodes) return c;
  }
  return pieces.size();
}

std::size_t ClothLayoutChange::piece_of_triangle(const std::vector<ClothPiece>& pieces, std::size_t t) {
  for (std::size_t c = 0; c < pieces.size(); ++c) {
    if (t < pieces[c].first_triangle + pieces[c].triangles) return c;
  }
  return pieces.size();
}

std::size_t ClothLayoutChange::node(std::size_t old) const {
  const std::size_t c = piece_of_node(m_before, old);
  if (c == m_before.size()) return old - m_nodes_before + m_nodes_after;
  return m_after[c].first_node + (old - m_before[c].first_node);
}

std::size_t ClothLayoutChange::triangle(std::size_t old) const {
  const std::size_t c = piece_of_triangle(m_before, old);
  if (c == m_before.size()) return old - m_triangles_before + m_triangles_after;
  if (m_after[c].nodes != m_before[c].nodes || m_after[c].triangles != m_before[c].triangles) return kGone;
  return m_after[c].first_triangle + (old - m_before[c].first_triangle);
}

bool ClothLayoutChange::is_new_node(std::size_t now) const {
  const std::size_t c = piece_of_node(m_after, now);
  if (c == m_after.size()) return false;
  return now - m_after[c].first_node >= m_before[c].nodes;
}

ScalarArray ClothLayoutChange::rest_lengths(const std::vector<std::pair<Index, Index>>& old_edges,
                                            const ScalarArray& old_lengths,
                                            const std::vector<std::pair<Index, Index>>& edges,
                                            const Vec3Array& positions) const {
  std::vector<std::pair<std::pair<Index, Index>, double>> kept;
  kept.reserve(old_edges.size());
  for (std::size_t e = 0; e < old_edges.size(); ++e) {
    const auto a = static_cast<Index>(node(old_edges[e].first));
    const auto b = static_cast<Index>(node(old_edges[e].second));
    kept.push_back({{std::min(a, b), std::max(a, b)}, old_lengths[e]});
  }
  std::sort(kept.begin(), kept.end());
  ScalarArray lengths;
  lengths.reserve(edges.size());
  for (const auto& edge : edges) {
    const auto found = std::lower_bound(kept.begin(), kept.end(), std::make_pair(edge, -1.0));
    lengths.push_back(found != kept.end() && found->first == edge
                          ? found->second
                          : (positions[edge.first] - positions[edge.second]).norm());
  }
  return lengths;
}

}  // namespace drench
