#pragma once
/// Distinct 64-bit keys and an open-addressing table that finds a key's position among them in O(1): the
/// hashed cells of the fluid's grid search (sph/neighbor_search.cpp) and of the grid broad phase
/// (coupling/broad_phase.cpp), where a binary search over the keys cost log n comparisons per cell.

#include <cstdint>
#include <utility>
#include <vector>

namespace drench {

/// splitmix64's finaliser: neighbouring cells' keys (Morton codes, or products of coordinates) differ in few
/// bits, so hash tables of cells mix them before masking them to a slot.
inline std::uint64_t mix_cell_key(std::uint64_t key) {
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return key;
}

class KeyIndexTable {
 public:
  /// Takes `keys` (distinct, in any order; they keep it) and indexes them. The table is at most half full,
  /// linear probing.
  void build(std::vector<std::uint64_t> keys) {
    m_keys = std::move(keys);
    std::size_t capacity = 16;
    while (capacity < 2 * m_keys.size())
      capacity *= 2;
    m_slots.assign(capacity, -1);
    m_mask = capacity - 1;
    for (std::size_t k = 0; k < m_keys.size(); ++k) {
      std::uint64_t slot = mix(m_keys[k]) & m_mask;
      while (m_slots[slot] >= 0)
        slot = (slot + 1) & m_mask;
      m_slots[slot] = static_cast<std::int64_t>(k);
    }
  }

  /// Forgets the keys (find() then answers -1).
  void clear() { build({}); }

  /// The position of `key` in the keys given to build(), or -1.
  std::int64_t find(std::uint64_t key) const {
    std::uint64_t slot = mix(key) & m_mask;
    while (true) {
      const std::int64_t k = m_slots[slot];
      if (k < 0 || m_keys[static_cast<std::size_t>(k)] == key) return k;
      slot = (slot + 1) & m_mask;
    }
  }

 private:
  static std::uint64_t mix(std::uint64_t key) { return mix_cell_key(key); }

  std::vector<std::uint64_t> m_keys;
  std::vector<std::int64_t> m_slots =
      std::vector<std::int64_t>(16, -1);  // slot -> position in m_keys, -1 empty
  std::uint64_t m_mask = 15;
};

/// Indexes the runs of equal keys in `entries`, sorted by key: `run_begin` gets the first entry of each
/// distinct key and one extra end entry, `table` the distinct keys in order, so that the entries of a key
/// that `table.find` places at k are [run_begin[k], run_begin[k + 1]). The cell grids of the grid broad phase
/// and of the leak audit keep their triangles so (coupling/broad_phase.cpp, coupling/leak_audit.cpp).
/// Precondition: fewer than 2^32 entries.
template <class Value>
void index_key_runs(const std::vector<std::pair<std::uint64_t, Value>>& entries,
                    std::vector<std::uint32_t>& run_begin, KeyIndexTable& table) {
  std::vector<std::uint64_t> keys;
  run_begin.clear();
  for (std::size_t e = 0; e < entries.size(); ++e) {
    if (e == 0 || entries[e].first != entries[e - 1].first) {
      keys.push_back(entries[e].first);
      run_begin.push_back(static_cast<std::uint32_t>(e));
    }
  }
  run_begin.push_back(static_cast<std::uint32_t>(entries.size()));
  table.build(std::move(keys));
}

}  // namespace drench
