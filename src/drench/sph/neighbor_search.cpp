#include <drench/sph/neighbor_search.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <drench/common/parallel.hpp>
#include <drench/sph/candidate_scan.hpp>

namespace drench {

namespace {

constexpr int kCellBits = 21;
constexpr std::int64_t kCellOffset = std::int64_t{1} << (kCellBits - 1);
constexpr std::int64_t kCellMax = (std::int64_t{1} << kCellBits) - 1;
constexpr Index kNoIndex = std::numeric_limits<Index>::max();
/// The hashed layout's end mark of a row in m_cell_x: above every cell's x (at most kCellMax), so the walks
/// along a row stop at it with no test of the row's end.
constexpr int kRowEndX = std::numeric_limits<int>::max();
/// End marks after the last row's: rows_along reads four entries from any cursor, which stops at an end mark.
constexpr std::size_t kRowEndPadding = 3;
/// Keys of ~0 (above every row's) after the hashed layout's row keys: rows_along compares four keys from a
/// cursor that stops at the first of them.
constexpr std::size_t kRowKeyPadding = 4;
constexpr std::uint32_t kNoRunEnd = std::numeric_limits<std::uint32_t>::max();

/// Spreads the low 21 bits of v so that bit k moves to bit 3k.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | (v << 32)) & 0x1f00000000ffffULL;
  v = (v | (v << 16)) & 0x1f0000ff0000ffULL;
  v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
  v = (v | (v << 2)) & 0x1249249249249249ULL;
  return v;
}

/// The key of the row of cells (y, z) along x, in the hashed layout: ordered by z, then y.
std::uint64_t row_key(int y, int z) {
  return (static_cast<std::uint64_t>(z) << kCellBits) | static_cast<std::uint64_t>(y);
}

/// Sorts `values` by `keys` (both n long, moved together), stably: a least-significant-digit radix sort of
/// the keys' low bits up to max_key's highest, in passes of at most 11 bits, through keys_to and values_to
/// (scratch kept by the caller: allocated and zero-filled per call, they were a tenth of the hashed build).
/// The grid's cells are sorted so every PBF sub-step; std::sort of (key, index) pairs was a quarter of the
/// build there (callgrind, issue 41's level), for keys of about 20 bits that two or three counting passes
/// sort.
void radix_sort_by_key(std::vector<std::uint64_t>& keys, IndexArray& values, std::uint64_t max_key,
                       std::vector<std::uint64_t>& keys_to, IndexArray& values_to) {
  const int bits = max_key == 0 ? 0 : 64 - __builtin_clzll(max_key);
  if (bits == 0) return;
  const int passes = (bits + 10) / 11;
  const int digit_bits = (bits + passes - 1) / passes;
  const std::uint64_t mask = (std::uint64_t{1} << digit_bits) - 1;
  const std::size_t n = keys.size();
  // Every entry is written by each pass before it is read: no need to clear what the last call left.
  keys_to.resize(n);
  values_to.resize(n);
  std::uint32_t start[(std::size_t{1} << 11) + 1];
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * digit_bits;
    std::fill(start, start + mask + 2, 0u);
    for (std::size_t k = 0; k < n; ++k)
      ++start[static_cast<std::size_t>((keys[k] >> shift) & mask) + 1];
    for (std::size_t d = 0; d <= mask; ++d)
      start[d + 1] += start[d];
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t slot = start[static_cast<std::size_t>((keys[k] >> shift) & mask)]++;
      keys_to[slot] = keys[k];
      values_to[slot] = values[k];
    }
    keys.swap(keys_to);
    values.swap(values_to);
  }
}

/// Gathers runs [b, e) (b <= e) of sorted points into a NeighborSearch::CandidateRuns, at most nine: each
/// joined to the last when it starts where that one ends, left out when empty. A joined run is read by the
/// scan in the same order as its parts; sparse water's rows hold a cell or two, so the runs of neighbouring
/// rows often touch, and the scans take at least a group of eight per run: joined, the PBF level's searches
/// scan fewer, fuller groups. With no branch: whether a row about a cell of sparse water is empty, or
/// touches the last, is a coin toss (with branches, the dense layout's candidate_runs mispredicted 1.6M
/// times in 0.9M calls in issue 41's level, 0.2M without; callgrind --branch-sim). What is not taken is
/// written past the last run. The counts are kept here, where they need not be read back after each store to
/// the arrays, and written by finish().
template <class Runs>
class RunAppender {
 public:
  explicit RunAppender(Runs& runs) : m_runs(runs) {}

  void add(std::uint32_t b, std::uint32_t e) {
    const int join = b == m_last_end ? 1 : 0;
    const int taken = b != e ? 1 : 0;
    m_runs.begin[m_count] = b;
    m_runs.end[m_count - join] = e;  // a join's run, or the new one (an empty one joins only where it ends)
    m_count += taken & (1 - join);
    // taken ? e : m_last_end, by a mask: as a conditional, GCC made it a branch in the unrolled rows_along.
    const std::uint32_t take = 0u - static_cast<std::uint32_t>(taken);
    m_last_end = (e & take) | (m_last_end & ~take);
    m_total += e - b;
  }

