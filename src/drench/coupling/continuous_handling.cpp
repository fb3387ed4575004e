// Continuous intersection handling (Huber et al. 2013 sec. 3.3, eq. 5-6): rounds of point-triangle CCD on
// the corrected motion, an inelastic impulse at each particle's earliest impact, and the fail-safe.
// resolve_ccd is declared and documented in coupler_stages.hpp.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>
#include <drench/coupling/coupler_stages.hpp>

namespace drench {
namespace coupling_detail {
namespace {

/// A particle's earliest impact in one CCD round: the triangle it hits and the CCD's answer.
struct Impact {
  Index triangle = 0;
  ccd::CcdResult ccd;
};

/// Earliest impact per particle among `pairs` (queries in parallel, reduction in pair order).
/// @param pairs  (particle, triangle) sorted by particle, then triangle
/// @param impacts  output, replaced: (particle, impact) in particle order, one per particle that hits
void find_impacts(const StepContext& ctx, const std::vector<std::pair<Index, Index>>& pairs,
                  std::vector<std::pair<Index, Impact>>& impacts) {
  std::vector<ccd::CcdResult> results(pairs.size());
  parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      results[k] = ccd::point_triangle_ccd(ctx.query(pairs[k].first, pairs[k].second));
  });
  impacts.clear();
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (!results[k].hit) continue;
    // A particle that starts exactly in the triangle (distance 0: it has no side yet) touches at t = 0
    // whatever it does next; pushing it would flip it back and forth. Repulsion handles it. Anything else at
    // toi = 0 may be a contact just after the start (toi is a lower bound) and is resolved.
    if (results[k].toi == 0.0 &&
        ccd::coplanarity_sign_exact(ctx.query(pairs[k].first, pairs[k].second), false) == 0) {
      continue;
    }
    const Index p = pairs[k].first;
    if (!impacts.empty() && impacts.back().first == p) {
      // One impact per particle: the earliest; a hit through a shared edge or vertex is handled once.
      if (results[k].toi < impacts.back().second.ccd.toi)
        impacts.back().second = {pairs[k].second, results[k]};
      continue;
    }
    impacts.push_back({p, {pairs[k].second, results[k]}});
  }
}

/// The inelastic impulse at an impact, Bridson, Fedkiw, Anderson 2002's response as sec. 3.3 uses it: the
/// relative normal velocity at the contact point becomes a small separating speed, 1% of the cloth thickness
/// per step, so the corrected motion stays on its side instead of ending exactly in the plane.
/// @param thickness  the cloth thickness (unit: m), > 0
void resolve_impact(StepContext& ctx, Index p, const Impact& impact, double thickness) {
  const Triangle& tri = ctx.triangle(impact.triangle);
  const ClothMesh& cloth = ctx.cloth();
  const double t = impact.ccd.toi;
  const Vec3& w = impact.ccd.barycentric;
  const auto at = [&](Index node) {
    return ((1.0 - t) * cloth.positions_t0[node] + t * cloth.positions_t1[node]).eval();
  };
  const Vec3 v = ctx.relative_velocity(p, impact.triangle, w);
  Vec3 normal = (at(tri[1]) - at(tri[0])).cross(at(tri[2]) - at(tri[0]));
  const double length = normal.norm();
  if (length > 0.0 && std::isfinite(length)) {
    normal /= length;
    // Towards the side the particle comes from: the sign of eq. 6 just before the impact (not at the start of
    // the step: the particle may pass the triangle's plane beside the triangle before it hits it, and a fast
    // turning cloth may turn the plane under it).
    const double before = 0.99 * t;
    const auto before_at = [&](const Vec3& x0, const Vec3& x1) {
      return ((1.0 - before) * x0 + before * x1).eval();
    };
    const Vec3 a = before_at(cloth.positions_t0[tri[0]], cloth.positions_t1[tri[0]]);
    const Vec3 b = before_at(cloth.positions_t0[tri[1]], cloth.positions_t1[tri[1]]);
    const Vec3 c = before_at(cloth.positions_t0[tri[2]], cloth.positions_t1[tri[2]]);
    const Vec3 x = before_at(ctx.x0()[p], ctx.x1()[p]);
    const Vec3 n_before = (b - a).cross(c - a);
    const double side = (x - a).dot(n_before) * (n_before.dot(normal) >= 0.0 ? 1.0 : -1.0);
    // A particle in the plane just before (an impact at t = 0, or grazing) keeps the side it comes from.
    if (side < 0.0 || (side == 0.0 && v.dot(normal) > 0.0)) normal = -normal;
  } else {
    normal = v.norm() > 0.0 ? Vec3(-v.normalized()) : Vec3::UnitY();  // zero-area triangle: push back
  }
  const double target = 0.01 * thickness / ctx.dt();
  const double vn = v.dot(normal);
  if (vn >= target) return;
  ctx.apply(p, impact.triangle, w, (target - vn) / ctx.inverse_mass(p, impact.triangle, w) * normal);
}

