// Continuous intersection handling (Huber et al. 2013 sec. 3.3, eq. 5-6): rounds of point-triangle CCD on
// the corrected motion, an inelastic impulse at each particle's earliest impact, and the fail-safe.
// resolve_ccd is declared and documented in coupler_stages.hpp.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/SVD>

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

using Pairs = std::vector<std::pair<Index, Index>>;

/// The pairs whose CCD query hits, with the answer, sorted by particle, then triangle.
using PairHits = std::vector<std::pair<std::pair<Index, Index>, ccd::CcdResult>>;

/// Queries every pair of `pairs` (in parallel, each answer in its own slot) and replaces `hits` with those
/// that hit, in the order of `pairs`.
void query_hits(const StepContext& ctx, const Pairs& pairs, PairHits& hits) {
  std::vector<ccd::CcdResult> results(pairs.size());
  parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      results[k] = ccd::point_triangle_ccd(ctx.query(pairs[k].first, pairs[k].second));
  });
  hits.clear();
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (results[k].hit) hits.emplace_back(pairs[k], results[k]);
  }
}

/// Earliest impact per particle among `hits` (the reduction, in pair order).
/// @param hits  sorted by particle, then triangle
/// @param impacts  output, replaced: (particle, impact) in particle order, one per particle that hits
void earliest_impacts(const StepContext& ctx, const PairHits& hits,
                      std::vector<std::pair<Index, Impact>>& impacts) {
  impacts.clear();
  for (const auto& [pair, result] : hits) {
    const Index p = pair.first;
    if (ctx.squeezed_out(p)) continue;
    // A particle that starts exactly in the triangle (distance 0: it has no side yet) touches at t = 0
    // whatever it does next; pushing it would flip it back and forth. Repulsion handles it. Anything else at
    // toi = 0 may be a contact just after the start (toi is a lower bound) and is resolved.
    if (result.toi == 0.0 && ccd::coplanarity_sign_exact(ctx.query(p, pair.second), false) == 0) continue;
    if (!impacts.empty() && impacts.back().first == p) {
      // One impact per particle: the earliest; a hit through a shared edge or vertex is handled once.
      if (result.toi < impacts.back().second.ccd.toi) impacts.back().second = {pair.second, result};
      continue;
    }
    impacts.push_back({p, {pair.second, result}});
  }
}

/// Every pair's CCD answer under the current motion, kept from round to round: a round that needs the
/// impacts of every pair (the fail-safe's check, each impact-zone round) queries only the pairs whose
/// particle or nodes moved since the last query. The others have the same query, so the same answer
/// (point_triangle_ccd is a function of its query), so the impacts are those of a query of every pair, bit
/// for bit, at the cost of the changed ones: querying every pair again there was 0.43 G of the 1.05 G
/// instructions of CCD queries in bench_game_frame's level (callgrind, 300 frames), where 43% of the frames
/// reach the fail-safe.
class KnownHits {
 public:
  /// Answers for every pair of `all` (round 0).
  void query_all(const StepContext& ctx, const Pairs& all) { query_hits(ctx, all, m_known); }

  /// After update_pairs and before clear_changes: keeps in `fresh` only the pairs whose motion changed,
  /// queries them, puts their hits in round_hits() and brings the known hits to the current motion.
  /// @param fresh  the pairs update_pairs returned (every changed pair of `all` is among them)
  void query_changed(const StepContext& ctx, Pairs& fresh) {
    fresh.erase(std::remove_if(fresh.begin(), fresh.end(),
                               [&](const auto& pair) { return !ctx.pair_changed(pair.first, pair.second); }),
                fresh.end());
    query_hits(ctx, fresh, m_round);
    m_known.erase(
        std::remove_if(m_known.begin(), m_known.end(),
                       [&](const auto& hit) { return ctx.pair_changed(hit.first.first, hit.first.second); }),
        m_known.end());
    m_merged.clear();
    m_merged.reserve(m_known.size() + m_round.size());
    std::merge(m_known.begin(), m_known.end(), m_round.begin(), m_round.end(), std::back_inserter(m_merged),
               [](const auto& a, const auto& b) { return a.first < b.first; });
    m_known.swap(m_merged);
  }

  /// The hits of every pair of `all` under the current motion, sorted by pair.
  const PairHits& known() const { return m_known; }
  /// The hits among the pairs the last query_changed queried.
  const PairHits& round_hits() const { return m_round; }