  void finish() const {
    m_runs.runs = m_count;
    m_runs.total = m_total;
  }

 private:
  Runs& m_runs;
  int m_count = 0;
  std::uint32_t m_total = 0;
  std::uint32_t m_last_end = kNoRunEnd;  // the last non-empty run's end
};

/// scan_runs with scan_candidates_lanes, compiled for each copy of DRENCH_SIMD_CLONES: the CPUs without AVX2.
DRENCH_SIMD_CLONES std::size_t scan_runs_lanes(const Scalar* xs, const Scalar* ys, const Scalar* zs,
                                               const Index* indices, const std::uint32_t* begins,
                                               const std::uint32_t* ends, int runs, const Vec3& x, Scalar r2,
                                               Index self, Index* dst) {
  return scan_runs<scan_candidates_lanes>(xs, ys, zs, indices, begins, ends, runs, x, r2, self, dst);
}

/// The scan over runs of `scan` (NeighborSearch::set_candidate_scan), all of one signature: find_sorted picks
/// it once per search rather than through scan()'s switch per query, a call of 30 instructions a query in
/// issue 41's level (callgrind).
using ScanRunsFunction = std::size_t (*)(const Scalar*, const Scalar*, const Scalar*, const Index*,
                                         const std::uint32_t*, const std::uint32_t*, int, const Vec3&, Scalar,
                                         Index, Index*);
ScanRunsFunction scan_runs_for(CandidateScan scan) {
  switch (scan) {
#if DRENCH_HAS_AVX512_SCAN
    case CandidateScan::kAvx512Compress:
      return scan_runs_compress;
#endif
#if DRENCH_HAS_AVX2_SCAN
    case CandidateScan::kAvx2Permute:
      return scan_runs_permute;
#endif
    default:
      return scan_runs_lanes;
  }
}

}  // namespace

NeighborSearch::NeighborSearch(Scalar support_radius)
    : m_radius(support_radius), m_inv_cell(1.0 / support_radius) {
  assert(support_radius > 0.0);
  for (const CandidateScan fastest :
       {CandidateScan::kAvx512Compress, CandidateScan::kAvx2Permute, CandidateScan::kFourLanes}) {
    if (set_candidate_scan(fastest)) break;
  }
}

bool NeighborSearch::candidate_scan_available(CandidateScan scan) {
  switch (scan) {
    case CandidateScan::kAvx512Compress:
      return DRENCH_HAS_AVX512_SCAN && avx512_copy();
    case CandidateScan::kAvx2Permute:
      // The AVX2 scan also uses BMI2's bzhi; every x86-64-v3 CPU has both.
      return DRENCH_HAS_AVX2_SCAN && (avx2_copy() || avx512_copy());
    case CandidateScan::kFourLanes:
      return true;
  }
  return false;
}

bool NeighborSearch::set_candidate_scan(CandidateScan scan) {
  if (!candidate_scan_available(scan)) return false;
  m_scan = scan;
  return true;
}

// Inlined into the loops that take it per point (build, find): as a call, with its cell returned through
// memory, a third of the build's pass of cells went to the call (callgrind, issue 41's level, whose bodies'
// 12,000 boundary points are built into a grid every frame).
__attribute__((always_inline)) inline Vec3i NeighborSearch::cell_of(const Vec3& x) const {
  // floor(x / cell) + kCellOffset, clamped to [1, kCellMax - 1]. Clamped before converting (a cast of an
  // out-of-range double to int is undefined behaviour), and before flooring, which keeps the integer bounds,
  // so the cells are the same; then floored by truncation and a correction for negative values: std::floor
  // was a libm call per axis in the baseline build, and made this 100 instructions per point, 2% of issue
  // 41's level (callgrind), most of it the grid's build every sub-step. The clamp is the CPU's max and min
  // (maxpd and maxsd give the second operand when unordered), so NaN takes the lowest bound and the lowest
  // cell with no branch of its own; the solver reports non-finite particles itself.
  constexpr Scalar kLowest = static_cast<Scalar>(1 - kCellOffset);
  constexpr Scalar kHighest = static_cast<Scalar>(kCellMax - 1 - kCellOffset);
#if defined(__SSE2__)
  // x and y in one SSE2 vector, z in another: the same products, clamps, truncations and corrections as the
  // scalar code below, lane by lane, without its branches (60 instructions per point in the scalar code, a
  // third of the neighbour search's build in issue 41's level; callgrind).
  const __m128d inv = _mm_set1_pd(m_inv_cell);
  const __m128d lowest = _mm_set1_pd(kLowest), highest = _mm_set1_pd(kHighest);
  const __m128i offset = _mm_set1_epi32(static_cast<int>(kCellOffset));
  const auto cells = [&](__m128d v) {
    const __m128d c = _mm_min_pd(_mm_max_pd(_mm_mul_pd(v, inv), lowest), highest);
    const __m128i truncated = _mm_cvttpd_epi32(c);  // two int32 lanes, then zeros
    // All ones (-1) in a lane whose truncation rounded up (c negative and not whole): the floor is one less.
    const __m128i below = _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmplt_pd(c, _mm_cvtepi32_pd(truncated))),
                                            _MM_SHUFFLE(2, 0, 2, 0));
    return _mm_add_epi32(_mm_add_epi32(truncated, below), offset);
  };
  const __m128i xy = cells(_mm_loadu_pd(x.data()));
  const __m128i z = cells(_mm_load_sd(x.data() + 2));
  return Vec3i(_mm_cvtsi128_si32(xy), _mm_cvtsi128_si32(_mm_srli_si128(xy, 4)), _mm_cvtsi128_si32(z));
