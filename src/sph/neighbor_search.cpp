#include "sph/neighbor_search.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include <omp.h>

#include "common/parallel.hpp"
#include "sph/candidate_scan.hpp"

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

std::uint64_t hash_key(std::uint64_t key) {
  // splitmix64 finaliser: Morton keys of neighbouring cells differ in few bits, so they need mixing.
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return key;
}

/// scan_candidates_lanes compiled for each copy of DRENCH_SIMD_CLONES (the CPUs without AVX-512).
DRENCH_SIMD_CLONES std::size_t scan_candidates(const Scalar* xs, const Scalar* ys, const Scalar* zs,
                                               const Index* indices, std::uint32_t end, const Vec3& x,
                                               Scalar r2, Index self, Index* dst) {
  return scan_candidates_lanes(xs, ys, zs, indices, end, x, r2, self, dst);
}

}  // namespace

NeighborSearch::NeighborSearch(Scalar support_radius)
    : m_radius(support_radius), m_inv_cell(1.0 / support_radius) {
  assert(support_radius > 0.0);
  set_compressed_scan(true);
}

void NeighborSearch::set_compressed_scan(bool on) {
  m_compressed_scan = on && DRENCH_HAS_COMPRESS_SCAN && avx512_copy();
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
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i)
    keyed[i] = {cell_key(points[i]), static_cast<Index>(i)};
  std::sort(keyed.begin(), keyed.end());
  IndexArray order(n);
  for (std::size_t k = 0; k < n; ++k)
    order[k] = keyed[k].second;
  return order;
}

void NeighborSearch::build(const Vec3Array& points) {
  const std::size_t n = points.size();
  std::vector<Vec3i> cells(n);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i)
    cells[i] = cell_of(points[i]);
  Vec3i lo = Vec3i::Constant(std::numeric_limits<int>::max());
  Vec3i hi = Vec3i::Constant(std::numeric_limits<int>::min());
  for (const Vec3i& c : cells) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const Vec3i dims = n > 0 ? Vec3i(hi - lo + Vec3i::Ones()) : Vec3i::Zero();
  const double cell_count = static_cast<double>(dims.x()) * dims.y() * dims.z();
  // Dense while it costs at most 128 cells (512 bytes of cell starts, one counting-sort pass) per point, up
  // to 2^24 cells (64 MB), or 4 per point whatever their number: a query run then reads nine row ranges
  // where the hash takes 27 lookups. The jet on a cloth (15K particles spread over up to 71 cells each)
  // spent 3.1-3.7 s in its neighbor phase over 0.5 s with this rule against 3.9-5.1 s with the earlier
  // limit of 4 per point (alternating runs, 2 threads), frames bit-identical.
  const double point_count = static_cast<double>(n);
  m_dense = n > 0 &&
            (cell_count <= 4.0 * point_count + 4096.0 || cell_count <= std::min(128.0 * point_count, 0x1p24));
  if (m_dense) {
    build_dense(cells, lo, dims);
  } else {
    build_hashed(points);
  }
  m_count = n;
  // kScanPadding entries after the last point: the compressed scan reads the runs of cells in place.
  m_sorted_index.resize(n + kScanPadding, 0);
  m_xs.resize(n + kScanPadding);
  m_ys.resize(n + kScanPadding);
  m_zs.resize(n + kScanPadding);
#pragma omp parallel for schedule(static)
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& x = points[m_sorted_index[k]];
    m_xs[k] = x.x();
    m_ys[k] = x.y();
    m_zs[k] = x.z();
  }
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
  m_cell_keys.clear();
  m_table.clear();
}

void NeighborSearch::build_hashed(const Vec3Array& points) {
  m_sorted_index = z_order(points);
  const std::size_t n = points.size();
  m_cell_keys.clear();
  m_cell_begin.clear();
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint64_t key = cell_key(points[m_sorted_index[k]]);
    if (m_cell_keys.empty() || m_cell_keys.back() != key) {
      m_cell_keys.push_back(key);
      m_cell_begin.push_back(static_cast<std::uint32_t>(k));
    }
  }
  m_cell_begin.push_back(static_cast<std::uint32_t>(n));

  std::size_t capacity = 16;
  while (capacity < 2 * m_cell_keys.size())
    capacity *= 2;
  m_table.assign(capacity, -1);
  m_table_mask = capacity - 1;
  for (std::size_t c = 0; c < m_cell_keys.size(); ++c) {
    std::uint64_t slot = hash_key(m_cell_keys[c]) & m_table_mask;
    while (m_table[slot] >= 0)
      slot = (slot + 1) & m_table_mask;
    m_table[slot] = static_cast<std::int64_t>(c);
  }
}

