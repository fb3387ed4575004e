#include <drench/bullet/bullet_cloth_set.hpp>

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <drench/common/error.hpp>

namespace drench::bullet {

namespace {

std::string body_name(std::size_t i) {
  return "soft body " + std::to_string(i);
}

/// The entries [first, first + count) of `all`.
template <typename Array>
Array slice(const Array& all, std::size_t first, std::size_t count) {
  return Array(all.begin() + static_cast<long>(first), all.begin() + static_cast<long>(first + count));
}

}  // namespace

BulletClothSet::BulletClothSet(btSoftRigidDynamicsWorld& world, const std::vector<btSoftBody*>& bodies)
    : m_world(&world), m_steps_world(true) {
  if (bodies.empty()) throw SceneError("no soft body to couple: the list of cloths is empty");
  const btSoftBodyArray& in_world = world.getSoftBodyArray();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    btSoftBody* body = bodies[i];
    if (!body) throw SceneError(body_name(i) + " is null");
    const auto first =
        static_cast<std::size_t>(std::find(bodies.begin(), bodies.end(), body) - bodies.begin());
    if (first != i) throw SceneError(body_name(i) + " is " + body_name(first) + " again");
    if (in_world.findLinearSearch(body) == in_world.size()) {
      throw SceneError(body_name(i) + " is not in the Bullet world: call world.addSoftBody first");
    }
    if (body->m_faces.size() == 0) {
      throw SceneError(
          body_name(i) + " has no faces (" + std::to_string(body->m_nodes.size()) + " nodes, " +
          std::to_string(body->m_links.size()) +
          " links: a rope?): drench couples the water with faces only, and would let it through; "
          "leave it out of the cloths coupled");
    }
  }
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    m_cloths.push_back(std::make_unique<BulletCloth>(*bodies[i]));  // no world: the set steps it
    try {
      m_cloths.back()->mesh().validate();
    } catch (const Error& e) {
      throw Error(body_name(i) + ": " + e.what());
    }
  }
  rebuild();
}

BulletClothSet::BulletClothSet(std::unique_ptr<BulletCloth> owned) {
  if (!owned || !owned->owns_world())
    throw std::invalid_argument("BulletClothSet: the one cloth given must own its world");
  m_world = owned->world();
  m_cloths.push_back(std::move(owned));
  rebuild();
}

BulletClothSet::~BulletClothSet() = default;

void BulletClothSet::rebuild() {
  m_first_node.assign(1, 0);
  m_first_triangle.assign(1, 0);
  m_mesh = ClothMesh();
  for (const auto& cloth : m_cloths) {
    const ClothMesh& own = cloth->mesh();
    const auto offset = static_cast<Index>(m_first_node.back());
    for (const Triangle& t : own.triangles)
      m_mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    m_first_node.push_back(m_first_node.back() + own.node_count());
    m_first_triangle.push_back(m_first_triangle.back() + own.triangle_count());
  }
  m_mesh.positions_t0.resize(m_first_node.back());
  m_mesh.positions_t1.resize(m_first_node.back());
  m_mesh.inverse_masses.resize(m_first_node.back());
  pull();
}

void BulletClothSet::pull() {
  for (std::size_t c = 0; c < m_cloths.size(); ++c) {
    const ClothMesh& own = m_cloths[c]->mesh();
    const auto at = static_cast<long>(m_first_node[c]);
    std::copy(own.positions_t0.begin(), own.positions_t0.end(), m_mesh.positions_t0.begin() + at);
    std::copy(own.positions_t1.begin(), own.positions_t1.end(), m_mesh.positions_t1.begin() + at);
    std::copy(own.inverse_masses.begin(), own.inverse_masses.end(), m_mesh.inverse_masses.begin() + at);
  }
}

void BulletClothSet::begin_step() {
  bool changed = false;
  for (std::size_t c = 0; c < m_cloths.size(); ++c) {
    m_cloths[c]->begin_step();
    const ClothMesh& own = m_cloths[c]->mesh();
    changed = changed || own.node_count() != node_count(c) || own.triangle_count() != triangle_count(c);
  }
  if (changed) {
    rebuild();
  } else {
    pull();
  }
}

void BulletClothSet::apply_impulses(const Vec3Array& impulses) {
  if (impulses.size() != m_mesh.node_count()) {
    throw std::invalid_argument("BulletClothSet::apply_impulses: " + std::to_string(impulses.size()) +
                                " impulses for " + std::to_string(m_mesh.node_count()) + " nodes");
  }
  for (std::size_t c = 0; c < m_cloths.size(); ++c)
    m_cloths[c]->apply_impulses(slice(impulses, m_first_node[c], node_count(c)));
}

void BulletClothSet::set_carried_masses(const ScalarArray& carried) {
  if (carried.size() != m_mesh.node_count()) {
    throw std::invalid_argument("BulletClothSet::set_carried_masses: " + std::to_string(carried.size()) +
                                " masses for " + std::to_string(m_mesh.node_count()) + " nodes");
  }
  for (std::size_t c = 0; c < m_cloths.size(); ++c)
    m_cloths[c]->set_carried_masses(slice(carried, m_first_node[c], node_count(c)));
}