#else
  Vec3i cell;
  for (int a = 0; a < 3; ++a) {
    const Scalar v = x[a] * m_inv_cell;
    const Scalar above_lowest = v > kLowest ? v : kLowest;  // NaN: kLowest
    const Scalar c = above_lowest < kHighest ? above_lowest : kHighest;
    const int truncated = static_cast<int>(c);
    cell[a] = truncated - (c < static_cast<Scalar>(truncated) ? 1 : 0) + static_cast<int>(kCellOffset);
  }
  return cell;
#endif
}

std::uint64_t NeighborSearch::key_of_cell(const Vec3i& cell) const {
  return spread_bits(static_cast<std::uint64_t>(cell.x())) |
         (spread_bits(static_cast<std::uint64_t>(cell.y())) << 1) |
         (spread_bits(static_cast<std::uint64_t>(cell.z())) << 2);
}

std::uint64_t NeighborSearch::cell_key(const Vec3& x) const {
  return key_of_cell(cell_of(x));
}

IndexArray NeighborSearch::z_order(const Vec3Array& points) const {
  const std::size_t n = points.size();
  std::vector<std::pair<std::uint64_t, Index>> keyed(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      keyed[i] = {cell_key(points[i]), static_cast<Index>(i)};
  });
  std::sort(keyed.begin(), keyed.end());
  IndexArray order(n);
  for (std::size_t k = 0; k < n; ++k)
    order[k] = keyed[k].second;
  return order;
}

void NeighborSearch::build(const Vec3Array& points) {
  const std::size_t n = points.size();
  // Kept from build to build: a new array was zero-filled first.
  std::vector<Vec3i>& cells = m_cells_scratch;
  cells.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      cells[i] = cell_of(points[i]);
  });
  Vec3i lo = Vec3i::Constant(std::numeric_limits<int>::max());
  Vec3i hi = Vec3i::Constant(std::numeric_limits<int>::min());
  for (const Vec3i& c : cells) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const Vec3i dims = n > 0 ? Vec3i(hi - lo + Vec3i::Ones()) : Vec3i::Zero();
  const double cell_count = static_cast<double>(dims.x()) * dims.y() * dims.z();
  // Dense while it costs at most 128 cells (512 bytes of cell starts, one counting-sort pass) per point, up
  // to 2^24 cells (64 MB), or 4 per point (plus 4,096) whatever their number: a query run then reads nine
  // row ranges where the hash takes 27 lookups. The 128 is for a jet on a cloth (15K particles spread over up
  // to 71 cells each), whose neighbor phase is faster with it than with 4 per point alone, frames identical
  // (bench_jet_on_cloth).
  const double point_count = static_cast<double>(n);
  m_dense = n > 0 &&
            (cell_count <= 4.0 * point_count + 4096.0 || cell_count <= std::min(128.0 * point_count, 0x1p24));
  if (m_dense) {
    build_dense(cells, lo, dims);
    m_cells_indexed = true;  // build_dense empties the table, as the dense layout wants
  } else {
    build_hashed(cells, lo, dims);
  }
  m_count = n;
  // Where a query can have neighbors: within the radius of the finite points' box (a NaN point is nobody's
  // neighbor). Two radii, so that no rounding of the bound can reject a query with a neighbor.
  Vec3 box_lo = Vec3::Constant(std::numeric_limits<Scalar>::infinity());
  Vec3 box_hi = -box_lo;
  for (const Vec3& x : points) {
    if (!x.allFinite()) continue;
    box_lo = box_lo.cwiseMin(x);
    box_hi = box_hi.cwiseMax(x);
  }
  m_reach_lo = box_lo.array() - 2.0 * m_radius;
  m_reach_hi = box_hi.array() + 2.0 * m_radius;
  // kScanPadding entries after the last point: the scans read runs of cells in place, whole groups.
  m_sorted_index.resize(n + kScanPadding, 0);
  m_xs.resize(n + kScanPadding);
  m_ys.resize(n + kScanPadding);
  m_zs.resize(n + kScanPadding);
  // Each sorted point's cell, for find_self, which takes the queries in this order, and its coordinates: one
  // pass over the sorted order, not two.
  m_sorted_cells.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const Index i = m_sorted_index[k];
      m_sorted_cells[k] = cells[i];
      const Vec3& x = points[i];
      m_xs[k] = x.x();
      m_ys[k] = x.y();
      m_zs[k] = x.z();
    }
  });
}

