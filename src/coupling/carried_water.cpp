#include "coupling/carried_water.hpp"

#include <algorithm>
#include <cassert>
#include <utility>

#include "common/triangle_geometry.hpp"

namespace drench {

CarriedWater::CarriedWater(double carry_distance, BroadPhaseKind broad_phase)
    : CarriedWater(carry_distance, make_broad_phase(broad_phase)) {}

CarriedWater::CarriedWater(double carry_distance, std::shared_ptr<TriangleBroadPhase> broad_phase)
    : m_distance(carry_distance), m_broad_phase(std::move(broad_phase)) {
  assert(carry_distance > 0.0 && m_broad_phase);
}

CarriedWater::~CarriedWater() = default;

void CarriedWater::attach(const ClothMesh& cloth, const Vec3Array& positions, const ScalarArray& masses) {
  m_static.positions_t0 = cloth.positions_t0;
  m_static.positions_t1 = cloth.positions_t0;
  m_static.inverse_masses = cloth.inverse_masses;
  m_static.triangles = cloth.triangles;
  m_carried.assign(cloth.node_count(), 0.0);
  m_links.clear();
  if (cloth.triangles.empty() || positions.empty()) return;
  m_broad_phase->find_pairs(positions, positions, m_static, m_distance, nullptr, m_pairs);
  // Distances in parallel, one slot per pair; the choice and the sums in particle order (deterministic).
  std::vector<double> distance(m_pairs.size());
  std::vector<Vec3> weights(m_pairs.size());
  const Vec3Array& x = m_static.positions_t0;
#pragma omp parallel for schedule(dynamic, 256)
  for (std::size_t k = 0; k < m_pairs.size(); ++k) {
    const auto [p, t] = m_pairs[k];
    const Triangle& tri = m_static.triangles[t];
    const Vec3 w = closest_point_barycentric(positions[p], x[tri[0]], x[tri[1]], x[tri[2]]);
    weights[k] = w;
    distance[k] = (positions[p] - (w[0] * x[tri[0]] + w[1] * x[tri[1]] + w[2] * x[tri[2]])).norm();
  }
  for (std::size_t k = 0; k < m_pairs.size();) {
    const Index p = m_pairs[k].first;
    std::size_t best = m_pairs.size();
    for (; k < m_pairs.size() && m_pairs[k].first == p; ++k) {
      if (distance[k] <= m_distance && (best == m_pairs.size() || distance[k] < distance[best])) best = k;
    }
    if (best == m_pairs.size()) continue;
    const Triangle& tri = m_static.triangles[m_pairs[best].second];
    bool carried = false;
    for (int i = 0; i < 3; ++i) {
      if (m_static.inverse_masses[tri[i]] > 0.0 && weights[best][i] > 0.0) {
        m_carried[tri[i]] += weights[best][i] * masses[p];
        carried = true;
      }
    }
    if (carried) m_links.push_back({p, m_pairs[best].second, weights[best]});
  }
}

Vec3 CarriedWater::hand_back(const Vec3Array& velocities_before, const Vec3Array& velocities_end,
                             const ClothMesh& cloth, double dt, Vec3Array& positions,
                             Vec3Array& particle_velocities, const ScalarArray& masses) const {
  Vec3 given = Vec3::Zero();
  for (const Link& link : m_links) {
    const Triangle& tri = cloth.triangles[link.triangle];
    Vec3 dv = Vec3::Zero();
    for (int i = 0; i < 3; ++i) {
      if (cloth.inverse_masses[tri[i]] > 0.0)
        dv += link.weights[i] * (velocities_end[tri[i]] - velocities_before[tri[i]]);
    }
    const Index p = link.particle;
    particle_velocities[p] += dv;
    positions[p] += dt * dv;
    given += masses[p] * dv;
  }
  return given;
}

}  // namespace drench
