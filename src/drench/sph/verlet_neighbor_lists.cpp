#include <drench/sph/verlet_neighbor_lists.hpp>

#include <algorithm>
#include <cassert>
#include <utility>

#include <drench/common/parallel.hpp>

namespace drench {

namespace {

/// factors[n] = the kernel's gradient factor of the pair n of `list`, rounded to float, for the rows [begin,
/// end): query i at xs[3i..3i+2], source j at ss[3j..3j+2] (unit: m). The distance is NeighborSearch::find's
/// expression (source minus query, summed x, y, z). Compiled per CPU (DRENCH_SIMD_CLONES): a square root and
/// a division per pair, which the baseline copy does only two at a time, in a loop that is a visible share of
/// a PCISPH step (bench_pair_loops neighbor_lists).
DRENCH_SIMD_CLONES void gradient_factor_rows(const CubicSplineKernel& kernel, const NeighborList& list,
                                             const Scalar* xs, const Scalar* ss, std::size_t begin,
                                             std::size_t end, float* factors) {
  const Index* js = list.indices.data();
  for (std::size_t i = begin; i < end; ++i) {
    const Scalar x0 = xs[3 * i], x1 = xs[3 * i + 1], x2 = xs[3 * i + 2];
    // Eight pairs per vector step: the AVX-512 copy otherwise took sixteen (two vectors) and left a row's
    // last up to fifteen pairs (of about 27) to scalar code, which is slower (bench_pair_loops
    // neighbor_lists).
#pragma omp simd simdlen(8)
    for (std::uint32_t n = list.offsets[i]; n < list.offsets[i + 1]; ++n) {
      const std::size_t j = 3 * std::size_t{js[n]};
      const Scalar d0 = ss[j] - x0, d1 = ss[j + 1] - x1, d2 = ss[j + 2] - x2;
      factors[n] = static_cast<float>(kernel.gradient_factor(d0 * d0 + d1 * d1 + d2 * d2));
    }
  }
}

/// The kept pairs of the particles [begin, end) moved to their place in the filtered list: particle i's kept
/// indices and squared distances (unit: m^2) start at candidate_offsets[i] in kept and kept_r2, and go to
/// out_offsets[i] in out_indices, with their gradient factors rounded to float in out_factors (unless null).
/// Compiled per CPU as gradient_factor_rows, and called per chunk (one dispatch per chunk, as
/// for_each_chunk's loops).
DRENCH_SIMD_CLONES void move_kept_rows(const CubicSplineKernel& kernel,
                                       const std::uint32_t* candidate_offsets,
                                       const std::uint32_t* out_offsets, const Index* kept,
                                       const Scalar* kept_r2, std::size_t begin, std::size_t end,
                                       Index* out_indices, float* out_factors) {
  for (std::size_t i = begin; i < end; ++i) {
    const std::uint32_t first = candidate_offsets[i];
    const std::uint32_t count = out_offsets[i + 1] - out_offsets[i];
    std::copy_n(kept + first, count, out_indices + out_offsets[i]);
    if (!out_factors) continue;
    const Scalar* r2 = kept_r2 + first;
    float* factors = out_factors + out_offsets[i];
#pragma omp simd
    for (std::uint32_t k = 0; k < count; ++k)
      factors[k] = static_cast<float>(kernel.gradient_factor(r2[k]));
  }
}

}  // namespace

VerletNeighborLists::VerletNeighborLists(const CubicSplineKernel& kernel, Scalar max_skin, Vec3Array boundary)
    : m_kernel(kernel),
      m_support(kernel.support_radius()),
      m_boundary_points(std::move(boundary)),
      m_exact_fluid(m_support),
      m_exact_boundary(m_support),
      m_wide_fluid(m_support + max_skin),
      m_wide_boundary(m_support + max_skin) {
  assert(max_skin >= 0.0);
  m_exact_boundary.build(m_boundary_points);
}

void VerletNeighborLists::set_boundary_points(std::size_t first, const Vec3Array& points) {
  assert(first <= m_boundary_points.size());
  m_boundary_points.resize(first + points.size());
  std::copy(points.begin(), points.end(), m_boundary_points.begin() + static_cast<long>(first));
  m_exact_boundary.build(m_boundary_points);
  m_wide_boundary_built = false;
  m_skin = 0.0;  // the kept candidates name the old points
}

bool VerletNeighborLists::moved_beyond_half_skin(const Vec3Array& positions) const {
  const Scalar max_sq = parallel_reduce(
      positions.size(), kLightChunk, Scalar(0.0),
      [&](std::size_t begin, std::size_t end) {
        Scalar m = 0.0;
        for (std::size_t i = begin; i < end; ++i)
          m = std::max(m, (positions[i] - m_positions[i]).squaredNorm());
        return m;
      },
      [](Scalar a, Scalar b) { return std::max(a, b); });
  // A NaN displacement fails `<=` and so rebuilds, as does any motion beyond half the skin.
  return !(max_sq <= 0.25 * m_skin * m_skin);
}

bool VerletNeighborLists::update(const Vec3Array& positions, const std::vector<std::uint32_t>& ids,
                                 Scalar skin) {
  assert(skin >= 0.0 && skin <= m_wide_fluid.support_radius() - m_support + 1e-12 * m_support);
  if (m_skin > 0.0 && ids == m_ids && !moved_beyond_half_skin(positions)) {
    filter(m_fluid_candidates, positions, positions, m_fluid, m_fluid_factors, m_want_fluid_factors);
    filter(m_boundary_candidates, positions, m_boundary_points, m_boundary, m_boundary_factors);
    return false;
  }
  m_skin = skin;
  if (skin > 0.0) {
    m_ids = ids;
    m_positions = positions;
    m_wide_fluid.build(positions);
    m_wide_fluid.find_self(m_fluid_candidates);
    // Built here, when a skin first needs it: a moving body's points change every step, and a solver that
    // never keeps a skin (PBF, PCISPH) would pay a second grid of them per step for nothing (issue 41).
    if (!m_wide_boundary_built) {
      m_wide_boundary.build(m_boundary_points);
      m_wide_boundary_built = true;
    }
    m_wide_boundary.find(positions, m_boundary_candidates, /*exclude_self=*/false);
    filter(m_fluid_candidates, positions, positions, m_fluid, m_fluid_factors, m_want_fluid_factors);
    filter(m_boundary_candidates, positions, m_boundary_points, m_boundary, m_boundary_factors);
  } else {
    // Exactly the neighbors: nothing to filter, and no candidates are kept.
    m_exact_fluid.build(positions);
    m_exact_fluid.find_self(m_fluid);
    m_exact_boundary.find_for_points_of(m_exact_fluid, m_boundary);
    if (m_want_fluid_factors) {
      gradient_factors(m_fluid, positions, positions, m_fluid_factors);
    } else {
      m_fluid_factors.clear();
    }
    gradient_factors(m_boundary, positions, m_boundary_points, m_boundary_factors);
  }
  return true;
}

void VerletNeighborLists::gradient_factors(const NeighborList& list, const Vec3Array& x,
                                           const Vec3Array& sources, GradientFactorArray& out_factors) const {
  out_factors.resize(list.indices.size());
  for_each_chunk(x.size(), [&](std::size_t begin, std::size_t end) {
    gradient_factor_rows(m_kernel, list, coordinates(x), coordinates(sources), begin, end,
                         out_factors.data());
  });
}

void VerletNeighborLists::filter(const NeighborList& candidates, const Vec3Array& x, const Vec3Array& sources,
                                 NeighborList& out, GradientFactorArray& out_factors, bool factors) {
  const std::size_t n = x.size();
  const Scalar r2_max = m_support * m_support;
  out.offsets.assign(n + 1, 0);
  // Grown only: the fluid and boundary lists share the scratch, and a vector grown again is zero-filled
  // again.
  if (m_kept.size() < candidates.indices.size()) {
    m_kept.resize(candidates.indices.size());
    m_kept_r2.resize(candidates.indices.size());
  }
  // One pass over the candidates writes each one, with its squared distance, at the particle's next free slot
  // of its own candidate range, and advances only for a neighbor: no branch (inside or not is a coin toss at
  // the skin), and a write never leaves the particle's range. The distance is NeighborSearch::find's
  // expression (source minus query, summed x, y, z), so a pair is kept exactly when a fresh search would
  // report it. The gradient factors are taken in the second pass, over the kept pairs only and vectorized.
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t first = candidates.offsets[i];
      Index* kept = m_kept.data() + first;
      Scalar* kept_r2 = m_kept_r2.data() + first;
      const Scalar x0 = x[i].x(), x1 = x[i].y(), x2 = x[i].z();
      std::uint32_t count = 0;
      for (std::uint32_t c = first; c < candidates.offsets[i + 1]; ++c) {
        const Index j = candidates.indices[c];
        const Scalar d0 = sources[j].x() - x0, d1 = sources[j].y() - x1, d2 = sources[j].z() - x2;
        const Scalar r2 = d0 * d0 + d1 * d1 + d2 * d2;
        kept[count] = j;
        kept_r2[count] = r2;
        count += r2 < r2_max ? 1u : 0u;
      }
      out.offsets[i + 1] = count;
    }
  });
  for (std::size_t i = 0; i < n; ++i)
    out.offsets[i + 1] += out.offsets[i];
  out.indices.resize(out.offsets[n]);
  out_factors.resize(factors ? out.offsets[n] : 0);
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    move_kept_rows(m_kernel, candidates.offsets.data(), out.offsets.data(), m_kept.data(), m_kept_r2.data(),
                   begin, end, out.indices.data(), factors ? out_factors.data() : nullptr);
  });
}

}  // namespace drench
