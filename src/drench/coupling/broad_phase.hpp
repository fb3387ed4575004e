#pragma once
/// Broad phase of the coupling (Huber et al. 2013 sec. 5 uses spatial hashing [THM*03]): which particles can
/// touch which triangles during a step. Boxes are swept over the step (start and end positions) and grown by
/// a margin, so the same candidates serve the proximity test at the start (sec. 3.1) and the CCD (sec. 3.3).
/// Two boxes each grown by m overlap exactly when one grown by 2 m overlaps the other bare: the triangles'
/// boxes are kept bare, so that one tree serves every margin.
/// Two implementations behind one interface, compared side by side by bench_coupling find_pairs and
/// coupler_step.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <drench/common/parallel.hpp>
#include <drench/common/types.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupling_settings.hpp>

namespace drench {

/// An axis-aligned box (unit: m).
struct Box3 {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(double margin) {
    lo.array() -= margin;
    hi.array() += margin;
  }
  /// All six comparisons, combined without a branch: the broad phase's candidates pass about one in ten,
  /// and an early exit at whichever comparison failed was most of its queries' branch mispredictions
  /// (bench_game_frame under callgrind --branch-sim=yes). False when a coordinate is NaN. As ints, which
  /// say the `&` is meant (clang's -Wbitwise-instead-of-logical).
  bool overlaps(const Box3& o) const {
    const int all = int{lo.x() <= o.hi.x()} & int{lo.y() <= o.hi.y()} & int{lo.z() <= o.hi.z()} &
                    int{o.lo.x() <= hi.x()} & int{o.lo.y() <= hi.y()} & int{o.lo.z() <= hi.z()};
    return all != 0;
  }
};

/// A particle's box over the step: x_t0 and x_t1 grown by `margin` (unit: m). Inline: every broad phase
/// query computes one per particle.
inline Box3 particle_box(const Vec3& x_t0, const Vec3& x_t1, double margin) {
  Box3 box;
  box.extend(x_t0);
  box.extend(x_t1);
  box.grow(margin);
  return box;
}

/// A triangle's box over the step: its nodes at both ends grown by `margin` (unit: m). Inline: the grid
/// recomputes one per moved triangle at every change of the cloth.
inline Box3 triangle_box(const ClothMesh& cloth, const Triangle& t, double margin) {
  Box3 box;
  for (Index v : t) {
    box.extend(cloth.positions_t0[v]);
    box.extend(cloth.positions_t1[v]);
  }
  box.grow(margin);
  return box;
}

/// The whole mesh's box over the step: every node at both ends, not grown (unit: m). It holds every
/// triangle_box(cloth, t, 0) exactly (min and max do not round).
Box3 mesh_box(const ClothMesh& cloth);

/// True when some particle's box over the step, particle_box(x_t0, x_t1, margin), overlaps `box`; stops at
/// the first. A broad phase query of margin m / 2 on the same positions can report a pair only where this is
/// true for margin m and box mesh_box(cloth): so false proves that such a query finds nothing (a particle
/// with a NaN coordinate overlaps nothing here, as in the query).
/// @param particles_t0, particles_t1  N positions (unit: m)
/// @param margin  growth of every particle box (unit: m), >= 0
bool any_particle_box_overlaps(const Vec3Array& particles_t0, const Vec3Array& particles_t1, double margin,
                               const Box3& box);

/// The cloth a broad phase last built its triangle boxes for. Within one step the same cloth is queried many
/// times (every fluid sub-step's obstacle and the carried water's search, every CCD round of a kinematic
/// cloth); its boxes are rebuilt (FCL's tree refitted) only when it changed, not for every query.
class TriangleBoxKey {
 public:
  /// True when `cloth` (both position sets, triangles) equals that of the last call that returned false
  /// (coordinates compared with ==, so a NaN always differs; the same bytes always equal); else remembers
  /// it and returns false.
  /// @param moved  when not null and the result is false: M flags, set for the nodes whose position at either
  ///        end differs from the remembered one (all of them when the node count or the triangles changed,
  ///        or on the first call); a node whose bytes did not change may be left unset even with a NaN, as
  ///        its boxes are the same bits
  bool same_as_last(const ClothMesh& cloth, std::vector<std::uint8_t>* moved = nullptr);

