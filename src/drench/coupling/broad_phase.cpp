#include <drench/coupling/broad_phase.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <drench/common/cell_lists.hpp>
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
/// the mean box stays within a factor 2 of it. One cell serves every size: a hierarchical grid (a level per
/// size class, each with a cell of its own) found fewer candidates, but its per-level tests and the small
/// faces' more frequent refiling cost more than that saved (bench_game_frame under callgrind), since a
/// candidate is a small part of a query's cost and the balls' and cloths' small faces already keep the mean
/// box near their size.
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
    if (!m_built_for.same_as_last(cloth, &m_moved)) update_bins(cloth);

    collect_pairs(
        particles_t0, particles_t1, margin, only,
        [&](const Box3& box, std::vector<Index>& hits) {
          const auto test = [&](Index t) {
            if (box.overlaps(m_boxes[t])) hits.push_back(t);
          };
          const CellRange range = cell_range(box);
          if (range.everywhere) {
            for (std::size_t t = 0; t < f; ++t)
              test(static_cast<Index>(t));
            return;
          }
          for (Index t : m_everywhere)
            test(t);
          for_cells(range, [&](std::uint64_t key) {
            if (const std::vector<Index>* list = m_lists.find(key)) {
              for (Index t : *list)
                test(t);
            }
          });
        },
        pairs);
  }

 private:
  /// The cells a box covers, [lo, hi] per axis, or `everywhere` when they are too many for the grid (or the
  /// box is not finite): for_cells' decision, kept per triangle to tell when it must be rebinned.
  struct CellRange {
    std::array<std::int64_t, 3> lo{}, hi{};
    bool everywhere = true;
    bool operator==(const CellRange& o) const {
      return everywhere == o.everywhere && (everywhere || (lo == o.lo && hi == o.hi));
    }
  };

  /// Cell k holds the coordinates c with k < c / cell <= k + 1, computed from c * (1 / cell) in integers:
  /// rounding keeps it monotonic in c, so boxes that overlap cover a common cell, which is all the grid needs
  /// (the cell size only decides speed). The division and std::floor per coordinate were a third of a query
  /// in issue 41's level. Cells closed at the top put a face that lies on a cell boundary, as a ground at
  /// y = 0 does, in the cell below the water resting on it, not in the water's own: 6% fewer query
  /// instructions there.
  CellRange cell_range(const Box3& box) const {
    CellRange r;
    // Written out per axis, with one test of all six ends and the cell count in doubles: the loops with a
    // test per axis and an overflow check per factor cost 125 instructions a box in issue 41's level, a
    // third of a particle's query and most of a moved face's upkeep.
    const double lx = box.lo.x() * m_inverse_cell, hx = box.hi.x() * m_inverse_cell;
    const double ly = box.lo.y() * m_inverse_cell, hy = box.hi.y() * m_inverse_cell;
    const double lz = box.lo.z() * m_inverse_cell, hz = box.hi.z() * m_inverse_cell;
    constexpr double kMax = kMaxCellCoordinate;
    // Also false for a NaN or an infinite end: such a box is tested against every triangle.
    if (!(lx >= -kMax && lx <= hx && hx <= kMax && ly >= -kMax && ly <= hy && hy <= kMax && lz >= -kMax &&
          lz <= hz && hz <= kMax)) {
      return r;
    }
    r.lo = {cell_of(lx), cell_of(ly), cell_of(lz)};
    r.hi = {cell_of(hx), cell_of(hy), cell_of(hz)};
    // Each factor is an integer below 2^42, exact in a double, and so is a product up to 4096; a larger
    // product rounds to no less than 4097, so the comparison is that of the integers.
    const double cells = static_cast<double>(r.hi[0] - r.lo[0] + 1) *
                         static_cast<double>(r.hi[1] - r.lo[1] + 1) *
                         static_cast<double>(r.hi[2] - r.lo[2] + 1);
    r.everywhere = !(cells <= static_cast<double>(kMaxCellsPerBox));
    return r;
  }

  /// The cell k with k < c <= k + 1, for |c| <= kMaxCellCoordinate: ceil(c) - 1.
  static std::int64_t cell_of(double c) {
    const auto i = static_cast<std::int64_t>(c);  // towards zero
    return static_cast<double>(i) < c ? i : i - 1;
  }

  /// Brings the bins to `cloth`'s triangle boxes. A triangle is rebinned when its box covers other cells than
  /// those it was binned in (a box with a NaN is filed for every query), so the bins are those a fresh
  /// binning with the same cell size would make; every box is updated for the exact test.
  void update_bins(const ClothMesh& cloth) {
    const std::size_t f = cloth.triangles.size();
    // Only the faces with a moved node (m_moved, from m_built_for) get new boxes: in a game's level most
    // never move (the ground's square, a table), and their boxes, extents and cells were most of this update
    // (issue 41's profile). The extents are summed in face order as before, so the cell is the same bits.
    const bool all_faces = m_boxes.size() != f || m_extents.size() != f || m_ranges.size() != f;
    m_boxes.resize(f);
    m_extents.resize(f);
    m_face_moved.assign(f, 0);
    // Each moved node's box over the step once, and a face's box as the union of its nodes' boxes: a node
    // is in about six faces, and the six-point box of every moved face was most of this update (issue 41).
    // The same box as triangle_box(cloth, t, 0): min and max do not round, and both drop a NaN coordinate.
    const std::size_t m = cloth.positions_t0.size();
    m_node_boxes.resize(m);
    for (std::size_t v = 0; v < m; ++v) {
      if (!all_faces && !m_moved[v]) continue;
      Box3 box;
      box.extend(cloth.positions_t0[v]);
      box.extend(cloth.positions_t1[v]);
      m_node_boxes[v] = box;
    }
    double extent_sum = 0.0;
    for (std::size_t t = 0; t < f; ++t) {
      const Triangle& tri = cloth.triangles[t];
      if (all_faces || m_moved[tri[0]] || m_moved[tri[1]] || m_moved[tri[2]]) {
        m_face_moved[t] = 1;
        const Box3& a = m_node_boxes[tri[0]];
        const Box3& b = m_node_boxes[tri[1]];
        const Box3& c = m_node_boxes[tri[2]];
        Box3& box = m_boxes[t];
        box.lo = a.lo.cwiseMin(b.lo).cwiseMin(c.lo);
        box.hi = a.hi.cwiseMax(b.hi).cwiseMax(c.hi);
        m_extents[t] = (box.hi - box.lo).maxCoeff();
      }
      extent_sum += m_extents[t];
    }
    const double cell = std::max(extent_sum / static_cast<double>(f), 1e-9);
    const bool rebin_all = m_ranges.size() != f || !(cell <= 2.0 * m_cell && cell >= 0.5 * m_cell);
    if (rebin_all) {
      m_cell = cell;
      m_inverse_cell = 1.0 / cell;
      m_lists.clear();
      m_everywhere.clear();
      m_ranges.resize(f);
      for (std::size_t t = 0; t < f; ++t) {
        m_ranges[t] = cell_range(m_boxes[t]);
        file(static_cast<Index>(t), m_ranges[t]);
      }
      return;
    }
    // A triangle that now covers other cells leaves the lists of its old cells and joins those of its new
    // ones: the cost follows the few that change cells, where sorting and indexing every entry again whenever
    // one changed was most of the update in issue 41's level.
    for (std::size_t t = 0; t < f; ++t) {
      // A face that did not move keeps its box, and with the same cell its cells.
      if (!m_face_moved[t]) continue;
      const CellRange range = cell_range(m_boxes[t]);
      if (range == m_ranges[t]) continue;
      refile(static_cast<Index>(t), m_ranges[t], range);
      m_ranges[t] = range;
    }
  }

  /// Moves triangle t from the cells of `from` to those of `to`. Only the cells in one range and not the
  /// other are touched: a box that slides into the next cells keeps most of its cells (half of them for a
  /// box over 2 x 2 x 2 cells moving by one along an axis), and each cell touched costs a key lookup.
  void refile(Index t, const CellRange& from, const CellRange& to) {
    if (from.everywhere || to.everywhere) {
      unfile(t, from);
      file(t, to);
      return;
    }
    for_cells_outside(from, to, [&](std::uint64_t key) { m_lists.remove(key, t); });
    for_cells_outside(to, from, [&](std::uint64_t key) { m_lists.add(key, t); });
  }

  /// Adds triangle t to the lists of the cells of `range`, or to m_everywhere when they are too many.
  void file(Index t, const CellRange& range) {
    if (!for_cells(range, [&](std::uint64_t key) { m_lists.add(key, t); })) m_everywhere.push_back(t);
  }

  /// Takes triangle t out of the lists file(t, range) put it in.
  void unfile(Index t, const CellRange& range) {
    if (!for_cells(range, [&](std::uint64_t key) { m_lists.remove(key, t); }))
      m_everywhere.erase(std::find(m_everywhere.begin(), m_everywhere.end(), t));
  }

  /// Visits the keys of the cells the box covers; returns false, visiting nothing, when they are too many (a
  /// particle flying across the domain in one step), and the caller tests every triangle instead.
  template <class Visit>
  static bool for_cells(const CellRange& range, Visit&& visit) {
    if (range.everywhere) return false;
    for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z) {
      for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y) {
        for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x)
          visit(key(x, y, z));
      }
    }
    return true;
  }

  /// Visits the keys of the cells of `range` that `other` does not cover. Precondition: neither is
  /// `everywhere`.
  template <class Visit>
  static void for_cells_outside(const CellRange& range, const CellRange& other, Visit&& visit) {
    const auto inside = [&](std::int64_t c, int axis) { return c >= other.lo[axis] && c <= other.hi[axis]; };
    for (std::int64_t z = range.lo[2]; z <= range.hi[2]; ++z) {
      const bool z_inside = inside(z, 2);
      for (std::int64_t y = range.lo[1]; y <= range.hi[1]; ++y) {
        const bool yz_inside = z_inside && inside(y, 1);
        for (std::int64_t x = range.lo[0]; x <= range.hi[0]; ++x) {
          if (!(yz_inside && inside(x, 0))) visit(key(x, y, z));
        }
      }
    }
  }

  static constexpr std::int64_t kMaxCellsPerBox = 4096;
  // Cell coordinates stay well inside std::int64_t and exact in a double.
  static constexpr double kMaxCellCoordinate = 1e12;

  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto i = static_cast<std::uint64_t>(x);
    const auto j = static_cast<std::uint64_t>(y);
    const auto k = static_cast<std::uint64_t>(z);
    return (i * 73856093ULL) ^ (j * 19349663ULL) ^ (k * 83492791ULL);
  }

  double m_cell = 1.0;
  double m_inverse_cell = 1.0;             // 1 / m_cell (unit: 1/m)
  std::vector<Box3> m_boxes;               // F, each triangle's current box (the exact test's)
  std::vector<Box3> m_node_boxes;          // M, each node's box over the step (moved nodes' updated)
  std::vector<CellRange> m_ranges;         // F, the cells each triangle is binned in
  std::vector<double> m_extents;           // F, each triangle's box's largest extent (unit: m)
  std::vector<std::uint8_t> m_moved;       // M, the nodes that moved since the last update (m_built_for)
  std::vector<std::uint8_t> m_face_moved;  // F, the triangles with such a node
  // The triangles of each cell key, in any order: collect_pairs sorts each particle's hits.
  CellLists<Index, CellListOrder::ANY> m_lists;
  std::vector<Index> m_everywhere;  // the triangles over kMaxCellsPerBox cells, in no order
  TriangleBoxKey m_built_for;
};

}  // namespace