/// The last resort, when even the fail-safe leaves impacts (a particle between two faces of a fold that move
/// apart cannot follow both): rigid impact zones (Bridson et al. 2002) that translate. Each colliding
/// particle is joined with its triangle's nodes into a zone, zones that collide merge, and every member of a
/// zone moves over the step by the zone's one displacement, so members do not move relative to each other and
/// cannot cross (the start of the step was free of crossings). What then collides with a zone joins it,
/// round after round, until no pair collides. The displacement is the mean of the members' own: of the
/// nodes the coupler sees as kinematic (inverse mass 0) when the zone has any, else mass-weighted over
/// particles and nodes; a zone holding a node that did not move (a pin) stays at rest. Zones at rest stopped
/// a fast cloth's nodes behind their neighbours and overstretched it (the crumpled cloth at dt 4 ms,
/// HostilePhysics.ACrumpledClothAtDt4msDoesNotLeak); moving zones keep the nodes with the cloth. A
/// particle's change of momentum goes to its triangle's nodes (StepContext::place); a kinematic node's move
/// goes to Coupler::node_shifts, for its caller to settle (a carried-water cloth owes it back,
/// owe_zone_shifts; a body's engine ignores it, CouplingStepStats::zone_ignored_shift). A crossing stays only
/// where a member cannot follow its zone (a pinned node moved by its engine).
/// @param all  every pair of the motion on entry (update_pairs), kept so
/// @param only, fresh, merged  scratch
/// @param impacts  the fail-safe's leftover impacts on entry; scratch
/// @return COUPLING_ZONES_STOPPED, with COUPLING_UNRESOLVED when an impact remained (named in `unresolved`)
std::uint32_t move_impact_zones(StepContext& ctx, TriangleBroadPhase& broad_phase,
                                std::vector<std::uint8_t>& only, std::vector<std::pair<Index, Index>>& fresh,
                                std::vector<std::pair<Index, Index>>& all,
                                std::vector<std::pair<Index, Index>>& merged,
                                std::vector<std::pair<Index, Impact>>& impacts,
                                std::pair<std::int64_t, std::int64_t>* unresolved) {
  ClothMesh& cloth = ctx.cloth();
  CouplingStepStats& stats = ctx.stats();
  const std::size_t n = ctx.x0().size();
  // Elements: particle p is p, node i is n + i. parent[e] == e for a root; kNone: not in a zone.
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::vector<std::size_t> parent(n + cloth.node_count(), kNone);
  std::vector<std::size_t> members;
  Vec3Array own;                             // per member: its displacement over the step when it joined (m)
  std::vector<std::pair<Index, Vec3>> link;  // per member particle: the triangle and weights it hit
  const auto root = [&parent](std::size_t e) {
    while (parent[e] != e) {
      parent[e] = parent[parent[e]];
      e = parent[e];
    }
    return e;
  };
  const auto join = [&](std::size_t e, const Vec3& displacement, Index t, const Vec3& w) {
    if (parent[e] != kNone) return false;
    parent[e] = e;
    members.push_back(e);
    own.push_back(displacement);
    link.emplace_back(t, w);
    if (e < n) {
      ++stats.stopped_particles;
    } else {
      ++stats.stopped_nodes;
    }
    return true;
  };
  const auto unite = [&](std::size_t a, std::size_t b) {
    a = root(a);
    b = root(b);
    if (a == b) return false;
    parent[std::max(a, b)] = std::min(a, b);  // the smaller root: the zones' order does not depend on rounds
    return true;
  };
  struct Zone {
    Vec3 kinematic = Vec3::Zero(), weighted = Vec3::Zero();
    double kinematic_count = 0.0, mass = 0.0;
    bool pinned = false;
  };
  std::vector<Zone> zones(parent.size());
  // Every round joins or merges at least one zone (else it ends), so the rounds are bounded by the elements.
  while (!impacts.empty()) {
    bool progress = false;
    for (const auto& [p, impact] : impacts) {
      const Triangle& tri = cloth.triangles[impact.triangle];
      progress |= join(p, ctx.x1()[p] - ctx.x0()[p], impact.triangle, impact.ccd.barycentric);
      for (const Index node : tri) {
        progress |= join(n + node, cloth.positions_t1[node] - cloth.positions_t0[node], 0, Vec3::Zero());
        progress |= unite(p, n + node);
      }
    }
    if (!progress) break;
    for (const std::size_t e : members)
      zones[root(e)] = Zone{};
    for (std::size_t k = 0; k < members.size(); ++k) {
      const std::size_t e = members[k];
      Zone& zone = zones[root(e)];
      if (e < n) {
        zone.weighted += ctx.mass(e) * own[k];
        zone.mass += ctx.mass(e);
      } else if (own[k] == Vec3::Zero()) {
        zone.pinned = true;
      } else if (const double im = cloth.inverse_masses[e - n]; im > 0.0) {
        zone.weighted += own[k] / im;
        zone.mass += 1.0 / im;
      } else {
        zone.kinematic += own[k];
        zone.kinematic_count += 1.0;
      }
    }
    for (std::size_t k = 0; k < members.size(); ++k) {
      const std::size_t e = members[k];
      const Zone& zone = zones[root(e)];
      const Vec3 displacement = zone.pinned                  ? Vec3::Zero()
                                : zone.kinematic_count > 0.0 ? Vec3(zone.kinematic / zone.kinematic_count)
                                                             : Vec3(zone.weighted / zone.mass);
      if (e < n) {
        ctx.place(static_cast<Index>(e), ctx.x0()[e] + displacement, link[k].first, link[k].second);
      } else {
        ctx.move_node(static_cast<Index>(e - n), cloth.positions_t0[e - n] + displacement);
      }
    }
    update_pairs(ctx, broad_phase, only, fresh, all, merged);
    ctx.clear_changes();
    find_impacts(ctx, all, impacts);
  }
  if (impacts.empty()) return COUPLING_ZONES_STOPPED;
  if (unresolved) *unresolved = {impacts.front().first, impacts.front().second.triangle};
  return COUPLING_ZONES_STOPPED | COUPLING_UNRESOLVED;
}

}  // namespace

