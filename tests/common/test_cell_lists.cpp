// CellLists (common/cell_lists.hpp), the triangle grids' lists kept across updates: after any sequence of
// additions and removals each key lists exactly the values added and not yet removed, ascending for
// ASCENDING (the leak audit's order) and in some order for ANY (the grid broad phase's).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <drench/common/cell_lists.hpp>

namespace drench {
namespace {

/// Random additions and removals over 40 keys (a few thousand apart, as cell keys are) and values 0-199,
/// with values listed twice under one key (two cells of a triangle whose keys collide): every 500 changes,
/// and at the end, each key's list is compared with a reference multiset.
template <CellListOrder kOrder>
void expect_lists_follow_the_changes() {
  std::mt19937_64 rng(5);
  CellLists<int, kOrder> lists;
  lists.clear();
  std::map<std::uint64_t, std::vector<int>> expected;  // per key, its values ascending
  const auto key_of = [](std::uint64_t k) { return 7919 * k + 3; };
  const auto check = [&](int change) {
    for (std::uint64_t k = 0; k < 40; ++k) {
      const std::vector<int>* list = lists.find(key_of(k));
      const auto it = expected.find(key_of(k));
      if (it == expected.end()) {
        EXPECT_EQ(list, nullptr) << "key " << k << " after change " << change;
        continue;
      }
      ASSERT_NE(list, nullptr) << "key " << k << " after change " << change;
      std::vector<int> got = *list;
      if (kOrder == CellListOrder::ANY) std::sort(got.begin(), got.end());
      EXPECT_EQ(got, it->second) << "key " << k << " after change " << change;
      if (kOrder == CellListOrder::ASCENDING) {
        EXPECT_TRUE(std::is_sorted(list->begin(), list->end())) << "key " << k;
      }
    }
  };
  for (int change = 0; change < 4000; ++change) {
    const std::uint64_t key = key_of(rng() % 40);
    std::vector<int>& values = expected[key];
    if (!values.empty() && rng() % 2 == 0) {
      const int value = values[rng() % values.size()];
      lists.remove(key, value);
      values.erase(std::lower_bound(values.begin(), values.end(), value));
    } else {
      const int value = static_cast<int>(rng() % 200);
      lists.add(key, value);
      values.insert(std::upper_bound(values.begin(), values.end(), value), value);
    }
    if (change % 500 == 0) check(change);
  }
  check(4000);
  lists.clear();
  EXPECT_EQ(lists.find(key_of(0)), nullptr) << "after clear()";
}

TEST(CellLists, AscendingListsHoldTheValuesAddedAndNotRemovedInOrder) {
  expect_lists_follow_the_changes<CellListOrder::ASCENDING>();
}

TEST(CellLists, UnorderedListsHoldTheValuesAddedAndNotRemoved) {
  expect_lists_follow_the_changes<CellListOrder::ANY>();
}

}  // namespace
}  // namespace drench
