#include <drench/coupling/cloth_obstacle.hpp>

#include <cassert>
#include <cmath>
#include <utility>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>

namespace drench {

ClothObstacle::ClothObstacle(double thickness, BroadPhaseKind broad_phase, bool kinematic_cloth)
    : m_thickness(thickness),
      m_kinematic_cloth(kinematic_cloth),
      m_broad_phase(make_broad_phase(broad_phase)) {
  m_counter.constructed = 1;
}

void ClothObstacle::begin_step(const ClothMesh& cloth, const Vec3Array& velocities) {
  m_static.positions_t0 = cloth.positions_t0;
  m_static.positions_t1 = cloth.positions_t0;  // not moving
  m_static.inverse_masses.assign(cloth.node_count(), 0.0);
  m_static.triangles = cloth.triangles;
  m_box = mesh_box(m_static);
  if (m_kinematic_cloth) {
    m_inverse_masses.assign(cloth.node_count(), 0.0);
  } else {
    m_inverse_masses = cloth.inverse_masses;
  }
  m_node_velocities = velocities;
  m_node_impulses.assign(cloth.node_count(), Vec3::Zero());
  m_impulse_links.clear();
  m_stops = 0;
}

void ClothObstacle::apply(const Vec3Array& positions_before, ParticleSet& particles, Scalar dt) {
  // The query below has margin 0: a pair needs a particle box meeting a triangle's, inside m_box.
  if (m_static.triangles.empty() || particles.empty() ||
      !any_particle_box_overlaps(positions_before, particles.positions, 0.0, m_box)) {
    ++m_counter.skipped;
    return;
  }
  ++m_counter.passes;
  m_broad_phase->find_pairs(positions_before, particles.positions, m_static, 0.0, nullptr, m_pairs);
  std::vector<ccd::CcdResult> hits(m_pairs.size());
  parallel_for(m_pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const auto [p, t] = m_pairs[k];
      const Triangle& tri = m_static.triangles[t];
      const Vec3Array& x = m_static.positions_t0;
      hits[k] = ccd::point_static_triangle_ccd(positions_before[p], particles.positions[p], x[tri[0]],
                                               x[tri[1]], x[tri[2]]);
    }
  });
  // In particle order, the earliest hit of each particle; its approach along the triangle's normal is stopped
  // (eq. 2: the relative normal velocity becomes zero; the position clamp below keeps the motion off the
  // plane), the rest of its velocity kept.
  for (std::size_t k = 0; k < m_pairs.size();) {
    const Index p = m_pairs[k].first;
    std::size_t best = m_pairs.size();
    for (; k < m_pairs.size() && m_pairs[k].first == p; ++k) {
      if (hits[k].hit && (best == m_pairs.size() || hits[k].toi < hits[best].toi)) best = k;
    }
    if (best == m_pairs.size()) continue;
    const Triangle& tri = m_static.triangles[m_pairs[best].second];
    const Vec3Array& x = m_static.positions_t0;
    Vec3 normal = (x[tri[1]] - x[tri[0]]).cross(x[tri[2]] - x[tri[0]]);
    const double length = normal.norm();
    if (!(length > 0.0)) continue;  // zero-area triangle: the coupler handles it at the end of the step
    normal /= length;
    const Vec3& w = hits[best].barycentric;
    const Vec3 point = w[0] * x[tri[0]] + w[1] * x[tri[1]] + w[2] * x[tri[2]];
    double side = (positions_before[p] - point).dot(normal);
    if (side == 0.0) continue;  // starts in the plane: no side to keep
    if (side < 0.0) {
      normal = -normal;
      side = -side;
    }
    Vec3& v = particles.velocities[p];
    Vec3 cloth_velocity = Vec3::Zero();
    double inverse_mass = 1.0 / particles.masses[p];
    for (int i = 0; i < 3; ++i) {
      cloth_velocity += w[i] * m_node_velocities[tri[i]];
      inverse_mass += w[i] * w[i] * m_inverse_masses[tri[i]];
    }
    const double relative = (v - cloth_velocity).dot(normal);
    // No separating speed: 1% of the thickness per sub-step is a speed that grows as the fluid's CFL
    // sub-steps shrink, and it would feed the fast particles that shrink them.
    if (relative >= 0.0) continue;
    const double j = -relative / inverse_mass;  // eq. 2, mass-weighted (N s)
    v += (j / particles.masses[p]) * normal;
    for (int i = 0; i < 3; ++i) {
      m_node_impulses[tri[i]] -= (w[i] * j) * normal;
      m_node_velocities[tri[i]] -= (w[i] * j * m_inverse_masses[tri[i]]) * normal;
    }
    // The motion over the sub-step, kept on the particle's side of the start-of-step cloth: it may approach
    // to 1% of the thickness (the coupler, which knows where the cloth went, settles the rest).
    Vec3 step = dt * v;
    const double room = std::max(side - 0.01 * m_thickness, 0.0);
    const double along = step.dot(normal);
    if (along < -room) step -= (along + room) * normal;
    particles.positions[p] = positions_before[p] + step;
    m_impulse_links.push_back({particles.ids[p], m_pairs[best].second, w, j});
    ++m_stops;
  }
}

double ClothObstacle::vertical_impulse() const {
  double sum = 0.0;
  for (const Vec3& j : m_node_impulses)
    sum += j.y();
  return sum;
}

void moves_crossing_cloth(const ClothMesh& cloth, const Vec3Array& from, const Vec3Array& to,
                          std::vector<std::uint8_t>& crosses) {
  assert(from.size() == to.size());
  crosses.assign(from.size(), 0);
  if (cloth.triangles.empty() || from.empty()) return;
  ClothMesh still;
  still.triangles = cloth.triangles;
  still.positions_t0 = cloth.positions_t0;
  still.positions_t1 = cloth.positions_t0;
  std::vector<std::pair<Index, Index>> pairs;
  make_broad_phase(BroadPhaseKind::GRID)->find_pairs(from, to, still, 0.0, nullptr, pairs);
  const Vec3Array& x = still.positions_t0;
  for (const auto& [k, t] : pairs) {
    if (crosses[k]) continue;
    const Triangle& tri = still.triangles[t];
    const Vec3 &a = x[tri[0]], &b = x[tri[1]], &c = x[tri[2]];
    // The CCD refuses a non-finite coordinate (InvalidQueryError).
    if (!(from[k].allFinite() && to[k].allFinite() && a.allFinite() && b.allFinite() && c.allFinite()))
      continue;
    if (ccd::point_static_triangle_ccd(from[k], to[k], a, b, c).hit) crosses[k] = 1;
  }
}

}  // namespace drench