void update_pairs(StepContext& ctx, TriangleBroadPhase& broad_phase, std::vector<std::uint8_t>& only,
                  std::vector<std::pair<Index, Index>>& fresh, std::vector<std::pair<Index, Index>>& all,
                  std::vector<std::pair<Index, Index>>& merged) {
  ctx.mark_changed_candidates(only);
  broad_phase.find_pairs(ctx.x0(), ctx.x1(), ctx.cloth(), 0.0, &only, fresh);
  merged.clear();
  merged.reserve(all.size() + fresh.size());
  auto next = fresh.begin();
  for (const auto& pair : all) {
    if (only[pair.first]) continue;
    for (; next != fresh.end() && next->first < pair.first; ++next)
      merged.push_back(*next);
    if (!ctx.pair_changed(pair.first, pair.second)) merged.push_back(pair);
  }
  merged.insert(merged.end(), next, fresh.end());
  all.swap(merged);
}

void StepContext::mark_changed_candidates(std::vector<std::uint8_t>& only) const {
  // Most rounds change no node (the fail-safe moves particles only, an impulse on a static face moves
  // nothing): then only the changed particles are marked, without a look at every triangle and particle.
  if (std::find(m_node_changed.begin(), m_node_changed.end(), std::uint8_t{1}) == m_node_changed.end()) {
    only = m_particle_changed;
    return;
  }
  Box3 changed_triangles;
  for (std::size_t t = 0; t < m_cloth.triangles.size(); ++t) {
    const Triangle& tri = m_cloth.triangles[t];
    if (!(m_node_changed[tri[0]] || m_node_changed[tri[1]] || m_node_changed[tri[2]])) continue;
    const Box3 box = triangle_box(m_cloth, tri, 0.0);
    // A box with a NaN overlaps nothing (its pairs are never reported); left out of the union, which it
    // would otherwise poison.
    if ((box.lo.array() <= box.hi.array()).all()) {
      changed_triangles.extend(box.lo);
      changed_triangles.extend(box.hi);
    }
  }
  const std::size_t n = m_x0.size();
  only.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      only[p] = m_particle_changed[p] || particle_box(m_x0[p], m_x1[p], 0.0).overlaps(changed_triangles);
    }
  });
}

