#include <drench/sph/neighbor_search.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include <drench/common/parallel.hpp>
#include <drench/sph/candidate_scan.hpp>

namespace drench {

namespace {

constexpr int kCellBits = 21;
constexpr std::int64_t kCellOffset = std::int64_t{1} << (kCellBits - 1);
constexpr std::int64_t kCellMax = (std::int64_t{1} << kCellBits) - 1;
constexpr Index kNoIndex = std::numeric_limits<Index>::max();

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

/// The bits of a Morton key that hold one axis' coordinate (x; shifted by 1 and 2, y and z).
constexpr std::uint64_t kAxisBits = 0x1249249249249249ULL;

/// The key of the cell `step` (-1, 0 or 1) cells along the axis whose bits are `mask` from the cell of
/// `key`, without spreading the coordinates again: the masked bits are incremented or decremented as one
/// number, the carry passing over the other axes' bits. The coordinate must stay in [0, 2^21): cell_of
/// clamps to [1, 2^21 - 2], so one step never leaves it.
std::uint64_t morton_step(std::uint64_t key, std::uint64_t mask, int step) {
  if (step > 0) return (((key | ~mask) + 1) & mask) | (key & ~mask);
  if (step < 0) return (((key & mask) - 1) & mask) | (key & ~mask);
  return key;
}

/// scan_runs with scan_candidates_lanes, compiled for each copy of DRENCH_SIMD_CLONES: the CPUs without AVX2.
DRENCH_SIMD_CLONES std::size_t scan_runs_lanes(const Scalar* xs, const Scalar* ys, const Scalar* zs,
                                               const Index* indices, const std::uint32_t* begins,
                                               const std::uint32_t* ends, int runs, const Vec3& x, Scalar r2,
                                               Index self, Index* dst) {
  return scan_runs<scan_candidates_lanes>(xs, ys, zs, indices, begins, ends, runs, x, r2, self, dst);
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

Vec3i NeighborSearch::cell_of(const Vec3& x) const {
  Vec3i cell;
  for (int a = 0; a < 3; ++a) {
    // Clamp before converting: a cast of an out-of-range double to int is undefined behaviour.
    // NaN goes to the lowest cell; the solver reports non-finite particles itself.
    const Scalar c = std::floor(x[a] * m_inv_cell) + static_cast<Scalar>(kCellOffset);
    cell[a] = std::isnan(c) ? 1 : static_cast<int>(std::clamp(c, 1.0, static_cast<Scalar>(kCellMax - 1)));
  }
  return cell;
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
  std::vector<Vec3i> cells(n);
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
  } else {
    build_hashed(points);
  }
  m_count = n;
  // kScanPadding entries after the last point: the scans read runs of cells in place, whole groups.
  m_sorted_index.resize(n + kScanPadding, 0);
  m_xs.resize(n + kScanPadding);
  m_ys.resize(n + kScanPadding);
  m_zs.resize(n + kScanPadding);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const Vec3& x = points[m_sorted_index[k]];
      m_xs[k] = x.x();
      m_ys[k] = x.y();
      m_zs[k] = x.z();
    }
  });
}

void NeighborSearch::build_dense(const std::vector<Vec3i>& cells, const Vec3i& lo, const Vec3i& dims) {
  m_lo = lo;
  m_dims = dims;
  const std::size_t cell_count = static_cast<std::size_t>(dims.x()) * dims.y() * dims.z();
  auto linear = [&](const Vec3i& c) {
    return (static_cast<std::size_t>(c.z() - lo.z()) * dims.y() + (c.y() - lo.y())) * dims.x() +
           (c.x() - lo.x());
  };
  // Counting sort by cell: stable in the point index, so the order is deterministic.
  m_cell_begin.assign(cell_count + 1, 0);
  for (const Vec3i& c : cells)
    ++m_cell_begin[linear(c) + 1];
  for (std::size_t c = 0; c < cell_count; ++c)
    m_cell_begin[c + 1] += m_cell_begin[c];
  std::vector<std::uint32_t> next(m_cell_begin.begin(), m_cell_begin.end() - 1);
  m_sorted_index.resize(cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i)
    m_sorted_index[next[linear(cells[i])]++] = static_cast<Index>(i);
  m_cells.clear();
}

void NeighborSearch::build_hashed(const Vec3Array& points) {
  m_sorted_index = z_order(points);
  const std::size_t n = points.size();
  std::vector<std::uint64_t> keys;
  m_cell_begin.clear();
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint64_t key = cell_key(points[m_sorted_index[k]]);
    if (keys.empty() || keys.back() != key) {
      keys.push_back(key);
      m_cell_begin.push_back(static_cast<std::uint32_t>(k));
    }
  }
  m_cell_begin.push_back(static_cast<std::uint32_t>(n));
  m_cells.build(std::move(keys));
}