 private:
  PairHits m_known, m_round, m_merged;
};

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

using Mat3 = Eigen::Matrix3d;

/// One motion of a zone's members over the step: x_t1 = rotation (x_t0 - from) + to. A translation has the
/// identity rotation.
struct ZoneMotion {
  Mat3 rotation = Mat3::Identity();
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Vec3 operator()(const Vec3& x_t0) const { return rotation * (x_t0 - from) + to; }
};

/// The one rigid motion that takes the start positions `x0` to the end positions `x1` (Kabsch's fit: the
/// rotation about the centroids that best maps one onto the other, without a reflection), or nullopt when
/// no rigid motion brings every point within `tolerance` (unit: m) of its end: nodes of two bodies, or of a
/// body and the ground, that move differently. Points that all move by one displacement are a translation,
/// exactly.
std::optional<ZoneMotion> rigid_motion(const Vec3Array& x0, const Vec3Array& x1, double tolerance) {
  ZoneMotion motion;
  const Vec3 shift = x1.front() - x0.front();
  bool translation = true;
  for (std::size_t i = 1; i < x0.size() && translation; ++i)
    translation = x1[i] - x0[i] == shift;
  if (translation) {
    motion.to = shift;  // x_t0 + shift: a zone at rest ends exactly where it started
    return motion;
  }
  for (std::size_t i = 0; i < x0.size(); ++i) {
    motion.from += x0[i];
    motion.to += x1[i];
  }
  motion.from /= static_cast<double>(x0.size());
  motion.to /= static_cast<double>(x0.size());
  Mat3 covariance = Mat3::Zero();
  for (std::size_t i = 0; i < x0.size(); ++i)
    covariance += (x1[i] - motion.to) * (x0[i] - motion.from).transpose();
  const Eigen::JacobiSVD<Mat3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 sign = Mat3::Identity();
  sign(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  motion.rotation = svd.matrixU() * sign * svd.matrixV().transpose();
  for (std::size_t i = 0; i < x0.size(); ++i) {
    if (!((motion(x0[i]) - x1[i]).norm() <= tolerance)) return std::nullopt;
  }
  return motion;
}

/// The last resort, when even the fail-safe leaves impacts (a particle between two faces of a fold that move
/// apart cannot follow both): rigid impact zones (Bridson et al. 2002). Each colliding particle is joined
/// with its triangle's nodes into a zone, zones that collide merge, and every member of a zone moves over
/// the step by the zone's one motion, so members do not move relative to each other and cannot cross (the
/// start of the step was free of crossings; a motion that is the same affine map for every member keeps
/// each point on its side of each face). What then collides with a zone joins it, round after round, until
/// no pair collides.
/// The motion takes the fixed nodes' as given: a node whose engine ignores a move (inverse mass 0 as its
/// engine holds it: a rigid body's, an obstacle's, a pin's) ends exactly where it was given, since water
/// placed against a face its engine puts elsewhere is inside the body at the next step (the leak audit's
/// audit_face_jumps). A zone whose fixed nodes share one rigid motion (one body, turning or not; bodies at
/// rest together) gives that motion to its other members, as if they were stuck to the body. A zone without
/// fixed nodes moves by one displacement: the mean of the displacements of the nodes the coupler sees as
/// kinematic (a carried-water cloth's) when it has any, else mass-weighted over particles and nodes. Zones
/// at rest stopped a fast cloth's nodes behind their neighbours and overstretched it (the crumpled cloth at
/// dt 4 ms, HostilePhysics.ACrumpledClothAtDt4msDoesNotLeak); moving with the cloth keeps the nodes with it.
/// Where the fixed nodes of a zone move differently (water squeezed between a falling box and the ground),
/// no motion serves both: the zone's particles that hit a face with a fixed node are squeezed out, removed
/// with their mass and momentum booked (StepContext::squeeze_out), and the zones are formed again without
/// them, so the water that only touched the cloth keeps a motion (squeezing out the whole zone removed far
/// more water in bench_game_frame's level). A node left alone
/// goes back where it was given. A particle outside the zones that hits a face only because a zone moved its
/// nodes is carried by that move at the point it hits, booked as the fail-safe books its move, and joins
/// only if it still hits. A particle's change of momentum goes to its triangle's
/// nodes (StepContext::place); a carried-water cloth's node moved by its zone goes to Coupler::node_shifts,
/// for its caller to settle (owe_zone_shifts). A crossing stays only where no round makes progress
/// (COUPLING_UNRESOLVED).
/// @param all  every pair of the motion on entry (update_pairs), kept so
/// @param known  the hits of every pair of `all` on entry, kept so
/// @param only, fresh, merged  scratch
/// @param impacts  the fail-safe's leftover impacts on entry; scratch
/// @param tolerance  how far a fixed node may be from a rigid motion that takes it as given (unit: m), > 0
/// @return COUPLING_ZONES_STOPPED, with COUPLING_UNRESOLVED when an impact remained (named in `unresolved`)
std::uint32_t move_impact_zones(StepContext& ctx, TriangleBroadPhase& broad_phase,
                                std::vector<std::uint8_t>& only, std::vector<std::pair<Index, Index>>& fresh,
                                std::vector<std::pair<Index, Index>>& all,
                                std::vector<std::pair<Index, Index>>& merged, KnownHits& known,
                                std::vector<std::pair<Index, Impact>>& impacts, double tolerance,
                                std::pair<std::int64_t, std::int64_t>* unresolved) {
  ClothMesh& cloth = ctx.cloth();
  CouplingStepStats& stats = ctx.stats();
  const std::size_t n = ctx.x0().size();
  // Elements: particle p is p, node i is n + i. index[e]: e's place in `members`, or kNone.
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::vector<std::size_t> index(n + cloth.node_count(), kNone);
  std::vector<std::size_t> members;
  Vec3Array given;                             // per member: its end position when it joined (m)
  std::vector<std::pair<Index, Vec3>> link;    // per member particle: the triangle and weights it hit first
  std::vector<std::pair<Index, Index>> edges;  // (particle, triangle) of every impact that joined zones
  std::vector<std::size_t> parent;             // per member: union-find over members, rebuilt each round
  const auto root = [&parent](std::size_t k) {
    while (parent[k] != k) {
      parent[k] = parent[parent[k]];
      k = parent[k];
    }
    return k;
  };
  const auto unite = [&](std::size_t a, std::size_t b) {
    a = root(a);
    b = root(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the zones' order does not depend on rounds
  };
  const auto join = [&](std::size_t e, const Vec3& end, Index t, const Vec3& w) {
    if (index[e] != kNone) return false;
    index[e] = members.size();
    members.push_back(e);
    given.push_back(end);
    link.emplace_back(t, w);
    if (e < n) {
      ++stats.stopped_particles;
    } else {
      ++stats.stopped_nodes;
    }
    return true;
  };
  const auto start_of = [&](std::size_t e) { return e < n ? ctx.x0()[e] : cloth.positions_t0[e - n]; };
  // Every pair's impacts under the motion as the round left it, querying only the changed pairs.
  const auto impacts_now = [&] {
    update_pairs(ctx, broad_phase, only, fresh, all, merged);
    known.query_changed(ctx, fresh);
    ctx.clear_changes();
    earliest_impacts(ctx, known.known(), impacts);
  };
  struct Zone {
    Vec3 kinematic = Vec3::Zero(), weighted = Vec3::Zero();
    double kinematic_count = 0.0, mass = 0.0;
    std::size_t size = 0;
    Vec3Array fixed_t0, fixed_t1;
    std::optional<ZoneMotion> motion;
  };
  std::vector<Zone> zones;
  // Per node: how far the zones moved its end this round (unit: m); `shifted` lists the nodes with a move.
  Vec3Array zone_move(cloth.node_count(), Vec3::Zero());
  std::vector<Index> shifted;
  // Every round adds a member or an edge (else it ends), so the rounds are bounded by the pairs.
  while (!impacts.empty()) {
    bool progress = false;
    for (const auto& [p, impact] : impacts) {
      const Triangle& tri = cloth.triangles[impact.triangle];
      progress |= join(p, ctx.x1()[p], impact.triangle, impact.ccd.barycentric);
      for (const Index node : tri)
        progress |= join(n + node, cloth.positions_t1[node], 0, Vec3::Zero());
      const std::pair<Index, Index> edge(p, impact.triangle);
      const auto at = std::lower_bound(edges.begin(), edges.end(), edge);
      if (at == edges.end() || *at != edge) {
        edges.insert(at, edge);
        progress = true;
      }
    }
    if (!progress) break;
    // The zones, and their motions; a zone whose fixed nodes move differently loses its particles against
    // a fixed face, which may split it, so the zones are formed again until every one has a motion.
    for (bool squeezed = true; squeezed;) {
      squeezed = false;
      parent.resize(members.size());
      for (std::size_t k = 0; k < members.size(); ++k)
        parent[k] = k;
      for (const auto& [p, t] : edges) {
        if (ctx.squeezed_out(p)) continue;
        for (const Index node : cloth.triangles[t])
          unite(index[p], index[n + node]);
      }
      zones.assign(members.size(), Zone{});
      for (std::size_t k = 0; k < members.size(); ++k) {
        const std::size_t e = members[k];
        if (e < n && ctx.squeezed_out(static_cast<Index>(e))) continue;
        Zone& zone = zones[root(k)];
        ++zone.size;
        const Vec3 own = given[k] - start_of(e);
        if (e < n) {
          zone.weighted += ctx.mass(e) * own;
          zone.mass += ctx.mass(e);
        } else if (ctx.fixed(static_cast<Index>(e - n))) {
          zone.fixed_t0.push_back(start_of(e));
          zone.fixed_t1.push_back(given[k]);
        } else if (const double im = cloth.inverse_masses[e - n]; im > 0.0) {
          zone.weighted += own / im;
          zone.mass += 1.0 / im;
        } else {
          zone.kinematic += own;
          zone.kinematic_count += 1.0;
        }
      }
      for (std::size_t k = 0; k < members.size(); ++k) {
        if (root(k) != k) continue;
        Zone& zone = zones[k];
        if (zone.fixed_t0.empty()) {
          const Vec3 shift = zone.kinematic_count > 0.0 ? Vec3(zone.kinematic / zone.kinematic_count)
                             : zone.mass > 0.0          ? Vec3(zone.weighted / zone.mass)
                                                        : Vec3::Zero();
          zone.motion = ZoneMotion{Mat3::Identity(), Vec3::Zero(), shift};
          continue;
        }
        zone.motion = rigid_motion(zone.fixed_t0, zone.fixed_t1, tolerance);
        if (zone.motion) continue;
        // Only the particles against a fixed face: the rest of the zone (water on the cloth) may then split
        // off with one fixed motion, or none.
        for (const auto& [p, t] : edges) {
          const Triangle& tri = cloth.triangles[t];
          if (ctx.squeezed_out(p) || root(index[p]) != k ||
              !(ctx.fixed(tri[0]) || ctx.fixed(tri[1]) || ctx.fixed(tri[2]))) {
            continue;
          }
          ctx.squeeze_out(p);
          squeezed = true;
        }
      }
    }
    for (std::size_t k = 0; k < members.size(); ++k) {
      const std::size_t e = members[k];
      if (e < n && ctx.squeezed_out(static_cast<Index>(e))) continue;
      if (e >= n && ctx.fixed(static_cast<Index>(e - n))) continue;  // never moved: where it was given
      const Zone& zone = zones[root(k)];
      // A node left alone when its zone lost its particles goes back where it was given.
      const Vec3 end = zone.size == 1 || !zone.motion ? given[k] : (*zone.motion)(start_of(e));
      if (e < n) {
        ctx.place(static_cast<Index>(e), end, link[k].first, link[k].second);
      } else {
        const Index node = static_cast<Index>(e - n);
        const Vec3 shift = end - cloth.positions_t1[node];
        if (shift != Vec3::Zero()) {
          if (zone_move[node] == Vec3::Zero()) shifted.push_back(node);
          zone_move[node] += shift;
        }
        ctx.move_node(node, end);
      }
    }
    impacts_now();
    if (shifted.empty()) continue;
    // A particle outside the zones that now hits a face whose nodes a zone just moved is carried by the
    // face's move at the point it hits, as the fail-safe carries one, and joins only if it still hits: water
    // resting on a cloth ends within 1% of the thickness of its faces, so joining it let the zones grow
    // through a whole pool (between a ball and the hammock of bench_game_frame's level). A later round that
    // moves the face back leaves the particle where it was carried: no crossing, at most the zone's move too
    // far; following the face in every round squeezed water out there again.
    bool carried = false;
    for (const auto& [p, impact] : impacts) {
      if (index[p] != kNone) continue;
      const Triangle& tri = cloth.triangles[impact.triangle];
      const Vec3& w = impact.ccd.barycentric;
      const Vec3 shift = w[0] * zone_move[tri[0]] + w[1] * zone_move[tri[1]] + w[2] * zone_move[tri[2]];
      if (shift == Vec3::Zero()) continue;
      ctx.place(p, ctx.x1()[p] + shift, impact.triangle, w, /*owe=*/true);
      ++stats.carried_by_zones;
      carried = true;
    }
    for (const Index node : shifted)
      zone_move[node] = Vec3::Zero();
    shifted.clear();
    if (!carried) continue;
    impacts_now();
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
  // The pairs of unmarked particles are copied in stretches up to the next marked particle's, all of them
  // when no node changed: a test per pair was twice the merge's instructions in bench_game_frame's level,
  // where a round marks about 36 of 3,000 particles and `all` holds about 1,700 pairs (callgrind).
  const bool nodes_changed = ctx.nodes_changed();
  auto next = fresh.begin();
  std::size_t k = 0;
  while (k < all.size()) {
    const Index p = all[k].first;
    if (next != fresh.end() && next->first < p) {
      merged.push_back(*next++);
      continue;
    }
    if (only[p]) {
      ++k;
      continue;
    }
    // Up to the next pair of a marked particle or of one after the next fresh pair's (all marked).
    std::size_t end = k + 1;
    while (end < all.size() && (next == fresh.end() || all[end].first < next->first) && !only[all[end].first])
      ++end;
    if (nodes_changed) {
      for (std::size_t j = k; j < end; ++j) {
        if (!ctx.pair_changed(all[j].first, all[j].second)) merged.push_back(all[j]);
      }
    } else {
      merged.insert(merged.end(), all.begin() + static_cast<std::ptrdiff_t>(k),
                    all.begin() + static_cast<std::ptrdiff_t>(end));
    }
    k = end;
  }
  merged.insert(merged.end(), next, fresh.end());
  all.swap(merged);
}

void StepContext::mark_changed_candidates(std::vector<std::uint8_t>& only) const {
  // Most rounds change no node (the fail-safe moves particles only, an impulse on a static face moves
  // nothing): then only the changed particles are marked, without a look at every triangle and particle.
  if (!nodes_changed()) {
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
  KnownHits known;
  for (int iteration = 0; iteration <= settings.max_ccd_iterations; ++iteration) {
    // Repulsion changed the motion, so the first round checks every pair; after it, only pairs whose motion
    // changed in the previous round can have a new impact, so the broad phase is asked only for the particles
    // that can be in one, and only the changed pairs are queried.
    if (iteration == 0) {
      broad_phase.find_pairs(ctx.x0(), ctx.x1(), cloth, 0.0, nullptr, all);
      known.query_all(ctx, all);
    } else {
      update_pairs(ctx, broad_phase, only, pairs, all, merged);
      known.query_changed(ctx, pairs);
    }
    ctx.clear_changes();
    ++stats.ccd_iterations;
    earliest_impacts(ctx, iteration == 0 ? known.known() : known.round_hits(), impacts);
    if (impacts.empty()) break;
    if (iteration == settings.max_ccd_iterations) {
      // Fail-safe: the particle follows its triangle's contact point over the step, so that triangle cannot
      // cross it; a last CCD round checks every pair again (the unchanged ones by their known answers).
      status |= COUPLING_FAILSAFE_USED;
      for (const auto& [p, impact] : impacts) {
        const Triangle& tri = cloth.triangles[impact.triangle];
        const Vec3& w = impact.ccd.barycentric;
        Vec3 shift = Vec3::Zero();
        for (int i = 0; i < 3; ++i)
          shift += w[i] * (cloth.positions_t1[tri[i]] - cloth.positions_t0[tri[i]]);
        ctx.place(p, ctx.x0()[p] + shift, impact.triangle, w, /*owe=*/true);
        ++stats.failsafe_activations;
      }
      update_pairs(ctx, broad_phase, only, pairs, all, merged);
      known.query_changed(ctx, pairs);
      ctx.clear_changes();
      earliest_impacts(ctx, known.known(), impacts);
      if (!impacts.empty())
        status |= move_impact_zones(ctx, broad_phase, only, pairs, all, merged, known, impacts,
                                    1e-3 * thickness, unresolved);
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