void NeighborSearch::build_dense(const std::vector<Vec3i>& cells, const Vec3i& lo, const Vec3i& dims) {
  m_lo = lo;
  m_dims = dims;
  const std::size_t n = cells.size();
  const std::size_t cell_count = static_cast<std::size_t>(dims.x()) * dims.y() * dims.z();
  // Counting sort by cell, stable in the point index, so the order is deterministic. Each point's cell is
  // linearised once, and the points are placed from the last one at the end of its cell, each cell's entry
  // counting down to its first point: no second array of cursors over every cell (the grid can hold 128
  // cells per point).
  std::vector<std::uint32_t>& linear = m_linear_scratch;
  linear.resize(n);
  m_cell_begin.assign(cell_count + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3i& c = cells[i];
    const std::size_t l =
        (static_cast<std::size_t>(c.z() - lo.z()) * dims.y() + (c.y() - lo.y())) * dims.x() +
        (c.x() - lo.x());
    linear[i] = static_cast<std::uint32_t>(l);
    ++m_cell_begin[l];
  }
  std::uint32_t sum = 0;
  for (std::size_t c = 0; c < cell_count; ++c) {
    sum += m_cell_begin[c];
    m_cell_begin[c] = sum;
  }
  m_cell_begin[cell_count] = static_cast<std::uint32_t>(n);
  m_sorted_index.resize(n);
  for (std::size_t i = n; i-- > 0;)
    m_sorted_index[--m_cell_begin[linear[i]]] = static_cast<Index>(i);
  m_cells.clear();
  m_row_keys.clear();
}

void NeighborSearch::build_hashed(const std::vector<Vec3i>& cells, const Vec3i& lo, const Vec3i& dims) {
  // Sorted by row (z, then y), then x, then index, as the dense grid's linear index sorts them: the three
  // cells x - 1 .. x + 1 of a row are then one run of sorted points, and a query looks up the nine rows about
  // its cell, not 27 cells. The hashed grid held sparse water (a jet, spray, a film on the ground) at 1.5
  // points per cell in issue 41's level, where the 27 lookups per cell were most of the search. The key is
  // the cell's linear index in the points' box of cells (below 2^63: 2^21 cells per axis), which orders the
  // cells so.
  const std::size_t n = cells.size();
  std::vector<std::uint64_t>& keys = m_keys_scratch;
  keys.resize(n);
  m_sorted_index.resize(n);
  const auto dx = static_cast<std::uint64_t>(dims.x()), dy = static_cast<std::uint64_t>(dims.y());
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3i& c = cells[i];
    keys[i] =
        (static_cast<std::uint64_t>(c.z() - lo.z()) * dy + static_cast<std::uint64_t>(c.y() - lo.y())) * dx +
        static_cast<std::uint64_t>(c.x() - lo.x());
    m_sorted_index[i] = static_cast<Index>(i);
  }
  radix_sort_by_key(keys, m_sorted_index, dx * dy * static_cast<std::uint64_t>(dims.z()) - 1, m_keys_to,
                    m_values_to);
  // At most n cells and rows, and an end mark per row: written by index into arrays of that size, then cut
  // to their counts (a call of push_back per cell, not inlined, was an eighth of this function; callgrind,
  // issue 41's level). Every point writes its entries and advances past those that are new, with no branch:
  // at 1.5 points per cell whether a point starts a cell is a coin toss. What is not taken lands on the next
  // free entry, which a later write or the end mark overwrites.
  const std::size_t entries = 1 + 2 * n + kRowEndPadding;
  m_cell_begin.resize(entries);
  m_cell_x.resize(entries);
  m_row_first.resize(n + 1);
  m_row_keys.resize(n + kRowKeyPadding);
  m_cell_x[0] = kRowEndX;  // the cursor of a missing row (rows_along)
  m_cell_begin[0] = 0;
  std::size_t entry = 1, row_count = 0;
  std::uint64_t last_key = ~std::uint64_t{0}, last_row = ~std::uint64_t{0};  // above every key and row
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3i& c = cells[m_sorted_index[k]];
    const std::uint64_t row = row_key(c.y(), c.z());
    const std::size_t new_cell = keys[k] != last_key ? 1 : 0;
    const std::size_t new_row = row != last_row ? 1 : 0;  // a new row is a new cell
    const auto first_point = static_cast<std::uint32_t>(k);
    m_cell_x[entry] = kRowEndX;  // the last row's end mark, when this point starts another row
    m_cell_begin[entry] = first_point;
    entry += new_row & (row_count > 0 ? 1 : 0);
    m_row_keys[row_count] = row;
    m_row_first[row_count] = static_cast<std::uint32_t>(entry);
    row_count += new_row;
    m_cell_x[entry] = c.x();
    m_cell_begin[entry] = first_point;
    entry += new_cell;
    last_key = keys[k];
    last_row = row;
  }
  if (row_count > 0) {
    m_cell_x[entry] = kRowEndX;
    m_cell_begin[entry] = static_cast<std::uint32_t>(n);
    ++entry;
  }
  m_row_first[row_count] = static_cast<std::uint32_t>(entry);
  for (std::size_t p = 0; p < kRowEndPadding; ++p) {
    m_cell_x[entry + p] = kRowEndX;
    m_cell_begin[entry + p] = static_cast<std::uint32_t>(n);
  }
  m_cell_begin.resize(entry + kRowEndPadding);
  m_cell_x.resize(entry + kRowEndPadding);
  m_row_first.resize(row_count + 1);
  std::fill(m_row_keys.begin() + static_cast<std::ptrdiff_t>(row_count),
            m_row_keys.begin() + static_cast<std::ptrdiff_t>(row_count + kRowKeyPadding), ~std::uint64_t{0});
  m_row_keys.resize(row_count + kRowKeyPadding);
  // The table of rows is built when find() first needs it (hashed_row_range): find_self and
  // find_for_points_of walk m_row_keys in order instead, and the fluid's grid, hashed and rebuilt every PBF
  // sub-step, is searched only so.
  m_cells_indexed = false;
}

