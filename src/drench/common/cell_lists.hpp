#pragma once
/// Lists of indices by 64-bit cell key, kept across updates: the triangle grids of the grid broad phase
/// (coupling/broad_phase.cpp) and of the leak audit (coupling/leak_audit.cpp), where a triangle that changes
/// cells leaves the lists of its old cells and joins those of its new ones. Rebuilding a sorted array of
/// every (key, triangle) entry whenever any triangle changed cells was most of those grids' upkeep in issue
/// 41's level, where most triangles (a ground, a table) never move.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <drench/common/key_index_table.hpp>

namespace drench {

/// The order of a cell's list: ASCENDING as a fresh filing's (the leak audit names the first triangle a
/// particle crosses, so its visiting order is part of its result), or ANY where the caller sorts what it
/// found (the grid broad phase): adding appends and removing moves the last entry into the gap, which cost
/// about half of a binary search and a shift of the tail per cell in issue 41's level.
enum class CellListOrder { ASCENDING, ANY };

/// Each key's indices, in an open-addressing table (linear probing, at most half full) that grows as keys
/// come. A key stays, with an empty list, when its last index leaves, until clear().
template <class Index, CellListOrder kOrder = CellListOrder::ASCENDING>
class CellLists {
 public:
  /// Forgets every key and list.
  void clear() {
    m_keys.clear();
    m_lists.clear();
    m_slots.assign(16, -1);
    m_mask = 15;
  }

  /// The list of `key` (ascending when kOrder is ASCENDING), or null when the key never had one.
  const std::vector<Index>* find(std::uint64_t key) const {
    for (std::uint64_t slot = mix(key) & m_mask;; slot = (slot + 1) & m_mask) {
      const std::int32_t k = m_slots[slot];
      if (k < 0) return nullptr;
      if (m_keys[static_cast<std::size_t>(k)] == key) return &m_lists[static_cast<std::size_t>(k)];
    }
  }

  /// Adds `value` to the list of `key`: in its ascending place, or at the end for ANY (a value added twice
  /// is listed twice).
  void add(std::uint64_t key, Index value) {
    std::vector<Index>& list = m_lists[find_or_insert(key)];
    if (kOrder == CellListOrder::ASCENDING)
      list.insert(std::upper_bound(list.begin(), list.end(), value), value);
    else
      list.push_back(value);
  }

  /// Takes one `value` out of the list of `key`. Precondition: add(key, value) came before.
  void remove(std::uint64_t key, Index value) {
    std::vector<Index>& list = m_lists[find_or_insert(key)];
    if (kOrder == CellListOrder::ASCENDING) {
      list.erase(std::lower_bound(list.begin(), list.end(), value));
    } else {
      *std::find(list.begin(), list.end(), value) = list.back();
      list.pop_back();
    }
  }

 private:
  std::size_t find_or_insert(std::uint64_t key) {
    std::uint64_t slot = mix(key) & m_mask;
    for (;; slot = (slot + 1) & m_mask) {
      const std::int32_t k = m_slots[slot];
      if (k < 0) break;
      if (m_keys[static_cast<std::size_t>(k)] == key) return static_cast<std::size_t>(k);
    }
    if (2 * (m_keys.size() + 1) > m_slots.size()) {
      grow();
      return find_or_insert(key);
    }
    m_slots[slot] = static_cast<std::int32_t>(m_keys.size());
    m_keys.push_back(key);
    m_lists.emplace_back();
    return m_keys.size() - 1;
  }

  void grow() {
    m_slots.assign(2 * m_slots.size(), -1);
    m_mask = m_slots.size() - 1;
    for (std::size_t k = 0; k < m_keys.size(); ++k) {
      std::uint64_t slot = mix(m_keys[k]) & m_mask;
      while (m_slots[slot] >= 0)
        slot = (slot + 1) & m_mask;
      m_slots[slot] = static_cast<std::int32_t>(k);
    }
  }

  static std::uint64_t mix(std::uint64_t key) { return mix_cell_key(key); }

  std::vector<std::uint64_t> m_keys;
  std::vector<std::vector<Index>> m_lists;
  std::vector<std::int32_t> m_slots = std::vector<std::int32_t>(16, -1);  // slot -> key's position, -1 empty
  std::uint64_t m_mask = 15;
};

}  // namespace drench