std::uint32_t resolve_ccd(StepContext& ctx, TriangleBroadPhase& broad_phase, const CouplingSettings& settings,
                          std::pair<std::int64_t, std::int64_t>* unresolved) {
  if (unresolved) *unresolved = {-1, -1};
  std::uint32_t status = COUPLING_OK;
  ClothMesh& cloth = ctx.cloth();
  CouplingStepStats& stats = ctx.stats();
  const double thickness = settings.cloth_thickness;
  std::vector<std::pair<Index, Index>> all;    // every pair of the motion at the last query
  std::vector<std::pair<Index, Index>> pairs;  // the pairs a round queries
  std::vector<std::pair<Index, Index>> merged;
  std::vector<std::pair<Index, Impact>> impacts;
  std::vector<std::uint8_t> only;
  for (int iteration = 0; iteration <= settings.max_ccd_iterations; ++iteration) {
    // Repulsion changed the motion, so the first round checks every pair; after it, only pairs whose motion
    // changed in the previous round can have a new impact, so the broad phase is asked only for the particles
    // that can be in one, and only the changed pairs are queried.
    if (iteration == 0) {
      broad_phase.find_pairs(ctx.x0(), ctx.x1(), cloth, 0.0, nullptr, all);
    } else {
      update_pairs(ctx, broad_phase, only, pairs, all, merged);
      pairs.erase(
          std::remove_if(pairs.begin(), pairs.end(),
                         [&](const auto& pair) { return !ctx.pair_changed(pair.first, pair.second); }),
          pairs.end());
    }
    ctx.clear_changes();
    ++stats.ccd_iterations;
    find_impacts(ctx, iteration == 0 ? all : pairs, impacts);
    if (impacts.empty()) break;
    if (iteration == settings.max_ccd_iterations) {
      // Fail-safe: the particle follows its triangle's contact point over the step, so that triangle cannot
      // cross it; a last CCD round checks every pair again.
      status |= COUPLING_FAILSAFE_USED;
      for (const auto& [p, impact] : impacts) {
        const Triangle& tri = cloth.triangles[impact.triangle];
        const Vec3& w = impact.ccd.barycentric;
        Vec3 shift = Vec3::Zero();
        for (int i = 0; i < 3; ++i)
          shift += w[i] * (cloth.positions_t1[tri[i]] - cloth.positions_t0[tri[i]]);
        ctx.place(p, ctx.x0()[p] + shift, impact.triangle, w);
        ++stats.failsafe_activations;
      }
      update_pairs(ctx, broad_phase, only, pairs, all, merged);
      ctx.clear_changes();
      find_impacts(ctx, all, impacts);
      if (!impacts.empty())
        status |= move_impact_zones(ctx, broad_phase, only, pairs, all, merged, impacts, unresolved);
      break;
    }
    stats.ccd_impacts += impacts.size();
    for (const auto& [p, impact] : impacts)
      resolve_impact(ctx, p, impact, thickness);
  }
  return status;
}

}  // namespace coupling_detail
}  // namespace drench