void NeighborSearch::index_rows() const {
  if (m_cells_indexed) return;
  // The rows' keys without their padding (build() leaves the dense layout indexed, with no keys).
  m_cells.build(std::vector<std::uint64_t>(m_row_keys.begin(),
                                           m_row_keys.end() - static_cast<std::ptrdiff_t>(kRowKeyPadding)));
  m_cells_indexed = true;
}

bool NeighborSearch::hashed_row_range(const Vec3i& cell, std::uint32_t& begin, std::uint32_t& end) const {
  const std::int64_t row = m_cells.find(row_key(cell.y(), cell.z()));
  if (row < 0) return false;
  const int* first = m_cell_x.data() + m_row_first[static_cast<std::size_t>(row)];
  const int* last = m_cell_x.data() + m_row_first[static_cast<std::size_t>(row) + 1] - 1;  // its end mark
  const int* from = std::lower_bound(first, last, cell.x() - 1);
  const int* to = from;
  while (to != last && *to <= cell.x() + 1)
    ++to;
  if (from == to) return false;
  begin = m_cell_begin[static_cast<std::size_t>(from - m_cell_x.data())];
  end = m_cell_begin[static_cast<std::size_t>(to - m_cell_x.data())];
  return true;
}

void NeighborSearch::candidate_runs(const Vec3i& cell, CandidateRuns& out) const {
  out.runs = 0;
  out.total = 0;
  if (m_dense) {
    // A query more than a cell off the grid (the fluid's particles far from a body's boundary points) has no
    // candidates: said at once, not by nine empty rows.
    const Vec3i local = cell - m_lo;
    if ((local.array() < -1).any() || (local.array() > m_dims.array()).any()) return;
    // row_range's runs, with the x range clipped once for the nine rows: nine calls of it were 700
    // instructions per query, most of the boundary's search each PBF sub-step in issue 41's level.
    const int x_first = std::max(local.x() - 1, 0);
    const int x_last = std::min(local.x() + 1, m_dims.x() - 1);
    if (x_first > x_last) return;
    RunAppender<CandidateRuns> append(out);
    // Unrolled, as rows_along's loops are; over dz and dy, since GCC unrolled no loop bounded by the cell.
#pragma GCC unroll 3
    for (int dz = -1; dz <= 1; ++dz) {
      const int z = local.z() + dz;
      if (z < 0 || z >= m_dims.z()) continue;
#pragma GCC unroll 3
      for (int dy = -1; dy <= 1; ++dy) {
        const int y = local.y() + dy;
        if (y < 0 || y >= m_dims.y()) continue;
        const std::size_t row = (static_cast<std::size_t>(z) * m_dims.y() + y) * m_dims.x();
        append.add(m_cell_begin[row + x_first], m_cell_begin[row + x_last + 1]);
      }
    }
    append.finish();
    return;
  }
  // Nine rows of three cells along x, in the order z, y: each row one run in either layout (the dense one's
  // above).
  RunAppender<CandidateRuns> append(out);
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      std::uint32_t b, e;
      const bool found = hashed_row_range(cell + Vec3i(0, dy, dz), b, e);
      if (!found) continue;
      append.add(b, e);
    }
  }
  append.finish();
}

