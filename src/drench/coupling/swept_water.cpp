#include <drench/coupling/swept_water.hpp>

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <utility>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>
#include <drench/coupling/broad_phase.hpp>

namespace drench {

std::size_t meet_swept_water(const std::vector<RigidSurface>& surfaces,
                             const std::vector<std::size_t>& first_node, double dt, double rest_density,
                             const Vec3Array& positions, const ScalarArray& masses, Vec3Array& velocities,
                             Vec3Array& node_impulses) {
  assert(first_node.size() == surfaces.size());
  std::size_t swept = 0;
  if (positions.empty()) return swept;
  std::vector<std::pair<Index, Index>> pairs;
  std::vector<ccd::CcdResult> hits;
  std::vector<std::uint8_t> only(positions.size());
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const RigidSurface& surface = surfaces[s];
    if (surface.motion != RigidMotion::DYNAMIC || surface.triangles.empty()) continue;
    if (!(surface.inverse_mass > 0.0)) continue;  // its source gave no mass: infinitely heavy
    // A body ten times heavier than the water it can sweep (no more than its faces' sweep along their normals
    // holds, nor than lies in its box) loses to that water what the coupler's stops give it, to within a
    // tenth of that loss (m / M against m / (M + m)): the sweep is for bodies the water can stop. Sweeping
    // the 3 kg ball that lies in the water of bench_game_frame's hammock kept it stirring, 0.5 ms a frame
    // more; with this test the level's frames are the same bits as without the sweep.
    double volume = 0.0;  // unit: m^3
    const Vec3Array& x0 = surface.positions_t0;
    const Vec3Array& v0 = surface.velocities_t0;
    for (const Triangle& t : surface.triangles) {
      const Vec3 area = 0.5 * (x0[t[1]] - x0[t[0]]).cross(x0[t[2]] - x0[t[0]]);
      volume += std::max(0.0, ((v0[t[0]] + v0[t[1]] + v0[t[2]]) / 3.0).dot(area)) * dt;
    }
    if (!(surface.inverse_mass * rest_density * volume * 10.0 > 1.0)) continue;
    ClothMesh sweep;
    sweep.positions_t0 = x0;
    sweep.positions_t1.resize(x0.size());
    for (std::size_t k = 0; k < x0.size(); ++k)
      sweep.positions_t1[k] = x0[k] + dt * v0[k];
    sweep.triangles = surface.triangles;
    const Box3 box = mesh_box(sweep);
    if (!box.lo.allFinite() || !box.hi.allFinite()) continue;  // the step names a body that is not finite
    // Only the particles in the body's box over the step can be swept: the broad phase looks at those alone.
    double near = 0.0;  // their mass (unit: kg)
    for (std::size_t p = 0; p < positions.size(); ++p) {
      const Vec3& x = positions[p];
      only[p] = (x.array() >= box.lo.array()).all() && (x.array() <= box.hi.array()).all();
      if (only[p]) near += masses[p];
    }
    if (!(surface.inverse_mass * near * 10.0 > 1.0)) continue;
    make_broad_phase(BroadPhaseKind::GRID)->find_pairs(positions, positions, sweep, 0.0, &only, pairs);
    hits.assign(pairs.size(), ccd::CcdResult{});
    parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const auto [p, t] = pairs[k];
        const Triangle& tri = sweep.triangles[t];
        const Vec3Array &a = sweep.positions_t0, &b = sweep.positions_t1;
        if (!positions[p].allFinite()) continue;
        hits[k] = ccd::point_triangle_ccd(
            {positions[p], a[tri[0]], a[tri[1]], a[tri[2]], positions[p], b[tri[0]], b[tri[1]], b[tri[2]]});
      }
    });
    // Per particle (pairs come in particle order) its earliest hit.
    std::vector<std::size_t> first_hit;
    for (std::size_t k = 0; k < pairs.size();) {
      const Index p = pairs[k].first;
      std::size_t best = pairs.size();
      for (; k < pairs.size() && pairs[k].first == p; ++k) {
        if (hits[k].hit && (best == pairs.size() || hits[k].toi < hits[best].toi)) best = k;
      }
      if (best != pairs.size()) first_hit.push_back(best);
    }
    if (first_hit.empty()) continue;
    const double mass = 1.0 / surface.inverse_mass;
    double water = 0.0;
    Vec3 momentum = mass * surface.velocity;
    for (std::size_t k : first_hit) {
      const Index p = pairs[k].first;
      water += masses[p];
      momentum += masses[p] * velocities[p];
    }
    const Vec3 common = momentum / (mass + water);
    for (std::size_t k : first_hit) {
      const auto [p, t] = pairs[k];
      const Vec3 impulse = masses[p] * (common - velocities[p]);
      velocities[p] = common;
      const Triangle& tri = sweep.triangles[t];
      for (int i = 0; i < 3; ++i)
        node_impulses[first_node[s] + tri[i]] -= hits[k].barycentric[i] * impulse;
    }
    swept += first_hit.size();
  }
  return swept;
}

}  // namespace drench
