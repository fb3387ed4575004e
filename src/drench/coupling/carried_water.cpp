#include <drench/coupling/carried_water.hpp>

#include <algorithm>

namespace drench {

void CarriedWater::attach(const ClothMesh& cloth, const ScalarArray& masses,
                          const std::vector<std::uint32_t>& ids, ImpulseLinks links) {
  m_carried.assign(cloth.node_count(), 0.0);
  m_links.clear();
  links.erase(std::remove_if(links.begin(), links.end(),
                             [&](const ImpulseLink& l) { return l.triangle >= cloth.triangle_count(); }),
              links.end());
  if (links.empty() || ids.empty()) return;
  // One link per particle id: its largest impulse (ties: the lower triangle index), so the order of the
  // links given does not matter.
  std::sort(links.begin(), links.end(), [](const ImpulseLink& a, const ImpulseLink& b) {
    if (a.particle_id != b.particle_id) return a.particle_id < b.particle_id;
    if (a.impulse != b.impulse) return a.impulse > b.impulse;
    return a.triangle < b.triangle;
  });
  links.erase(
      std::unique(links.begin(), links.end(),
                  [](const ImpulseLink& a, const ImpulseLink& b) { return a.particle_id == b.particle_id; }),
      links.end());
  // In particle order, so that the sums per node do not depend on the links' order.
  for (std::size_t p = 0; p < ids.size(); ++p) {
    const auto link =
        std::lower_bound(links.begin(), links.end(), ids[p],
                         [](const ImpulseLink& l, std::uint32_t id) { return l.particle_id < id; });
    if (link == links.end() || link->particle_id != ids[p] || link->triangle >= cloth.triangle_count())
      continue;
    const Triangle& tri = cloth.triangles[link->triangle];
    bool carried = false;
    for (int i = 0; i < 3; ++i) {
      if (cloth.inverse_masses[tri[i]] > 0.0 && link->weights[i] > 0.0) {
        m_carried[tri[i]] += link->weights[i] * masses[p];
        carried = true;
      }
    }
    if (carried) m_links.push_back({static_cast<Index>(p), link->triangle, link->weights});
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