void NeighborSearch::rows_along(const Vec3i& cell, RowCursor& rows, CandidateRuns& out) const {
  // The cells come in the sorted order: along a row, x only grows, and the nine rows about it stay the same.
  // They are found once per row of cells, and each row's cursor moves on from where the last cell left it,
  // rather than nine lookups and searches per cell (candidate_runs, which gives the same runs). The rows
  // come in order too, so the three runs of rows (z + dz, y - 1 .. y + 1) are found by walking three cursors
  // forward over the sorted row keys: nine hash lookups per row of cells were a third of find_self in issue
  // 41's level (callgrind), where sparse water has rows of one or two cells. The walks take a few steps at a
  // time with no branch on each: how far a cursor moves is a coin toss there, and the loops that stepped one
  // entry at a time were a fifth of the level's mispredicted branches (callgrind --branch-sim).
  const bool same_row = rows.valid && cell.y() == rows.y && cell.z() == rows.z;
  if (!same_row || cell.x() < rows.x) {
    const std::uint64_t* keys = m_row_keys.data();
    const auto row_count = static_cast<std::uint32_t>(m_row_keys.size() - kRowKeyPadding);
    const bool forward = rows.valid && row_key(cell.y(), cell.z()) > row_key(rows.y, rows.z);
    int r = 0;
    // Unrolled, as are the nine rows below: fewer instructions, and no loop exit (which callgrind's
    // predictor, having no history, missed once a call).
#pragma GCC unroll 3
    for (int dz = -1; dz <= 1; ++dz) {
      const std::uint64_t first_key = row_key(cell.y() - 1, cell.z() + dz);
      std::uint32_t& first = rows.first_row[dz + 1];
      if (forward) {
        // The keys ascend, padding included, so of the next four those below first_key are a prefix and
        // their count a sum; the cursor never passes the padding, so the four are always there.
        std::uint32_t step;
        do {
          const std::uint64_t* next = keys + first;
          step = static_cast<std::uint32_t>((next[0] < first_key ? 1 : 0) + (next[1] < first_key ? 1 : 0) +
                                            (next[2] < first_key ? 1 : 0) + (next[3] < first_key ? 1 : 0));
          first += step;
        } while (step == 4);
      } else {
        first = static_cast<std::uint32_t>(std::lower_bound(keys, keys + row_count, first_key) - keys);
      }
      std::uint32_t k = first;
#pragma GCC unroll 3
      for (int dy = -1; dy <= 1; ++dy, ++r) {
        // A missing row's cursor is entry 0, a lone end mark (m_row_first has an entry for k = row_count).
        const std::uint32_t found = keys[k] == first_key + static_cast<std::uint64_t>(dy + 1) ? 1u : 0u;
        rows.from[r] = m_row_first[k] & (0u - found);
        k += found;
      }
    }
    rows.valid = true;
    rows.y = cell.y();
    rows.z = cell.z();
  }
  rows.x = cell.x();
  RunAppender<CandidateRuns> append(out);
  const int* xs = m_cell_x.data();
#if defined(__SSE2__)
  // Four entries of a row at a time: the lanes left of cx - 1, then those within cx + 1, counted from their
  // masks. Both are prefixes of the four: a row's x ascend, and its end mark is above every x (the entries
  // past it, another row's, are not counted). Within cx + 1 at most three cells follow the cursor, so the
  // fourth lane or an end mark before it ends that count.
  const __m128i left_of = _mm_set1_epi32(cell.x() - 1);
  const __m128i right_of = _mm_set1_epi32(cell.x() + 1);
  const auto lanes = [&](std::uint32_t at) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(xs + at));
  };
  const auto mask = [](__m128i lanes_compared) {
    return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(lanes_compared)));
  };
#pragma GCC unroll 9
  for (int r = 0; r < 9; ++r) {
    std::uint32_t from = rows.from[r];
    unsigned left = mask(_mm_cmplt_epi32(lanes(from), left_of));
    while (left == 0xfu) {
      from += 4;
      left = mask(_mm_cmplt_epi32(lanes(from), left_of));
    }
    from += static_cast<std::uint32_t>(__builtin_ctz(~left));
    const unsigned beyond = mask(_mm_cmpgt_epi32(lanes(from), right_of));
    const std::uint32_t to = from + static_cast<std::uint32_t>(__builtin_ctz(beyond));
    rows.from[r] = from;
    append.add(m_cell_begin[from], m_cell_begin[to]);
  }
#else
  for (int r = 0; r < 9; ++r) {
    std::uint32_t from = rows.from[r];
    while (xs[from] < cell.x() - 1)
      ++from;
    std::uint32_t to = from;
    while (xs[to] <= cell.x() + 1)
      ++to;
    rows.from[r] = from;
    append.add(m_cell_begin[from], m_cell_begin[to]);
  }
#endif
  append.finish();
}

