#include <drench/wetting/cloth_wetting.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/common/triangle_geometry.hpp>

namespace drench {

namespace {

// The explicit scheme's sub-step keeps dt_sub * rate_i at most this; 1 is the positivity bound, half of it
// keeps the front from overshooting visibly between sub-steps.
constexpr double kStepFraction = 0.5;

}  // namespace

void check_wetting_settings(const WettingSettings& s) {
  const auto require = [](bool ok, const std::string& key, const std::string& range, double value) {
    require_setting(ok, "wetting." + key, range, value);
  };
  require(s.max_saturation > 0.0 && std::isfinite(s.max_saturation), "max_saturation", "> 0",
          s.max_saturation);
  require(s.absorption_rate >= 0.0 && std::isfinite(s.absorption_rate), "absorption_rate", ">= 0",
          s.absorption_rate);
  require(s.diffusion >= 0.0 && s.diffusion <= kMaxWettingDiffusion, "diffusion",
          "in [0, " + format_number(kMaxWettingDiffusion) + "]", s.diffusion);
  require(s.gravity_flow >= 0.0 && s.gravity_flow <= kMaxGravityFlow, "gravity_flow",
          "in [0, " + format_number(kMaxGravityFlow) + "]", s.gravity_flow);
}

ClothWetting::ClothWetting(const WettingSettings& settings, const std::vector<Triangle>& triangles,
                           const Vec3Array& rest_positions, const ScalarArray& dry_masses)
    : m_settings(settings), m_triangles(triangles) {
  check_wetting_settings(settings);
  const std::size_t m = rest_positions.size();
  if (dry_masses.size() != m) {
    throw Error("wetting: " + std::to_string(dry_masses.size()) + " node masses for " + std::to_string(m) +
                " nodes");
  }
  m_capacity.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    if (!(dry_masses[i] > 0.0) || !std::isfinite(dry_masses[i])) {
      throw Error("wetting: cloth node " + std::to_string(i) + " has mass " + format_number(dry_masses[i]) +
                  ", must be > 0 and finite");
    }
    m_capacity[i] = settings.max_saturation * dry_masses[i];
  }
  m_water.assign(m, 0.0);
  m_rest_positions = rest_positions;
  m_node_area.assign(m, 0.0);
  m_flow.assign(m, 0.0);
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] >= m) {
        throw Error("wetting: cloth triangle " + std::to_string(f) + " has node " + std::to_string(t[k]) +
                    ", out of range [0, " + std::to_string(m) + ")");
      }
    }
    const Vec3& a = rest_positions[t[0]];
    const double area = 0.5 * (rest_positions[t[1]] - a).cross(rest_positions[t[2]] - a).norm();
    for (const Index v : t)
      m_node_area[v] += area / 3.0;
  }
  const std::vector<std::pair<Index, Index>> pairs = unique_edges(triangles);
  m_edges.reserve(pairs.size());
  for (const auto& [a, b] : pairs) {
    const double length = (rest_positions[a] - rest_positions[b]).norm();
    if (!(length > 0.0) || !std::isfinite(length)) {
      throw Error("wetting: cloth edge between nodes " + std::to_string(a) + " and " + std::to_string(b) +
                  " has length " + format_number(length) + ", must be > 0 and finite");
    }
    m_edges.push_back(edge(a, b, length));
  }
}

ClothWetting::Edge ClothWetting::edge(Index a, Index b, double rest_length) const {
  return {a, b, m_settings.diffusion * 0.5 * (m_capacity[a] + m_capacity[b]) / (rest_length * rest_length),
          rest_length};
}

