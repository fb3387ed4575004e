#pragma once
/// Fixed-radius neighbor search on a uniform grid of cells one support radius wide, with cells keyed by
/// z-order (Morton) codes so that sorting particles by key also sorts them along a space-filling curve.

#include <cstdint>

#include <drench/common/key_index_table.hpp>
#include <drench/common/types.hpp>

namespace drench {

/// Neighbors of N query points in compressed rows: the neighbors of point i are
/// indices[offsets[i] .. offsets[i + 1]), in a deterministic order (by cell, then by source index).
struct NeighborList {
  std::vector<std::uint32_t> offsets;  ///< N + 1
  IndexArray indices;                  ///< indices into the source point set

  std::size_t count(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
  const Index* begin(std::size_t i) const { return indices.data() + offsets[i]; }
  const Index* end(std::size_t i) const { return indices.data() + offsets[i + 1]; }
};

/// One number per entry of a NeighborList: the kernel gradient factor f of the pair (grad W = f (x_i - x_j),
/// unit: 1/m^5), in single precision. PCISPH's pressure loop streams the factors every iteration; as floats
/// the stream is a third smaller (with the indices), which makes the dam break's pressure phase faster
/// (bench_dam_break pcisph_59k) though the loop alone with a warm cache is not (bench_pair_loops
/// pressure_accelerations_float): the gain is the cache the other passes keep. The relative rounding, at
/// most 2^-24, is far below any solver tolerance, and f_ij = f_ji still holds exactly (the same squared
/// distance).
using GradientFactorArray = std::vector<float>;

/// The inner loop of NeighborSearch::find, which keeps the candidates within the radius of a query
/// (sph/candidate_scan.hpp).
enum class CandidateScan {
  kFourLanes = 0,       ///< four candidates at a time, GCC's vector extension: any CPU
  kAvx2Permute = 1,     ///< eight at a time, AVX2's lane permute and a table: CPUs with AVX2 (x86-64-v3)
  kAvx512Compress = 2,  ///< eight at a time, AVX-512's compress: CPUs with AVX-512 (x86-64-v4)
};

/// Uniform-grid neighbor search. `build` sorts the source points into cells; `find` answers, for every query
/// point, all source points at distance strictly less than the support radius. When the points' bounding box
/// holds few enough cells (at most 128 per point and 2^24 in all, or at most 4 per point plus 4,096), cells
/// live in a dense array filled by a counting sort; otherwise (a jet spread far) in rows along x found
/// through an open-addressing hash of their (y, z), so the domain is unbounded (up to 2^20 cells from the
/// origin on each axis; farther points are clamped into the outermost cells, which stays correct but slow).
/// Both layouts sort the points by row, then x, then index, so they give the same lists in the same order.
class NeighborSearch {
 public:
  /// @param support_radius  search radius and cell size (unit: m), > 0
  explicit NeighborSearch(Scalar support_radius);

  Scalar support_radius() const { return m_radius; }

  /// Sorts `points` (N, unit: m, finite) into cells. The points are copied; later calls to `find` use them.
  void build(const Vec3Array& points);

  /// For each query point, the source points within the support radius. Not to be called concurrently on one
  /// object (it reuses per-thread scratch buffers).
  /// @param queries  M points (unit: m, finite)
  /// @param exclude_self  skip source index i for query i (queries and sources are the same set)
  void find(const Vec3Array& queries, NeighborList& out, bool exclude_self) const;

  /// find(points, out, true) for the points of the last build: the same lists, found faster, since each
  /// point's cell is known and the points of a cell are taken together. Not to be called concurrently on one
  /// object.
  void find_self(NeighborList& out) const;

  /// find(points, out, false) for the points of `queries`' last build (its query i is its build's point i):
  /// the same lists, found faster, as find_self finds them (the queries' cells are known and sorted). The
  /// fluid's search of its boundary points each sub-step takes the fluid's grid so.
  /// @throws std::invalid_argument when `queries` has another support radius (its cells would differ)
  void find_for_points_of(const NeighborSearch& queries, NeighborList& out) const;

  /// Permutation that orders `points` along the z-order curve of their cells (ties by index): new position k
  /// holds old index order[k].
  IndexArray z_order(const Vec3Array& points) const;

  /// Morton key of the cell holding `x`.
  std::uint64_t cell_key(const Vec3& x) const;

  /// True when the last build kept its cells in the dense array, false when it hashed them (the tests check
  /// that each layout is exercised).
  bool dense() const { return m_dense; }

  /// The inner loop of find(): the fastest the CPU and the build allow by default. All give the same lists in
  /// the same order; tests and benchmarks pick each to compare them on one CPU.
  CandidateScan candidate_scan() const { return m_scan; }
  /// Picks find()'s inner loop; false (and no change) when the CPU or the build lacks it.
  bool set_candidate_scan(CandidateScan scan);
  /// True when the CPU and the build can run `scan`.
  static bool candidate_scan_available(CandidateScan scan);

 private:
  /// Where the candidates of a query lie in the sorted arrays (m_xs, ...): the runs [begin[r], end[r]),
  /// r < runs, in find()'s order (nine rows of three cells, in either layout; rows whose runs touch in the
  /// sorted arrays are joined into one run, so at most nine), `total` points in all.
  struct CandidateRuns {
    std::uint32_t begin[9];
    std::uint32_t end[9];
    int runs = 0;
    std::uint32_t total = 0;
  };

