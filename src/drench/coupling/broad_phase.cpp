#include <drench/coupling/broad_phase.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <drench/common/key_index_table.hpp>
#include <drench/common/parallel.hpp>

namespace drench {
namespace {

/// Triangles binned into a uniform grid of cells about one triangle box in size: a particle looks only at the
/// cells its swept box covers. Keys are hashed cell coordinates; a hash collision only adds candidates, which
/// the exact box test removes. The bins are kept across calls and only the triangles whose box now covers
/// other cells are rebinned: in a game's level most triangles (the ground's square, a table) never move, and
/// a moving cloth's triangles move by a small part of a cell per step, so most keep their cells. Rebinning
/// every triangle whose box changed made the grid 1.75x FCL's time on bench_coupling's coupler_step, where
/// the whole cloth moves (issue 41). The cell size only decides speed, never the pairs, so it is kept while
/// the mean box stays within a factor 2 of it.
class GridBroadPhase final : public TriangleBroadPhase {
 public:
  void find_pairs(const Vec3Array& particles_t0, const Vec3Array& particles_t1, const ClothMesh& cloth,
                  double margin, const std::vector<std::uint8_t>* only,
                  std::vector<std::pair<Index, Index>>& pairs) override {
    pairs.clear();
    const std::size_t f = cloth.triangles.size();
    const std::size_t n = particles_t0.size();
    if (f == 0 || n == 0) return;
    // The same cloth as the last call (every sub-step's obstacle, every CCD round): nothing to rebin, and
    // comparing the positions costs less than recomputing every triangle's box.
    if (!m_built_for.same_as_last(cloth)) update_bins(cloth);

    collect_pairs(
        particles_t0, particles_t1, margin, only, m_boxes,
        [&](const Box3& box, std::vector<Index>& candidates) {
          candidates.assign(m_everywhere.begin(), m_everywhere.end());
          const bool binned = for_cells(box, [&](std::uint64_t key) {
            const std::int64_t cell = m_cells.find(key);
            if (cell < 0) return;
            for (std::uint32_t e = m_cell_begin[cell]; e < m_cell_begin[cell + 1]; ++e)
              candidates.push_back(m_entries[e].second);
          });
          if (!binned) {
            candidates.resize(f);
            for (std::size_t t = 0; t < f; ++t)
              candidates[t] = static_cast<Index>(t);
          }
        },
        pairs);
  }

 private:
  /// The cells a box covers, [lo, hi] per axis, or `everywhere` when they are too many for the grid (a box
  /// with a NaN among them): for_cells' decision, kept per triangle to tell when it must be rebinned.
  struct CellRange {
    Eigen::Array3d lo = Eigen::Array3d::Zero(), hi = Eigen::Array3d::Zero();
    bool everywhere = true;
    bool operator==(const CellRange& o) const {
      return everywhere == o.everywhere && (everywhere || ((lo == o.lo).all() && (hi == o.hi).all()));
    }
  };

  CellRange cell_range(const Box3& box) const {
    CellRange r;
    r.lo = (box.lo / m_cell).array().floor();
    r.hi = (box.hi / m_cell).array().floor();
    r.everywhere = !((r.hi - r.lo + 1.0).prod() <= kMaxCellsPerBox);
    return r;
  }