namespace {

/// a == b for every element, as std::vector's ==, or the same bytes: bytes that are the same give the same
/// boxes bit for bit, so a NaN that is still there need not be seen as a change. One comparison of the
/// bytes first: the element loop was most of a query that found the cloth unchanged (every sub-step's
/// obstacle, every CCD round).
bool same_positions(const Vec3Array& a, const Vec3Array& b) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "a position is three doubles");
  if (a.size() != b.size()) return false;
  if (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0) return true;
  bool same = true;
  for (std::size_t i = 0; i < a.size() && same; ++i)
    same = a[i].x() == b[i].x() && a[i].y() == b[i].y() && a[i].z() == b[i].z();
  return same;
}

}  // namespace

bool TriangleBoxKey::same_as_last(const ClothMesh& cloth, std::vector<std::uint8_t>* moved) {
  const bool same_triangles_as_last = m_valid && same_triangles(cloth.triangles, m_triangles);
  if (same_triangles_as_last && same_positions(cloth.positions_t0, m_positions_t0) &&
      same_positions(cloth.positions_t1, m_positions_t1)) {
    return true;
  }
  const std::size_t m = cloth.positions_t0.size();
  const bool comparable = same_triangles_as_last && m_positions_t0.size() == m &&
                          m_positions_t1.size() == m && cloth.positions_t1.size() == m;
  if (moved) moved->assign(m, comparable ? 0 : 1);
  if (comparable) {
    // As the comparison above: a NaN differs from itself, so a node with one counts as moved. Only the
    // moved nodes are copied: a CCD round moves a few of thousands, and copying both position sets and the
    // triangles at every change was a third of this call.
    const auto differs = [](const Vec3& a, const Vec3& b) {
      return !(a.x() == b.x() && a.y() == b.y() && a.z() == b.z());
    };
    // Blocks of nodes whose bytes are the same at both ends are passed over in two memcmp calls: a CCD round
    // moves a few nodes of thousands, and comparing every node's six coordinates was most of this call. A
    // node with a NaN in such a block is then not marked moved; its bytes, and so its boxes, are the same.
    constexpr std::size_t kBlock = 16;
    for (std::size_t begin = 0; begin < m; begin += kBlock) {
      const std::size_t end = std::min(begin + kBlock, m);
      const std::size_t bytes = (end - begin) * sizeof(Vec3);
      if (std::memcmp(&cloth.positions_t0[begin], &m_positions_t0[begin], bytes) == 0 &&
          std::memcmp(&cloth.positions_t1[begin], &m_positions_t1[begin], bytes) == 0) {
        continue;
      }
      for (std::size_t i = begin; i < end; ++i) {
        const bool moved_t0 = differs(cloth.positions_t0[i], m_positions_t0[i]);
        const bool moved_t1 = differs(cloth.positions_t1[i], m_positions_t1[i]);
        if (moved_t0) m_positions_t0[i] = cloth.positions_t0[i];
        if (moved_t1) m_positions_t1[i] = cloth.positions_t1[i];
        if (moved) (*moved)[i] = static_cast<std::uint8_t>(moved_t0 || moved_t1);
      }
    }
  } else {
    m_positions_t0 = cloth.positions_t0;
    m_positions_t1 = cloth.positions_t1;
    m_triangles = cloth.triangles;
  }
  m_valid = true;
  return false;
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