std::size_t NeighborSearch::scan(const CandidateRuns& runs, const Vec3& x, Index self, Index* dst) const {
  const Scalar r2 = m_radius * m_radius;
  switch (m_scan) {
#if DRENCH_HAS_AVX512_SCAN
    case CandidateScan::kAvx512Compress:
      return scan_runs_compress(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(), runs.begin,
                                runs.end, runs.runs, x, r2, self, dst);
#endif
#if DRENCH_HAS_AVX2_SCAN
    case CandidateScan::kAvx2Permute:
      return scan_runs_permute(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(), runs.begin,
                               runs.end, runs.runs, x, r2, self, dst);
#endif
    default:
      return scan_runs_lanes(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(), runs.begin,
                             runs.end, runs.runs, x, r2, self, dst);
  }
}

void NeighborSearch::find_self(NeighborList& out) const {
  find_sorted(*this, /*exclude_self=*/true, out);
}

void NeighborSearch::find_for_points_of(const NeighborSearch& queries, NeighborList& out) const {
  if (queries.m_radius != m_radius) {
    throw std::invalid_argument("NeighborSearch::find_for_points_of: the queries' grid has cells of " +
                                std::to_string(queries.m_radius) + " m, this one of " +
                                std::to_string(m_radius) + " m");
  }
  find_sorted(queries, /*exclude_self=*/false, out);
}

void NeighborSearch::find_sorted(const NeighborSearch& queries, bool exclude_self, NeighborList& out) const {
  const std::size_t m = queries.m_count;
  out.offsets.assign(m + 1, 0);
  if (m == 0 || m_count == 0) {
    out.indices.clear();
    return;
  }
  // The queries in their grid's sorted order, where the points of a cell are contiguous: the runs of a
  // cell's 27 neighbours are looked up once per cell, and no query's cell is computed again. In the caller's
  // order a z-order sorted some sub-steps ago kept runs of only 1.2 queries per cell in issue 41's level, and
  // looking the runs up again for nearly every query was half the search. Both grids sort their cells by row
  // (z, y), then x, so the queries' cells come in this grid's order too. Each thread gathers the lists of the
  // chunks it takes into its own buffer and remembers where each query's list starts; the lists are then
  // copied to their place in query order, the same for any thread count and any deal.
  const int threads = thread_count();
  std::vector<IndexArray>& buffers = m_thread_buffers;
  if (buffers.size() < static_cast<std::size_t>(threads)) buffers.resize(static_cast<std::size_t>(threads));
  m_query_owner.resize(m);
  m_query_start.resize(m);
  std::vector<std::size_t> used_by(static_cast<std::size_t>(threads), 0);
  const ScanRunsFunction scan_runs_function = scan_runs_for(m_scan);
  const Scalar r2 = m_radius * m_radius;
  const auto gather = [&](std::size_t chunk_begin, std::size_t chunk_end, int thread) {
    IndexArray& local = buffers[static_cast<std::size_t>(thread)];
    std::size_t used = used_by[static_cast<std::size_t>(thread)];
    CandidateRuns runs;
    RowCursor rows;
    bool buffered = false;
    Vec3i buffered_cell = Vec3i::Zero();
    for (std::size_t k = chunk_begin; k < chunk_end; ++k) {
      const Vec3i& c = queries.m_sorted_cells[k];
      if (!buffered || c != buffered_cell) {
        if (m_dense) {
          candidate_runs(c, runs);
        } else {
          rows_along(c, rows, runs);
        }
        buffered = true;
        buffered_cell = c;
      }
      const Index i = queries.m_sorted_index[k];
      const std::size_t first = used;
      // No candidates, no scan: most of the fluid's particles are far from every body's boundary points, and
      // the scan's call was most of their search.
      if (runs.runs > 0) {
        const std::size_t room = used + runs.total + kScanPadding;
        if (local.size() < room) local.resize(std::max(2 * local.size(), room));
        used +=
            scan_runs_function(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(), runs.begin,
                               runs.end, runs.runs, Vec3(queries.m_xs[k], queries.m_ys[k], queries.m_zs[k]),
                               r2, exclude_self ? i : kNoIndex, local.data() + used);
      }
      out.offsets[i + 1] = static_cast<std::uint32_t>(used - first);
      m_query_owner[i] = thread;
      m_query_start[i] = first;
    }
    used_by[static_cast<std::size_t>(thread)] = used;
  };
  parallel_for_slots(m, kParticleChunk, threads, gather);
  for (std::size_t i = 0; i < m; ++i)
    out.offsets[i + 1] += out.offsets[i];
  out.indices.resize(out.offsets[m]);
  parallel_for(m, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto from = buffers[static_cast<std::size_t>(m_query_owner[i])].begin() +
                        static_cast<std::ptrdiff_t>(m_query_start[i]);
      std::copy(from, from + static_cast<std::ptrdiff_t>(out.offsets[i + 1] - out.offsets[i]),
                out.indices.begin() + static_cast<std::ptrdiff_t>(out.offsets[i]));
    }
  });
}