  /// Brings the bins to `cloth`'s triangle boxes. A triangle is rebinned when its box covers other cells than
  /// those it was binned in (a box with a NaN is filed for every query), so the bins are those a fresh
  /// binning with the same cell size would make; every box is updated for the exact test.
  void update_bins(const ClothMesh& cloth) {
    const std::size_t f = cloth.triangles.size();
    m_boxes.resize(f);
    double extent_sum = 0.0;
    for (std::size_t t = 0; t < f; ++t) {
      m_boxes[t] = triangle_box(cloth, cloth.triangles[t], 0.0);
      extent_sum += (m_boxes[t].hi - m_boxes[t].lo).maxCoeff();
    }
    const double cell = std::max(extent_sum / static_cast<double>(f), 1e-9);
    const bool rebin_all = m_ranges.size() != f || !(cell <= 2.0 * m_cell && cell >= 0.5 * m_cell);
    if (rebin_all) m_cell = cell;
    m_changed.assign(f, 0);
    std::size_t changed = 0;
    m_ranges.resize(f);
    for (std::size_t t = 0; t < f; ++t) {
      const CellRange range = cell_range(m_boxes[t]);
      if (rebin_all || !(range == m_ranges[t])) {
        m_ranges[t] = range;
        m_changed[t] = 1;
        ++changed;
      }
    }
    if (changed == 0) return;
    if (rebin_all) {
      m_entries.clear();
      m_everywhere.clear();
    } else {
      const auto stale = [&](Index t) { return m_changed[t] != 0; };
      m_entries.erase(std::remove_if(m_entries.begin(), m_entries.end(),
                                     [&](const auto& entry) { return stale(entry.second); }),
                      m_entries.end());
      m_everywhere.erase(std::remove_if(m_everywhere.begin(), m_everywhere.end(), stale), m_everywhere.end());
    }
    // The changed triangles' entries, sorted, merged into the kept ones (which stay sorted).
    const std::size_t kept = m_entries.size();
    for (std::size_t t = 0; t < f; ++t) {
      if (!m_changed[t]) continue;
      const bool binned = for_cells(m_boxes[t], [&](std::uint64_t key) {
        m_entries.push_back({key, static_cast<Index>(t)});
      });
      if (!binned) m_everywhere.push_back(static_cast<Index>(t));  // too large for the grid: every particle's
    }
    std::sort(m_entries.begin() + static_cast<std::ptrdiff_t>(kept), m_entries.end());
    std::inplace_merge(m_entries.begin(), m_entries.begin() + static_cast<std::ptrdiff_t>(kept),
                       m_entries.end());
    std::sort(m_everywhere.begin(), m_everywhere.end());
    // Each distinct key's run of entries, found through a hash table: a binary search of all the entries
    // per cell would dominate the grid's queries (bench_coupling find_pairs, docs/performance.md).
    index_key_runs(m_entries, m_cell_begin, m_cells);
  }

  /// Visits the keys of the cells the box covers; returns false, visiting nothing, when they are too many (a
  /// particle flying across the domain in one step), and the caller tests every triangle instead.
  template <class Visit>
  bool for_cells(const Box3& box, Visit&& visit) const {
    const Eigen::Array3d lo = (box.lo / m_cell).array().floor();
    const Eigen::Array3d hi = (box.hi / m_cell).array().floor();
    const Eigen::Array3d count = hi - lo + 1.0;
    if (!(count.prod() <= kMaxCellsPerBox)) return false;
    for (double z = lo[2]; z <= hi[2]; z += 1.0) {
      for (double y = lo[1]; y <= hi[1]; y += 1.0) {
        for (double x = lo[0]; x <= hi[0]; x += 1.0)
          visit(key(x, y, z));
      }
    }
    return true;
  }

  static constexpr double kMaxCellsPerBox = 4096.0;

  static std::uint64_t key(double x, double y, double z) {
    const auto i = static_cast<std::uint64_t>(static_cast<std::int64_t>(x));
    const auto j = static_cast<std::uint64_t>(static_cast<std::int64_t>(y));
    const auto k = static_cast<std::uint64_t>(static_cast<std::int64_t>(z));
    return (i * 73856093ULL) ^ (j * 19349663ULL) ^ (k * 83492791ULL);
  }