void ClothWetting::follow(const ClothLayoutChange& change, const std::vector<Triangle>& triangles,
                          const Vec3Array& positions, const ScalarArray& dry_masses) {
  const std::size_t m = positions.size();
  if (m != change.cloth_nodes_after() || dry_masses.size() != m ||
      m_water.size() != change.cloth_nodes_before()) {
    throw Error("wetting: a cloth of " + std::to_string(m_water.size()) + " nodes followed to " +
                std::to_string(change.cloth_nodes_after()) + " with " + std::to_string(m) +
                " positions and " + std::to_string(dry_masses.size()) + " masses");
  }
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    for (const Index v : triangles[f]) {
      if (v >= m) {
        throw Error("wetting: cloth triangle " + std::to_string(f) + " has node " + std::to_string(v) +
                    ", out of range [0, " + std::to_string(m) + ")");
      }
    }
  }
  // The water stays with its nodes, a node the tear made holding none. The capacities are those of the
  // dry masses now: the engine may have moved mass from the old nodes to the new (Bullet's refine does), and
  // kept, the old nodes' would hold more water than the cloth can. Water over a capacity drips.
  ScalarArray capacity(m);
  for (std::size_t i = 0; i < m; ++i) {
    if (!(dry_masses[i] > 0.0) || !std::isfinite(dry_masses[i])) {
      throw Error("wetting: cloth node " + std::to_string(i) + " has mass " + format_number(dry_masses[i]) +
                  ", must be > 0 and finite");
    }
    capacity[i] = m_settings.max_saturation * dry_masses[i];
  }
  m_capacity = std::move(capacity);
  m_water = change.nodes_moved(m_water, 0.0);
  m_flow.assign(m, 0.0);
  // Rest geometry: a face of old nodes keeps theirs; one with a new node, whose place at rest is unknown, is
  // taken as it lies now (all three of its nodes, so that its shape is one the cloth had). An edge keeps
  // its rest length when it was an edge before, else takes its length now.
  std::vector<std::uint8_t> is_new(m, 0);
  for (std::size_t i = 0; i < m; ++i)
    is_new[i] = change.is_new_node(i) ? 1 : 0;
  m_rest_positions = change.nodes_moved(m_rest_positions, Vec3(Vec3::Zero()));
  for (std::size_t i = 0; i < m; ++i) {
    if (is_new[i]) m_rest_positions[i] = positions[i];
  }
  std::vector<std::pair<Index, Index>> old_edges;
  ScalarArray old_lengths;
  for (const Edge& e : m_edges) {
    old_edges.emplace_back(e.a, e.b);
    old_lengths.push_back(e.rest_length);
  }
  m_triangles = triangles;
  m_node_area.assign(m, 0.0);
  for (const Triangle& t : triangles) {
    const bool moved = is_new[t[0]] || is_new[t[1]] || is_new[t[2]];
    const Vec3Array& x = moved ? positions : m_rest_positions;
    const double area = 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
    for (const Index v : t)
      m_node_area[v] += area / 3.0;
  }
  const std::vector<std::pair<Index, Index>> pairs = unique_edges(triangles);
  const ScalarArray lengths = change.rest_lengths(old_edges, old_lengths, pairs, positions);
  m_edges.clear();
  for (std::size_t e = 0; e < pairs.size(); ++e) {
    const auto [a, b] = pairs[e];
    const double length = lengths[e];
    // Two nodes a tear put at one place share no water along their edge: it has no length to diffuse over.
    if (!(length > 0.0) || !std::isfinite(length)) continue;
    m_edges.push_back(edge(a, b, length));
  }
}

void ClothWetting::absorb(const std::vector<WettingContact>& contacts, ScalarArray& masses,
                          std::vector<std::uint8_t>& remove, double min_mass, double dt,
                          WettingStepStats& stats) {
  const double fraction = std::min(1.0, m_settings.absorption_rate * dt);
  if (!(fraction > 0.0)) return;
  for (const WettingContact& c : contacts) {
    if (remove[c.particle]) continue;
    const Triangle& t = m_triangles[c.triangle];
    double held = 0.0, capacity = 0.0;
    for (int k = 0; k < 3; ++k) {
      held += c.weights[k] * m_water[t[k]];
      capacity += c.weights[k] * m_capacity[t[k]];
    }
    const double saturation = capacity > 0.0 ? held / capacity : 1.0;
    if (!(saturation < 1.0)) continue;
    double& mass = masses[c.particle];
    const double take = fraction * (1.0 - saturation) * mass;
    double given = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double room = std::max(0.0, m_capacity[t[k]] - m_water[t[k]]);
      const double part = std::min(c.weights[k] * take, room);
      m_water[t[k]] += part;
      given += part;
    }
    mass -= given;
    stats.absorbed_kg += given;
    if (mass < min_mass) {
      // The rest goes whole to the node nearest the contact, even past its capacity (it drips from there),
      // so no mass is lost with the particle.
      int nearest = 0;
      for (int k = 1; k < 3; ++k)
        if (c.weights[k] > c.weights[nearest]) nearest = k;
      m_water[t[nearest]] += mass;
      stats.absorbed_kg += mass;
      mass = 0.0;
      remove[c.particle] = 1;
      ++stats.particles_absorbed;
    }
  }
}