void NeighborSearch::find(const Vec3Array& queries, NeighborList& out, bool exclude_self) const {
  const std::size_t m = queries.size();
  out.offsets.assign(m + 1, 0);
  if (m_count == 0 || m == 0) {
    out.indices.clear();
    return;
  }
  index_rows();  // before the threads read the table

  // One pass: the queries are cut into chunks of kParticleChunk, each taken by the next free thread (as
  // for_each_chunk), so that each thread gets some of every region of the z-ordered fluid: contiguous halves
  // were unbalanced (the half at the floor has the boundary neighbors). Each thread gathers into its own
  // buffer and remembers where each of its chunks starts; the chunks are then copied to their place in query
  // order, so the result is the same for any thread count and any deal.
  const int threads = thread_count();
  const std::size_t chunks = (m + kParticleChunk - 1) / kParticleChunk;
  // The per-thread buffers keep their capacity from call to call: grown from empty by doubling, every call
  // copied each buffer about twice over before its first write.
  std::vector<IndexArray>& buffers = m_thread_buffers;
  if (buffers.size() < static_cast<std::size_t>(threads)) buffers.resize(static_cast<std::size_t>(threads));
  std::vector<int> chunk_owner(chunks);
  std::vector<std::size_t> chunk_start(chunks);
  // Per thread: the buffer is grown ahead of the writes; only its first `used` entries are this call's.
  std::vector<std::size_t> used_by(static_cast<std::size_t>(threads), 0);
  const auto gather = [&](std::size_t chunk_begin, std::size_t chunk_end, int thread) {
    const std::size_t k = chunk_begin / kParticleChunk;
    IndexArray& local = buffers[static_cast<std::size_t>(thread)];
    std::size_t used = used_by[static_cast<std::size_t>(thread)];
    CandidateRuns runs;
    chunk_owner[k] = thread;
    chunk_start[k] = used;
    // Each query scans the runs of its nine rows of three cells in place in the sorted arrays; the runs are
    // looked up once per run of queries in one cell. Copying the candidates into one array per run of
    // queries first was rejected: particles drift between sorts, so a copy serves only about three queries,
    // and the eight-lane scans do better in place (bench_dam_break pcisph_59k; on the sorted block of
    // bench_neighbor_search they are even, and only the four-lane scan, for CPUs without AVX2, loses a
    // little). A row-by-row scan that skipped cells beyond the radius was slower still.
    bool buffered = false;
    Vec3i buffered_cell = Vec3i::Zero();
    for (std::size_t i = chunk_begin; i < chunk_end; ++i) {
      const Vec3& x = queries[i];
      // Out of reach of every point (the fluid's particles far from a body's boundary points): no cell to
      // look at. A NaN query fails both tests and is searched, finding nothing.
      if ((x.array() <= m_reach_lo.array()).any() || (x.array() >= m_reach_hi.array()).any()) continue;
      const Vec3i c = cell_of(x);
      if (!buffered || c != buffered_cell) {
        candidate_runs(c, runs);
        buffered = true;
        buffered_cell = c;
      }
      const Index self = exclude_self ? static_cast<Index>(i) : kNoIndex;
      const std::size_t room = used + runs.total + kScanPadding;
      if (local.size() < room) local.resize(std::max(2 * local.size(), room));
      const std::size_t first = used;
      used += scan(runs, x, self, local.data() + used);
      out.offsets[i + 1] = static_cast<std::uint32_t>(used - first);
    }
    used_by[static_cast<std::size_t>(thread)] = used;
  };
  parallel_for_slots(m, kParticleChunk, threads, gather);
  for (std::size_t i = 0; i < m; ++i)
    out.offsets[i + 1] += out.offsets[i];
  // The copy is parallel too: a serial concatenation was a tenth of WCSPH's sub-step on two threads
  // (bench_dam_break wcsph_59k). The list keeps its old entries until the copy overwrites every one: cleared
  // first, the resize zero-filled the whole list (a memset of 4 bytes per pair) on every search.
  out.indices.resize(out.offsets[m]);
  parallel_for(chunks, 4, [&](std::size_t first_chunk, std::size_t end_chunk) {
    for (std::size_t k = first_chunk; k < end_chunk; ++k) {
      const std::size_t begin = out.offsets[k * kParticleChunk];
      const std::size_t end = out.offsets[std::min(m, (k + 1) * kParticleChunk)];
      const auto from = buffers[static_cast<std::size_t>(chunk_owner[k])].begin() +
                        static_cast<std::ptrdiff_t>(chunk_start[k]);
      std::copy(from, from + static_cast<std::ptrdiff_t>(end - begin),
                out.indices.begin() + static_cast<std::ptrdiff_t>(begin));
    }
  });
}

}  // namespace drench
