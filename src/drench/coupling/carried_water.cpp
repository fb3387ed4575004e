#include <drench/coupling/carried_water.hpp>

namespace drench {

void CarriedWater::attach(const ClothMesh& cloth, const ScalarArray& masses,
                          const std::vector<std::uint32_t>& ids, const ImpulseLinks& links) {
  m_carried.assign(cloth.node_count(), 0.0);
  m_links.clear();
  if (links.empty() || ids.empty()) return;
  const std::size_t n = ids.size();
  // Each link's particle is found by its id in a hashed table, not by sorting the links by id: a particle's
  // links are scattered over the step's sub-steps and its ids come in z-order, and std::sort of the
  // step's links was most of the carried water's cost (callgrind of bench_game_frame, issue 41).
  m_ids.build(std::vector<std::uint64_t>(ids.begin(), ids.end()));
  m_best.assign(n, nullptr);
  keep_largest_links(links, cloth.triangle_count(), m_ids, m_best);
  // In particle order, so that the sums per node do not depend on the links' order.
  for (std::size_t p = 0; p < n; ++p) {
    if (!m_best[p]) continue;
    const ImpulseLink& link = *m_best[p];
    const Triangle& tri = cloth.triangles[link.triangle];
    bool carried = false;
    for (int i = 0; i < 3; ++i) {
      if (cloth.inverse_masses[tri[i]] > 0.0 && link.weights[i] > 0.0) {
        m_carried[tri[i]] += link.weights[i] * masses[p];
        carried = true;
      }
    }
    if (carried) m_links.push_back({static_cast<Index>(p), link.triangle, link.weights});
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

void owe_zone_shifts(const Vec3Array& shifts, const ScalarArray& inverse_masses, double dt, Vec3Array& owed,
                     CouplingStepStats& stats) {
  for (std::size_t i = 0; i < shifts.size(); ++i) {
    if (shifts[i] == Vec3::Zero()) continue;
    if (inverse_masses[i] > 0.0) {
      const Vec3 momentum = shifts[i] / (inverse_masses[i] * dt);
      owed[i] -= momentum;
      stats.zone_cloth_momentum += momentum.norm();
    } else {
      stats.zone_ignored_shift += shifts[i].norm();
    }
  }
}

}  // namespace drench
