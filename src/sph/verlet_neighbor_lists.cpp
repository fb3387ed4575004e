#include "sph/verlet_neighbor_lists.hpp"

#include <algorithm>
#include <cassert>
#include <limits>

#include "common/parallel.hpp"

namespace drench {

VerletNeighborLists::VerletNeighborLists(Scalar support_radius, Scalar max_skin, const Vec3Array& boundary)
    : m_support(support_radius),
      m_boundary_points(boundary),
      m_exact_fluid(support_radius),
      m_exact_boundary(support_radius),
      m_wide_fluid(support_radius + max_skin),
      m_wide_boundary(support_radius + max_skin) {
  assert(max_skin >= 0.0);
  m_exact_boundary.build(m_boundary_points);
  if (max_skin > 0.0) m_wide_boundary.build(m_boundary_points);
}

bool VerletNeighborLists::moved_beyond_half_skin(const Vec3Array& positions) const {
  Scalar max_sq = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max_sq)
  for (std::size_t i = 0; i < positions.size(); ++i)
    max_sq = std::max(max_sq, (positions[i] - m_positions[i]).squaredNorm());
  // A NaN displacement fails `<=` and so rebuilds, as does any motion beyond half the skin.
  return !(max_sq <= 0.25 * m_skin * m_skin);
}

bool VerletNeighborLists::update(const Vec3Array& positions, const std::vector<std::uint32_t>& ids,
                                 Scalar skin) {
  assert(skin >= 0.0 && skin <= m_wide_fluid.support_radius() - m_support + 1e-12 * m_support);
  const bool reuse = m_skin > 0.0 && ids == m_ids && !moved_beyond_half_skin(positions);
  if (!reuse) {
    m_skin = skin;
    NeighborSearch& fluid_search = skin > 0.0 ? m_wide_fluid : m_exact_fluid;
    const NeighborSearch& boundary_search = skin > 0.0 ? m_wide_boundary : m_exact_boundary;
    fluid_search.build(positions);
    fluid_search.find(positions, m_fluid_candidates, /*exclude_self=*/true);
    boundary_search.find(positions, m_boundary_candidates, /*exclude_self=*/false);
    if (skin > 0.0) {
      m_ids = ids;
      m_positions = positions;
    }
  }
  // Without a skin the search found exactly the neighbors: the pass only takes their squared distances.
  const bool keep_all = m_skin <= 0.0;
  filter(m_fluid_candidates, positions, positions, keep_all, m_fluid, m_fluid_r2);
  filter(m_boundary_candidates, positions, m_boundary_points, keep_all, m_boundary, m_boundary_r2);
  return !reuse;
}

void VerletNeighborLists::filter(const NeighborList& candidates, const Vec3Array& x, const Vec3Array& sources,
                                 bool keep_all, NeighborList& out, ScalarArray& out_r2) {
  const std::size_t n = x.size();
  const Scalar r2_max = keep_all ? std::numeric_limits<Scalar>::infinity() : m_support * m_support;
  out.offsets.assign(n + 1, 0);
  // Grown only: the fluid and boundary lists share the scratch, and a vector grown again is zero-filled again.
  if (m_kept.size() < candidates.indices.size()) {
    m_kept.resize(candidates.indices.size());
    m_kept_r2.resize(candidates.indices.size());
  }
  // One pass over the candidates writes each one, with its squared distance, at the particle's next free slot
  // of its own candidate range, and advances only for a neighbor: no branch (inside or not is a coin toss at
  // the skin), and a write never leaves the particle's range. The expression is NeighborSearch::find's
  // (source minus query, summed x, y, z), so a pair is kept exactly when a fresh search would report it.
#pragma omp parallel for schedule(static, kParticleChunk)
  for (std::size_t i = 0; i < n; ++i) {
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
  for (std::size_t i = 0; i < n; ++i)
    out.offsets[i + 1] += out.offsets[i];
  out.indices.resize(out.offsets[n]);
  out_r2.resize(out.offsets[n]);
#pragma omp parallel for schedule(static, kParticleChunk)
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t first = candidates.offsets[i];
    const std::uint32_t count = out.offsets[i + 1] - out.offsets[i];
    std::copy_n(m_kept.data() + first, count, out.indices.data() + out.offsets[i]);
    std::copy_n(m_kept_r2.data() + first, count, out_r2.data() + out.offsets[i]);
  }
}

}  // namespace drench