void ClothWetting::spread(const Vec3Array& positions, const Vec3& gravity, double dt,
                          WettingStepStats& stats) {
  const std::size_t m = m_water.size();
  const double g = gravity.norm();
  const Vec3 down = g > 0.0 ? Vec3(gravity / g) : Vec3::Zero();
  const double drain = g > 0.0 ? m_settings.gravity_flow : 0.0;
  // Drainage rate of each edge from a to b (unit: 1/s; positive: b is lower): speed times slope over length,
  // at the current positions.
  ScalarArray slope(m_edges.size(), 0.0);
  ScalarArray rate(m, 0.0);  // sum_j k_ij / C_i + sum_j max(0, slope rate_ij): the scheme's limit per node
  for (std::size_t e = 0; e < m_edges.size(); ++e) {
    const Edge& edge = m_edges[e];
    const Vec3 d = positions[edge.b] - positions[edge.a];
    const double length = d.norm();
    slope[e] = length > 0.0 ? drain * d.dot(down) / (length * edge.rest_length) : 0.0;
    rate[edge.a] += edge.conductance / m_capacity[edge.a] + std::max(0.0, slope[e]);
    rate[edge.b] += edge.conductance / m_capacity[edge.b] + std::max(0.0, -slope[e]);
  }
  const double fastest = *std::max_element(rate.begin(), rate.end());
  if (!(fastest > 0.0)) return;
  const auto substeps = static_cast<std::uint64_t>(std::max(1.0, std::ceil(dt * fastest / kStepFraction)));
  const double h = dt / static_cast<double>(substeps);
  for (std::uint64_t s = 0; s < substeps; ++s) {
    std::fill(m_flow.begin(), m_flow.end(), 0.0);
    for (std::size_t e = 0; e < m_edges.size(); ++e) {
      const Edge& edge = m_edges[e];
      const double sa = m_water[edge.a] / m_capacity[edge.a];
      const double sb = m_water[edge.b] / m_capacity[edge.b];
      // Fick's law on the saturation, then drainage out of the higher node (upwind, so never more than
      // it holds).
      double flow = edge.conductance * (sa - sb);
      flow += slope[e] * (slope[e] > 0.0 ? m_water[edge.a] : m_water[edge.b]);
      m_flow[edge.a] -= h * flow;
      m_flow[edge.b] += h * flow;
    }
    for (std::size_t i = 0; i < m; ++i)
      m_water[i] = std::max(0.0, m_water[i] + m_flow[i]);
  }
  stats.spread_substeps += substeps;
}

std::vector<WettingDrop> ClothWetting::drip(const Vec3Array& positions, const Vec3Array& velocities,
                                            const Vec3& gravity, double particle_mass, double offset,
                                            const Vec3Array& particles, double clearance,
                                            WettingStepStats& stats) {
  std::vector<WettingDrop> drops;
  if (!(particle_mass > 0.0)) return drops;
  const std::size_t m = m_water.size();
  std::vector<Index> full;
  for (std::size_t i = 0; i < m; ++i) {
    if (m_water[i] - m_capacity[i] >= particle_mass) full.push_back(static_cast<Index>(i));
  }
  if (full.empty()) return drops;
  // Area-weighted vertex normals, only now that some node drips.
  Vec3Array normals(m, Vec3::Zero());
  for (const Triangle& t : m_triangles) {
    const Vec3 n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (int k = 0; k < 3; ++k)
      normals[t[k]] += n;
  }
  const double clearance2 = clearance * clearance;
  auto free_at = [&](const Vec3& x) {
    for (const Vec3& p : particles)
      if ((p - x).squaredNorm() < clearance2) return false;
    for (const WettingDrop& d : drops)
      if ((d.position - x).squaredNorm() < clearance2) return false;
    return true;
  };
  for (const Index i : full) {
    Vec3 n = normals[i];
    const double length = n.norm();
    if (!(length > 0.0)) continue;
    n /= length;
    if (n.dot(gravity) < 0.0) n = -n;
    const Vec3 x = positions[i] + offset * n;
    if (!x.allFinite() || !free_at(x)) continue;
    drops.push_back({x, velocities[i], i});
    m_water[i] -= particle_mass;
    stats.dripped_kg += particle_mass;
    ++stats.particles_dripped;
  }
  return drops;
}

ScalarArray ClothWetting::wetness() const {
  ScalarArray w(m_water.size());
  for (std::size_t i = 0; i < w.size(); ++i)
    w[i] = std::clamp(m_water[i] / m_capacity[i], 0.0, 1.0);
  return w;
}

double ClothWetting::held() const {
  double sum = 0.0;
  for (const double w : m_water)
    sum += w;
  return sum;
}

double ClothWetting::wet_area_fraction() const {
  double wet = 0.0, total = 0.0;
  for (std::size_t i = 0; i < m_water.size(); ++i) {
    total += m_node_area[i];
    if (m_water[i] > 0.01 * m_capacity[i]) wet += m_node_area[i];
  }
  return total > 0.0 ? wet / total : 0.0;
}

void ClothWetting::set_water(const ScalarArray& water) {
  if (water.size() != m_water.size()) {
    throw Error("wetting: " + std::to_string(water.size()) + " water masses for " +
                std::to_string(m_water.size()) + " nodes");
  }
  for (std::size_t i = 0; i < water.size(); ++i) {
    if (!(water[i] >= 0.0) || !std::isfinite(water[i])) {
      throw Error("wetting: node " + std::to_string(i) + " water " + format_number(water[i]) +
                  ", must be >= 0 and finite");
    }
  }
  m_water = water;
}

}  // namespace drench