 private:
  bool m_valid = false;
  Vec3Array m_positions_t0, m_positions_t1;
  std::vector<Triangle> m_triangles;
};

/// Sorts `v` ascending and drops repeated values, by insertion: for the few triangles of one particle's
/// query, where std::sort and std::unique cost more than the work.
inline void sort_unique_few(std::vector<Index>& v) {
  std::size_t kept = 1;  // v[0, kept) sorted, no repeats
  for (std::size_t i = 1; i < v.size(); ++i) {
    const Index x = v[i];
    std::size_t j = kept;
    while (j > 0 && v[j - 1] > x)
      --j;
    if (j > 0 && v[j - 1] == x) continue;
    for (std::size_t k = kept; k > j; --k)
      v[k] = v[k - 1];
    v[j] = x;
    ++kept;
  }
  v.resize(kept);
}

/// What every broad phase shares, once: for each particle (in parallel; the result in particle order, so the
/// same for any thread count) the triangles `found(box, hits)` appends to `hits` for its swept box grown by
/// 2 margin, sorted, duplicates removed. `found` must append exactly the triangles whose bare box overlaps
/// `box` (Box3::overlaps), each at least once, in any order. A template, not a std::function: the call per
/// particle was a quarter of the grid's query time in issue 41's level.
template <class Found>
void collect_pairs(const Vec3Array& particles_t0, const Vec3Array& particles_t1, double margin,
                   const std::vector<std::uint8_t>* only, const Found& found,
                   std::vector<std::pair<Index, Index>>& pairs) {
  pairs.clear();
  const std::size_t n = particles_t0.size();
  // One list per chunk of particles, concatenated in chunk order: pairs come in particle order, whichever
  // thread took a chunk.
  constexpr std::size_t kChunk = 256;
  std::vector<std::vector<std::pair<Index, Index>>> parts((n + kChunk - 1) / kChunk);
  parallel_for(n, kChunk, [&](std::size_t begin, std::size_t end) {
    std::vector<std::pair<Index, Index>>& mine = parts[begin / kChunk];
    std::vector<Index> hits;
    for (std::size_t p = begin; p < end; ++p) {
      if (only && !(*only)[p]) continue;
      hits.clear();
      found(particle_box(particles_t0[p], particles_t1[p], 2.0 * margin), hits);
      // Only the few triangles that passed the exact test are sorted: a particle has about one. Up to 16 by
      // insertion in place: std::sort and std::unique on so few cost 2.5% of find_pairs (bench_game_frame
      // under callgrind).
      if (hits.size() > 16) {
        std::sort(hits.begin(), hits.end());
        hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
      } else if (hits.size() > 1) {
        sort_unique_few(hits);
      }
      for (Index t : hits)
        mine.emplace_back(static_cast<Index>(p), t);
    }
  });
  std::size_t total = 0;
  for (const auto& part : parts)
    total += part.size();
  pairs.reserve(total);
  for (const auto& part : parts)
    pairs.insert(pairs.end(), part.begin(), part.end());
}

/// Candidate (particle, triangle) pairs: every pair whose swept boxes, each grown by the margin, overlap
/// (tested as the particle's grown by twice the margin against the triangle's bare box), sorted by particle
/// then triangle, each pair once. Implementations must return exactly this set (tests compare with brute
/// force).
class TriangleBroadPhase {
 public:
  virtual ~TriangleBroadPhase() = default;

  /// @param particles_t0, particles_t1  N particle positions at the start and end of the step (unit: m)
  /// @param cloth  the mesh, with positions_t0 and positions_t1
  /// @param margin  growth of every box (unit: m), >= 0
  /// @param only  when not null, N flags: pairs only for particles whose flag is set
  /// @param pairs  output, replaced
  virtual void find_pairs(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                          const ClothMesh& cloth, double margin, const std::vector<std::uint8_t>* only,
                          std::vector<std::pair<Index, Index>>& pairs) = 0;
};

/// The broad phase of a kind. FCL is linked privately; its types never appear in a header.
std::unique_ptr<TriangleBroadPhase> make_broad_phase(BroadPhaseKind kind);

/// Reference for tests: every pair tested, O(N F).
void find_pairs_brute_force(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                            const ClothMesh& cloth, double margin,
                            std::vector<std::pair<Index, Index>>& pairs);

}  // namespace drench