  /// out = the runs of sorted points in the 27 cells around `cell`, in find()'s order (empty runs left out).
  void candidate_runs(const Vec3i& cell, CandidateRuns& out) const;

  /// Hashed mode: the nine rows about a row of cells, each with a cursor at the first cell not left of the
  /// last query's x - 1.
  struct RowCursor {
    bool valid = false;
    int x = 0, y = 0, z = 0;  // the cell of the last query
    std::uint32_t
        first_row[3];       // per dz = -1, 0, 1: the first row (of m_row_keys) not before (z + dz, y - 1)
    std::uint32_t from[9];  // into m_cell_x (at most the row's end mark); 0, the lone end mark, for no row
  };
  /// Hashed mode: candidate_runs(cell, out) for cells taken in the sorted order, as find_self takes them,
  /// with `rows` kept from the previous cell.
  void rows_along(const Vec3i& cell, RowCursor& rows, CandidateRuns& out) const;
  /// find_self and find_for_points_of: the lists of the points of `queries`' last build (which may be this),
  /// taken in its sorted order; with exclude_self, query i skips source i.
  void find_sorted(const NeighborSearch& queries, bool exclude_self, NeighborList& out) const;
  std::uint64_t key_of_cell(const Vec3i& cell) const;
  Vec3i cell_of(const Vec3& x) const;
  /// Hashed mode: builds m_cells from m_row_keys unless it holds them (m_cells_indexed); not concurrently.
  void index_rows() const;
  /// Hashed mode only, after index_rows(): the sorted-point range of the cells x - 1 .. x + 1 of the row of
  /// `cell`; false when empty.
  bool hashed_row_range(const Vec3i& cell, std::uint32_t& begin, std::uint32_t& end) const;
  void build_dense(const std::vector<Vec3i>& cells, const Vec3i& lo, const Vec3i& dims);
  /// @param cells  the cell of every point (cell_of); lo, dims: their box of cells, as for build_dense
  void build_hashed(const std::vector<Vec3i>& cells, const Vec3i& lo, const Vec3i& dims);
  /// Appends to dst the original indices of the candidates of `runs` within the radius of x, but `self`, with
  /// the CPU's scan (m_scan); returns how many. dst has room for runs.total + kScanPadding.
  std::size_t scan(const CandidateRuns& runs, const Vec3& x, Index self, Index* dst) const;

  Scalar m_radius;
  Scalar m_inv_cell;
  // Source points in sorted (cell) order, one array per coordinate (the scans read runs of them in place),
  // and the original index of each.
  ScalarArray m_xs, m_ys, m_zs;
  IndexArray m_sorted_index;          // n entries, then kScanPadding
  std::vector<Vec3i> m_sorted_cells;  // n: the cell of each sorted point
  Vec3 m_reach_lo = Vec3::Zero();     // the finite points' box grown by two radii (unit: m)
  Vec3 m_reach_hi = Vec3::Zero();
  std::size_t m_count = 0;              // source points of the last build
  mutable KeyIndexTable m_cells;        // hashed mode: the distinct rows (z, y), ascending, and their table
  mutable bool m_cells_indexed = true;  // m_cells holds m_row_keys (index_rows)
  // Hashed mode: the same rows' keys, ascending (rows_along), then kRowKeyPadding keys of ~0, above all.
  std::vector<std::uint64_t> m_row_keys;
  // Dense mode: the first sorted point of each cell, one extra end entry. Hashed mode: one entry per entry of
  // m_cell_x, the first sorted point of its cell, or for an end mark the end of the cells before it.
  std::vector<std::uint32_t> m_cell_begin;
  std::vector<std::uint32_t> m_linear_scratch;  // build_dense: each point's cell, linearised
  std::vector<Vec3i> m_cells_scratch;           // build: each point's cell
  std::vector<std::uint64_t> m_keys_scratch;    // build_hashed: each point's key, then sorted
  std::vector<std::uint64_t> m_keys_to;         // build_hashed: the radix sort's scratch
  IndexArray m_values_to;
  // Hashed mode: an end mark (kRowEndX, above every cell's x), then per row the x of its distinct cells,
  // ascending, and an end mark; then kRowEndPadding end marks more, so that four entries from any end mark
  // can be read.
  std::vector<int> m_cell_x;
  // Hashed mode: per row, its first entry in m_cell_x; one extra entry, one past the last row's end mark (so
  // row r's end mark is at m_row_first[r + 1] - 1).
  std::vector<std::uint32_t> m_row_first;
  bool m_dense = false;
  CandidateScan m_scan = CandidateScan::kFourLanes;
  Vec3i m_lo = Vec3i::Zero();                        // dense mode: first cell of the grid
  Vec3i m_dims = Vec3i::Zero();                      // dense mode: cells per axis
  mutable std::vector<IndexArray> m_thread_buffers;  // find(): one result buffer per thread, kept for reuse
  mutable std::vector<int> m_query_owner;            // find_self(): the thread that listed each query
  mutable std::vector<std::size_t> m_query_start;    // find_self(): where in its buffer its list starts
};

}  // namespace drench