bool NeighborSearch::key_range(std::uint64_t key, std::uint32_t& begin, std::uint32_t& end) const {
  const std::int64_t c = m_cells.find(key);
  if (c < 0) return false;
  begin = m_cell_begin[static_cast<std::size_t>(c)];
  end = m_cell_begin[static_cast<std::size_t>(c) + 1];
  return begin < end;
}

bool NeighborSearch::row_range(const Vec3i& cell, int count, std::uint32_t& begin, std::uint32_t& end) const {
  const Vec3i local = cell - m_lo;
  if (local.y() < 0 || local.y() >= m_dims.y() || local.z() < 0 || local.z() >= m_dims.z()) return false;
  const int x_first = std::max(local.x(), 0);
  const int x_last = std::min(local.x() + count - 1, m_dims.x() - 1);
  if (x_first > x_last) return false;
  const std::size_t row = (static_cast<std::size_t>(local.z()) * m_dims.y() + local.y()) * m_dims.x();
  begin = m_cell_begin[row + x_first];
  end = m_cell_begin[row + x_last + 1];
  return begin < end;
}

void NeighborSearch::candidate_runs(const Vec3i& cell, CandidateRuns& out) const {
  out.runs = 0;
  out.total = 0;
  const auto add = [&](std::uint32_t b, std::uint32_t e) {
    out.begin[out.runs] = b;
    out.end[out.runs] = e;
    ++out.runs;
    out.total += e - b;
  };
  // Hashed: the 27 keys from the centre's by masked steps, the same keys key_of_cell would give each cell
  // (spreading the bits of every neighbor was a quarter of the lookups' time in issue 41's level).
  const std::uint64_t centre = m_dense ? 0 : key_of_cell(cell);
  for (int dz = -1; dz <= 1; ++dz) {
    const std::uint64_t key_z = morton_step(centre, kAxisBits << 2, dz);
    for (int dy = -1; dy <= 1; ++dy) {
      std::uint32_t b, e;
      if (m_dense) {
        if (row_range(cell + Vec3i(-1, dy, dz), 3, b, e)) add(b, e);
      } else {
        const std::uint64_t key_zy = morton_step(key_z, kAxisBits << 1, dy);
        for (int dx = -1; dx <= 1; ++dx) {
          if (key_range(morton_step(key_zy, kAxisBits, dx), b, e)) add(b, e);
        }
      }
    }
  }
}

void NeighborSearch::find(const Vec3Array& queries, NeighborList& out, bool exclude_self) const {
  const std::size_t m = queries.size();
  const Scalar r2 = m_radius * m_radius;
  out.offsets.assign(m + 1, 0);
  if (m_count == 0 || m == 0) {
    out.indices.clear();
    return;
  }

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
  parallel_for_slots(
      m, kParticleChunk, threads, [&](std::size_t chunk_begin, std::size_t chunk_end, int thread) {
        const std::size_t k = chunk_begin / kParticleChunk;
        IndexArray& local = buffers[static_cast<std::size_t>(thread)];
        std::size_t used = used_by[static_cast<std::size_t>(thread)];
        CandidateRuns runs;
        chunk_owner[k] = thread;
        chunk_start[k] = used;
        // Each query scans the runs of its 27 cells in place in the sorted arrays (nine rows in the dense
        // grid); the runs are looked up once per run of queries in one cell. Copying the candidates into one
        // array per run of queries first was rejected: particles drift between sorts, so a copy serves only
        // about three queries, and the eight-lane scans do better in place (bench_dam_break pcisph_59k; on
        // the sorted block of bench_neighbor_search they are even, and only the four-lane scan, for CPUs
        // without AVX2, loses a little). A row-by-row scan that skipped cells beyond the radius was slower
        // still.
        bool buffered = false;
        Vec3i buffered_cell = Vec3i::Zero();
        for (std::size_t i = chunk_begin; i < chunk_end; ++i) {
          const Vec3& x = queries[i];
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
          Index* dst = local.data() + used;
          switch (m_scan) {
#if DRENCH_HAS_AVX512_SCAN
            case CandidateScan::kAvx512Compress:
              used += scan_runs_compress(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(),
                                         runs.begin, runs.end, runs.runs, x, r2, self, dst);
              break;
#endif
#if DRENCH_HAS_AVX2_SCAN
            case CandidateScan::kAvx2Permute:
              used += scan_runs_permute(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(),
                                        runs.begin, runs.end, runs.runs, x, r2, self, dst);
              break;
#endif
            default:
              used += scan_runs_lanes(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(),
                                      runs.begin, runs.end, runs.runs, x, r2, self, dst);
          }
          out.offsets[i + 1] = static_cast<std::uint32_t>(used - first);
        }
        used_by[static_cast<std::size_t>(thread)] = used;
      });
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
