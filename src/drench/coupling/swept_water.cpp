#include <drench/coupling/swept_water.hpp>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>
#include <drench/coupling/broad_phase.hpp>

namespace drench {

namespace {

/// Weights alpha_k, one per node, summing to 1 with sum alpha_k (x_k - centre) = 0, the least in sum of
/// squares: an impulse J spread as alpha_k J over the nodes is J at the centre, with no torque about it.
ScalarArray central_weights(const Vec3Array& x, const Vec3& centre) {
  Eigen::Matrix4d g = Eigen::Matrix4d::Zero();
  for (const Vec3& xk : x) {
    const Eigen::Vector4d a(1.0, xk.x() - centre.x(), xk.y() - centre.y(), xk.z() - centre.z());
    g += a * a.transpose();
  }
  // Rank 3 for a flat body, whose centre lies in its plane: the least-norm solution still holds it.
  const Eigen::Vector4d y = g.completeOrthogonalDecomposition().solve(Eigen::Vector4d(1.0, 0.0, 0.0, 0.0));
  ScalarArray alpha(x.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    alpha[k] = y[0] + y.tail<3>().dot(x[k] - centre);
  return alpha;
}

}  // namespace

std::size_t meet_swept_water(std::vector<RigidSurface>& surfaces, const std::vector<std::size_t>& first_node,
                             std::size_t node_count, double dt, double rest_density,
                             const Vec3Array& positions, const ScalarArray& masses, Vec3Array& velocities,
                             Vec3Array& node_impulses) {
  if (first_node.size() != surfaces.size() || masses.size() != positions.size() ||
      velocities.size() != positions.size()) {
    throw std::invalid_argument("meet_swept_water: " + std::to_string(surfaces.size()) + " surfaces, " +
                                std::to_string(first_node.size()) + " first nodes, " +
                                std::to_string(positions.size()) + " positions, " +
                                std::to_string(masses.size()) + " masses, " +
                                std::to_string(velocities.size()) + " velocities");
  }
  node_impulses.clear();
  std::size_t swept = 0;
  std::vector<std::pair<Index, Index>> pairs;
  std::vector<ccd::CcdResult> hits;
  std::vector<std::uint8_t> only;
  Vec3Array ends;  // each particle where its velocity takes it over the step
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    RigidSurface& surface = surfaces[s];
    const Vec3Array& x0 = surface.positions_t0;
    const Vec3 velocity = surface.velocity;
    if (surface.motion != RigidMotion::DYNAMIC || surface.triangles.empty() || x0.empty()) continue;
    if (!(surface.inverse_mass > 0.0) || !velocity.allFinite()) continue;  // no mass: infinitely heavy
    if (first_node[s] + x0.size() > node_count) {
      throw std::invalid_argument("meet_swept_water: surface " + std::to_string(s) + " ends past node " +
                                  std::to_string(node_count));
    }
    // Its translation sweeps the water; its spin is left to the coupler, which moves the water with the
    // faces' own velocities. A body ten times heavier than the water it can sweep (no more than its faces'
    // sweep holds, nor than lies in its way) loses to that water what the coupler's stops give it, to within
    // a tenth of that loss (m / M against m / (M + m)): the sweep is for bodies the water can stop. Sweeping
    // the 3 kg ball that lies in the water of bench_game_frame's hammock kept it stirring, 0.5 ms a frame
    // more; with this test the level's frames are the same bits as without the sweep.
    double volume = 0.0;  // unit: m^3
    for (const Triangle& t : surface.triangles)
      volume += std::max(0.0, velocity.dot(0.5 * (x0[t[1]] - x0[t[0]]).cross(x0[t[2]] - x0[t[0]]))) * dt;
    if (!(surface.inverse_mass * rest_density * volume * 10.0 > 1.0)) continue;
    ClothMesh sweep;
    sweep.positions_t0 = x0;
    sweep.positions_t1.resize(x0.size());
    for (std::size_t k = 0; k < x0.size(); ++k)
      sweep.positions_t1[k] = x0[k] + dt * velocity;
    sweep.triangles = surface.triangles;
    const Box3 box = mesh_box(sweep);
    if (!box.lo.allFinite() || !box.hi.allFinite()) continue;  // the step names a body that is not finite
    if (ends.empty()) {
      ends.resize(positions.size());
      for (std::size_t p = 0; p < positions.size(); ++p)
        ends[p] = positions[p] + dt * velocities[p];
      only.resize(positions.size());
    }
    // The water moves too: a particle that runs ahead of a face faster than it is not met. Only those whose
    // motion's box meets the body's are asked for, and only finite ones (the step names the others).
    double near = 0.0;  // their mass (unit: kg)
    for (std::size_t p = 0; p < positions.size(); ++p) {
      const Vec3 lo = positions[p].cwiseMin(ends[p]), hi = positions[p].cwiseMax(ends[p]);
      only[p] = ends[p].allFinite() && positions[p].allFinite() && (hi.array() >= box.lo.array()).all() &&
                (lo.array() <= box.hi.array()).all();
      if (only[p]) near += masses[p];
    }
    if (!(surface.inverse_mass * near * 10.0 > 1.0)) continue;
    make_broad_phase(BroadPhaseKind::GRID)->find_pairs(positions, ends, sweep, 0.0, &only, pairs);
    hits.assign(pairs.size(), ccd::CcdResult{});
    parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const auto [p, t] = pairs[k];
        const Triangle& tri = sweep.triangles[t];
        const Vec3Array &a = sweep.positions_t0, &b = sweep.positions_t1;
        hits[k] = ccd::point_triangle_ccd(
            {positions[p], a[tri[0]], a[tri[1]], a[tri[2]], ends[p], b[tri[0]], b[tri[1]], b[tri[2]]});
      }
    });
    // Per particle (pairs come in particle order) whether a face meets it.
    std::vector<Index> met;
    for (std::size_t k = 0; k < pairs.size();) {
      const Index p = pairs[k].first;
      bool hit = false;
      for (; k < pairs.size() && pairs[k].first == p; ++k)
        hit = hit || hits[k].hit;
      if (hit) met.push_back(p);
    }
    if (met.empty()) continue;
    const double mass = 1.0 / surface.inverse_mass;
    double water = 0.0;
    Vec3 momentum = mass * velocity;
    for (const Index p : met) {
      water += masses[p];
      momentum += masses[p] * velocities[p];
    }
    const Vec3 common = momentum / (mass + water);
    // The water's impulses, summed, reach the body at its centre: a torque from where each particle met it
    // would make the collision gain energy (a light rod that meets its own mass of water at one end would
    // leave spinning with an eighth more energy than it had).
    Vec3 given = Vec3::Zero();
    for (const Index p : met) {
      given += masses[p] * (common - velocities[p]);
      velocities[p] = common;
    }
    if (node_impulses.empty()) node_impulses.assign(node_count, Vec3::Zero());
    const ScalarArray alpha = central_weights(x0, surface.centre);
    for (std::size_t k = 0; k < x0.size(); ++k)
      node_impulses[first_node[s] + k] -= alpha[k] * given;
    // The rest of the step sees the body as it will move: the sub-step obstacle stops water against its
    // faces at these velocities.
    for (Vec3& v : surface.velocities_t0)
      v += common - velocity;
    surface.velocity = common;
    swept += met.size();
  }
  return swept;
}

}  // namespace drench
