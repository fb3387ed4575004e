// How a mesh's indices move when a cloth of it is torn between two steps (cloth_layout.hpp): a cloth's
// nodes keep their place in it, the cloths after it and the other nodes after the cloths move up by the
// nodes it gained, a torn cloth's old faces are left unnamed, and a cloth that lost nodes is refused naming
// it.

#include <drench/coupling/cloth_layout.hpp>

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <drench/common/error.hpp>

namespace drench {
namespace {

// Two cloths (4 nodes and 2 faces, 3 nodes and 1 face); the mesh holds 2 nodes and 1 face of a body after
// them. Cloth 0 is torn: 2 nodes and 2 faces more.
const std::vector<ClothPiece> kBefore = {{0, 4, 0, 2}, {4, 3, 2, 1}};
const std::vector<ClothPiece> kAfter = {{0, 6, 0, 4}, {6, 3, 4, 1}};

TEST(ClothLayout, NodesAndFacesKeepTheirPlaceInTheirClothAndTheRestMoveUp) {
  const ClothLayoutChange change(kBefore, kAfter);
  const std::vector<std::size_t> nodes = {0, 1, 2, 3, 6, 7, 8, 9, 10};  // old 0..8: cloth 0, cloth 1, body
  for (std::size_t old = 0; old < nodes.size(); ++old)
    EXPECT_EQ(change.node(old), nodes[old]) << old;
  // Old faces 0..3: the torn cloth 0's two (their nodes may be others now: not followed), cloth 1's, the
  // body's.
  const std::vector<std::size_t> faces = {ClothLayoutChange::kGone, ClothLayoutChange::kGone, 4, 5};
  for (std::size_t old = 0; old < faces.size(); ++old)
    EXPECT_EQ(change.triangle(old), faces[old]) << old;
  for (std::size_t now = 0; now < 11; ++now)
    EXPECT_EQ(change.is_new_node(now), now == 4 || now == 5) << now;
  // An array of the old mesh's nodes (cloths' and body's) in the new layout, the new nodes filled.
  const std::vector<int> moved = change.nodes_moved(std::vector<int>{10, 11, 12, 13, 20, 21, 22, 30, 31}, -1);
  EXPECT_EQ(moved, (std::vector<int>{10, 11, 12, 13, -1, -1, 20, 21, 22, 30, 31}));
  EXPECT_EQ(change.cloth_nodes_before(), 7u);
  EXPECT_EQ(change.cloth_nodes_after(), 9u);
  EXPECT_EQ(change.cloth_triangles_before(), 3u);
  EXPECT_EQ(change.cloth_triangles_after(), 5u);
}

TEST(ClothLayout, AClothThatLostFacesLeavesItsOldFacesUnnamed) {
  // Cloth 1 lost its face (a game took it out) and gained a node; cloth 0 is as it was.
  const ClothLayoutChange change(kBefore, {{0, 4, 0, 2}, {4, 4, 2, 0}});
  EXPECT_EQ(change.triangle(0), 0u);
  EXPECT_EQ(change.triangle(1), 1u);
  EXPECT_EQ(change.triangle(2), ClothLayoutChange::kGone);
  EXPECT_EQ(change.triangle(3), 2u) << "the body's face moves down by the face cloth 1 lost";
  EXPECT_EQ(change.node(7), 8u) << "the body's first node moves up by the node cloth 1 gained";
}

TEST(ClothLayout, AClothThatLostNodesOrAnotherCountOfClothsIsRefused) {
  try {
    ClothLayoutChange({{0, 4, 0, 2}, {4, 3, 2, 1}}, {{0, 4, 0, 2}, {4, 2, 2, 1}});
    FAIL() << "a cloth with fewer nodes";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cloth 1 has 2 nodes, 3 before"), std::string::npos) << e.what();
  }
  try {
    ClothLayoutChange(kBefore, {{0, 7, 0, 3}});
    FAIL() << "another count of cloths";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("had 2 cloths and now has 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ClothLayoutChange(kBefore, {{0, 6, 0, 4}, {5, 3, 4, 1}}), std::invalid_argument)
      << "pieces that are not back to back";
}

}  // namespace
}  // namespace drench