  double m_cell = 1.0;
  std::vector<Box3> m_boxes;        // F, each triangle's current box (the exact test's)
  std::vector<CellRange> m_ranges;  // F, the cells each triangle is binned in
  std::vector<std::uint8_t> m_changed;
  std::vector<std::pair<std::uint64_t, Index>> m_entries;  // (cell key, triangle), ascending
  KeyIndexTable m_cells;                                   // the distinct keys of m_entries, ascending
  std::vector<std::uint32_t> m_cell_begin;  // first entry of each distinct key; one extra end entry
  std::vector<Index> m_everywhere;
  TriangleBoxKey m_built_for;
};

}  // namespace

bool TriangleBoxKey::same_as_last(const ClothMesh& cloth) {
  if (m_valid && cloth.positions_t0 == m_positions_t0 && cloth.positions_t1 == m_positions_t1 &&
      cloth.triangles == m_triangles) {
    return true;
  }
  m_valid = true;
  m_positions_t0 = cloth.positions_t0;
  m_positions_t1 = cloth.positions_t1;
  m_triangles = cloth.triangles;
  return false;
}

Box3 particle_box(const Vec3& x_t0, const Vec3& x_t1, double margin) {
  Box3 box;
  box.extend(x_t0);
  box.extend(x_t1);
  box.grow(margin);
  return box;
}

Box3 triangle_box(const ClothMesh& cloth, const Triangle& t, double margin) {
  Box3 box;
  for (Index v : t) {
    box.extend(cloth.positions_t0[v]);
    box.extend(cloth.positions_t1[v]);
  }
  box.grow(margin);
  return box;
}

Box3 mesh_box(const ClothMesh& cloth) {
  Box3 box;
  for (const Vec3& x : cloth.positions_t0)
    box.extend(x);
  for (const Vec3& x : cloth.positions_t1)
    box.extend(x);
  return box;
}

bool any_particle_box_overlaps(const Vec3Array& particles_t0, const Vec3Array& particles_t1, double margin,
                               const Box3& box) {
  for (std::size_t p = 0; p < particles_t0.size(); ++p) {
    if (particle_box(particles_t0[p], particles_t1[p], margin).overlaps(box)) return true;
  }
  return false;
}

void collect_pairs(const Vec3Array& particles_t0, const Vec3Array& particles_t1, double margin,
                   const std::vector<std::uint8_t>* only, const std::vector<Box3>& triangle_boxes,
                   const std::function<void(const Box3& box, std::vector<Index>& candidates)>& propose,
                   std::vector<std::pair<Index, Index>>& pairs) {
  pairs.clear();
  const std::size_t n = particles_t0.size();
  // One list per chunk of particles, concatenated in chunk order: pairs come in particle order, whichever
  // thread took a chunk.
  constexpr std::size_t kChunk = 256;
  std::vector<std::vector<std::pair<Index, Index>>> found((n + kChunk - 1) / kChunk);
  parallel_for(n, kChunk, [&](std::size_t begin, std::size_t end) {
    std::vector<std::pair<Index, Index>>& mine = found[begin / kChunk];
    std::vector<Index> candidates;
    for (std::size_t p = begin; p < end; ++p) {
      if (only && !(*only)[p]) continue;
      const Box3 box = particle_box(particles_t0[p], particles_t1[p], 2.0 * margin);
      candidates.clear();
      propose(box, candidates);
      // The exact box test first, then the order and the duplicates of the few that pass: sorting every
      // proposal (a grid names a triangle once per cell it shares with the box) was most of the grid's
      // query time in issue 41's level and on bench_coupling's resting layer.
      candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                      [&](Index t) { return !box.overlaps(triangle_boxes[t]); }),
                       candidates.end());
      std::sort(candidates.begin(), candidates.end());
      candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
      for (Index t : candidates)
        mine.emplace_back(static_cast<Index>(p), t);
    }
  });
  std::size_t total = 0;
  for (const auto& part : found)
    total += part.size();
  pairs.reserve(total);
  for (const auto& part : found)
    pairs.insert(pairs.end(), part.begin(), part.end());
}

void find_pairs_brute_force(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                            const ClothMesh& cloth, double margin,
                            std::vector<std::pair<Index, Index>>& pairs) {
  pairs.clear();
  std::vector<Box3> boxes;
  for (const Triangle& t : cloth.triangles)
    boxes.push_back(triangle_box(cloth, t, 0.0));
  for (std::size_t p = 0; p < particles_t0.size(); ++p) {
    const Box3 box = particle_box(particles_t0[p], particles_t1[p], 2.0 * margin);
    for (std::size_t t = 0; t < boxes.size(); ++t) {
      if (box.overlaps(boxes[t])) pairs.emplace_back(static_cast<Index>(p), static_cast<Index>(t));
    }
  }
}

std::unique_ptr<TriangleBroadPhase> make_broad_phase_fcl();  // broad_phase_fcl.cpp

std::unique_ptr<TriangleBroadPhase> make_broad_phase(BroadPhaseKind kind) {
  if (kind == BroadPhaseKind::FCL) return make_broad_phase_fcl();
  return std::make_unique<GridBroadPhase>();
}

}  // namespace drench