bool NeighborSearch::cell_range(const Vec3i& cell, std::uint32_t& begin, std::uint32_t& end) const {
  std::size_t slot;
  if (m_dense) {
    const Vec3i local = cell - m_lo;
    if ((local.array() < 0).any() || (local.array() >= m_dims.array()).any()) return false;
    slot = (static_cast<std::size_t>(local.z()) * m_dims.y() + local.y()) * m_dims.x() + local.x();
  } else {
    const std::int64_t c = lookup(key_of_cell(cell));
    if (c < 0) return false;
    slot = static_cast<std::size_t>(c);
  }
  begin = m_cell_begin[slot];
  end = m_cell_begin[slot + 1];
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

std::int64_t NeighborSearch::lookup(std::uint64_t key) const {
  std::uint64_t slot = hash_key(key) & m_table_mask;
  while (true) {
    const std::int64_t c = m_table[slot];
    if (c < 0) return -1;
    if (m_cell_keys[static_cast<std::size_t>(c)] == key) return c;
    slot = (slot + 1) & m_table_mask;
  }
}

void NeighborSearch::gather_candidates(const Vec3i& cell, Candidates& out) const {
  out.size = 0;
  const auto append = [&](std::uint32_t b, std::uint32_t e) {
    const std::size_t size = out.size + (e - b);
    if (out.indices.size() < size + kScanPadding) {
      // The scans read whole groups of up to eight.
      const std::size_t grown = std::max(2 * out.indices.size(), size + kScanPadding);
      out.xs.resize(grown);
      out.ys.resize(grown);
      out.zs.resize(grown);
      out.indices.resize(grown);
    }
    std::copy(m_xs.begin() + b, m_xs.begin() + e, out.xs.begin() + out.size);
    std::copy(m_ys.begin() + b, m_ys.begin() + e, out.ys.begin() + out.size);
    std::copy(m_zs.begin() + b, m_zs.begin() + e, out.zs.begin() + out.size);
    std::copy(m_sorted_index.begin() + b, m_sorted_index.begin() + e, out.indices.begin() + out.size);
    out.size = static_cast<std::uint32_t>(size);
  };
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      std::uint32_t b, e;
      if (m_dense) {
        // The row's cells are adjacent in the dense grid, so their points are one range: one lookup instead
        // of three, the same points in the same order.
        if (row_range(cell + Vec3i(-1, dy, dz), 3, b, e)) append(b, e);
      } else {
        for (int dx = -1; dx <= 1; ++dx) {
          if (cell_range(cell + Vec3i(dx, dy, dz), b, e)) append(b, e);
        }
      }
    }
  }
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
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      std::uint32_t b, e;
      if (m_dense) {
        if (row_range(cell + Vec3i(-1, dy, dz), 3, b, e)) add(b, e);
      } else {
        for (int dx = -1; dx <= 1; ++dx) {
          if (cell_range(cell + Vec3i(dx, dy, dz), b, e)) add(b, e);
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
  const int threads = omp_get_max_threads();
  const std::size_t chunks = (m + kParticleChunk - 1) / kParticleChunk;
  // The per-thread buffers keep their capacity from call to call: grown from empty by doubling, every call
  // copied each buffer about twice over before its first write.
  std::vector<IndexArray>& buffers = m_thread_buffers;
  if (buffers.size() < static_cast<std::size_t>(threads)) buffers.resize(static_cast<std::size_t>(threads));
  if (m_thread_candidates.size() < static_cast<std::size_t>(threads))
    m_thread_candidates.resize(static_cast<std::size_t>(threads));
  std::vector<int> chunk_owner(chunks);
  std::vector<std::size_t> chunk_start(chunks);
#pragma omp parallel num_threads(threads)
  {
    const int thread = omp_get_thread_num();
    IndexArray& local = buffers[static_cast<std::size_t>(thread)];
    Candidates& candidates = m_thread_candidates[static_cast<std::size_t>(thread)];
    CandidateRuns runs;
    std::size_t used =
        0;  // local is grown ahead of the writes; only its first `used` entries are this call's
#pragma omp for schedule(dynamic, 1)
    for (std::size_t k = 0; k < chunks; ++k) {
      chunk_owner[k] = thread;
      chunk_start[k] = used;
      const std::size_t chunk_end = std::min(m, (k + 1) * kParticleChunk);
      // The candidates of a cell are gathered once for the run of queries in it (z-ordered particles come
      // in runs of about eight per cell), then each query scans them in one loop. Scanning the cells row by
      // row per query, skipping cells beyond the radius, read 24% fewer points but was slower: nine short
      // loops per query, each of a different length (bench/bench_neighbor_search, 1 thread: 23.6-41.4 ms
      // against 18.5-19.5 ms, bench/results/debian12-2core/neighbor_search_99939d6_vs_7d87b95.txt).
      // The compressed scan reads the nine rows in place instead, the gather (four copies per row) costing
      // more than its own per-row tails: in the dam break the particles drift between sorts, and a gather
      // served only about three queries (0.35 gathers per query over 100 steps of the 59K run). The 59K
      // PCISPH dam break ran 336K and 346K particle-steps/s on 1 thread against 322K and 332K with the
      // gather (alternating); on the sorted block of bench_neighbor_search the two are even.
      bool buffered = false;
      Vec3i buffered_cell = Vec3i::Zero();
      for (std::size_t i = k * kParticleChunk; i < chunk_end; ++i) {
        const Vec3& x = queries[i];
        const Vec3i c = cell_of(x);
        const Index self = exclude_self ? static_cast<Index>(i) : kNoIndex;
#if DRENCH_HAS_COMPRESS_SCAN
        if (m_compressed_scan) {
          if (!buffered || c != buffered_cell) {
            candidate_runs(c, runs);
            buffered = true;
            buffered_cell = c;
          }
          const std::size_t room = used + runs.total + kScanPadding;
          if (local.size() < room) local.resize(std::max(2 * local.size(), room));
          const std::size_t first = used;
          used += scan_runs_compress(m_xs.data(), m_ys.data(), m_zs.data(), m_sorted_index.data(), runs.begin,
                                     runs.end, runs.runs, x, r2, self, local.data() + used);
          out.offsets[i + 1] = static_cast<std::uint32_t>(used - first);
          continue;
        }
#endif
        if (!buffered || c != buffered_cell) {
          gather_candidates(c, candidates);
          buffered = true;
          buffered_cell = c;
        }
        const std::size_t room = used + candidates.size + kScanPadding;
        if (local.size() < room) local.resize(std::max(2 * local.size(), room));
        const std::size_t first = used;
        used += scan_candidates(candidates.xs.data(), candidates.ys.data(), candidates.zs.data(),
                                candidates.indices.data(), candidates.size, x, r2, self, local.data() + used);
        out.offsets[i + 1] = static_cast<std::uint32_t>(used - first);
      }
    }
  }
  for (std::size_t i = 0; i < m; ++i)
    out.offsets[i + 1] += out.offsets[i];
  // The copy is parallel too: a serial concatenation was a tenth of WCSPH's sub-step on two threads
  // (measured). The list keeps its old entries until the copy overwrites every one: cleared first, the
  // resize zero-filled the whole list (a memset of 4 bytes per pair) on every search.
  out.indices.resize(out.offsets[m]);
#pragma omp parallel for schedule(static)
  for (std::size_t k = 0; k < chunks; ++k) {
    const std::size_t begin = out.offsets[k * kParticleChunk];
    const std::size_t end = out.offsets[std::min(m, (k + 1) * kParticleChunk)];
    const auto from = buffers[static_cast<std::size_t>(chunk_owner[k])].begin() +
                      static_cast<std::ptrdiff_t>(chunk_start[k]);
    std::copy(from, from + static_cast<std::ptrdiff_t>(end - begin),
              out.indices.begin() + static_cast<std::ptrdiff_t>(begin));
  }
}

}  // namespace drench