void BulletClothSet::set_water_masses(const ScalarArray& water) {
  if (water.size() != m_mesh.node_count()) {
    throw std::invalid_argument("BulletClothSet::set_water_masses: " + std::to_string(water.size()) +
                                " masses for " + std::to_string(m_mesh.node_count()) + " nodes");
  }
  // All checked before any cloth changes.
  for (std::size_t i = 0; i < water.size(); ++i) {
    if (!(water[i] >= 0.0) || !std::isfinite(water[i])) {
      throw std::invalid_argument("BulletClothSet::set_water_masses: node " + std::to_string(i) + " water " +
                                  format_number(water[i]) + ", must be >= 0 and finite");
    }
  }
  for (std::size_t c = 0; c < m_cloths.size(); ++c)
    m_cloths[c]->set_water_masses(slice(water, m_first_node[c], node_count(c)));
  pull();  // the inverse masses Bullet holds now
}

void BulletClothSet::step(double dt) {
  check_time_step("BulletClothSet::step", dt);
  // maxSubSteps 0: exactly one step of dt (no accumulator, no interpolation), for every cloth at once.
  if (m_steps_world) m_world->stepSimulation(dt, 0);
  for (std::size_t c = 0; c < m_cloths.size(); ++c) {
    m_cloths[c]->step(dt);  // without a world of its own: captures its end positions only
    const Vec3Array& t1 = m_cloths[c]->mesh().positions_t1;
    std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin() + static_cast<long>(m_first_node[c]));
  }
}

void BulletClothSet::end_step(double dt) {
  check_time_step("BulletClothSet::end_step", dt);
  for (std::size_t c = 0; c < m_cloths.size(); ++c) {
    Vec3Array& t1 = m_cloths[c]->mesh().positions_t1;
    const auto at = m_mesh.positions_t1.begin() + static_cast<long>(m_first_node[c]);
    std::copy(at, at + static_cast<long>(t1.size()), t1.begin());
    m_cloths[c]->end_step(dt);
    std::copy(t1.begin(), t1.end(), at);  // rounded, for a single-precision Bullet
  }
}

Vec3Array BulletClothSet::velocities() const {
  Vec3Array v;
  v.reserve(m_mesh.node_count());
  for (const auto& cloth : m_cloths) {
    const Vec3Array own = cloth->velocities();
    v.insert(v.end(), own.begin(), own.end());
  }
  return v;
}

double BulletClothSet::total_mass() const {
  double mass = 0.0;
  for (const auto& cloth : m_cloths)
    mass += cloth->total_mass();
  return mass;
}

ScalarArray BulletClothSet::dry_node_masses() const {
  ScalarArray masses;
  masses.reserve(m_mesh.node_count());
  for (const auto& cloth : m_cloths) {
    const ScalarArray own = cloth->dry_node_masses();
    masses.insert(masses.end(), own.begin(), own.end());
  }
  return masses;
}

std::size_t BulletClothSet::check_index(std::size_t i) const {
  if (i >= m_cloths.size()) {
    throw std::out_of_range("cloth " + std::to_string(i) +
                            " out of range: " + std::to_string(m_cloths.size()) + " cloth(s) coupled");
  }
  return i;
}

BulletCloth& BulletClothSet::cloth(std::size_t i) {
  return *m_cloths[check_index(i)];
}

const BulletCloth& BulletClothSet::cloth(std::size_t i) const {
  return *m_cloths[check_index(i)];
}

std::vector<ClothPiece> BulletClothSet::pieces() const {
  std::vector<ClothPiece> pieces(m_cloths.size());
  for (std::size_t c = 0; c < m_cloths.size(); ++c) {
    pieces[c] = {m_first_node[c], m_first_node[c + 1] - m_first_node[c], m_first_triangle[c],
                 m_first_triangle[c + 1] - m_first_triangle[c]};
  }
  return pieces;
}

std::size_t BulletClothSet::first_node(std::size_t i) const {
  return m_first_node[check_index(i)];
}

std::size_t BulletClothSet::first_triangle(std::size_t i) const {
  return m_first_triangle[check_index(i)];
}

std::size_t BulletClothSet::node_count(std::size_t i) const {
  check_index(i);
  return m_first_node[i + 1] - m_first_node[i];
}

std::size_t BulletClothSet::triangle_count(std::size_t i) const {
  check_index(i);
  return m_first_triangle[i + 1] - m_first_triangle[i];
}

namespace {

ClothElement locate(const std::vector<std::size_t>& first, std::int64_t index) {
  if (index < 0 || static_cast<std::size_t>(index) >= first.back()) return {};
  // The last cloth whose first element is at or before `index`.
  const auto after = std::upper_bound(first.begin(), first.end(), static_cast<std::size_t>(index));
  const auto cloth = static_cast<std::int64_t>(after - first.begin()) - 1;
  return {cloth, index - static_cast<std::int64_t>(first[static_cast<std::size_t>(cloth)])};
}

}  // namespace

ClothElement BulletClothSet::locate_node(std::int64_t node) const {
  return locate(m_first_node, node);
}

ClothElement BulletClothSet::locate_triangle(std::int64_t triangle) const {
  return locate(m_first_triangle, triangle);
}

}  // namespace drench::bullet
