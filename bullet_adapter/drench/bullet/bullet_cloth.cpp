#include <drench/bullet/bullet_cloth.hpp>

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

#include <drench/bullet/soft_body_builder.hpp>
#include <drench/common/error.hpp>

namespace drench::bullet {

/// Everything an owned cloth needs, in construction order; destroyed in reverse.
struct BulletCloth::OwnedWorld {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  std::unique_ptr<btSoftBody> body;

  ~OwnedWorld() {
    if (body) world.removeSoftBody(body.get());
  }
};

void check_time_step(const std::string& where, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw std::invalid_argument(where + ": dt must be > 0 and finite, got " + format_number(dt) + " s");
}

BulletCloth::BulletCloth(btSoftBody& body, btSoftRigidDynamicsWorld* world) : m_body(&body), m_world(world) {
  read_topology();
}

BulletCloth::BulletCloth(const ClothSettings& settings, const Vec3& gravity) {
  if (!gravity.allFinite()) {
    throw SceneError("gravity must be finite, got (" + format_number(gravity.x()) + ", " +
                     format_number(gravity.y()) + ", " + format_number(gravity.z()) + ")");
  }
  m_owned = std::make_unique<OwnedWorld>();
  btSoftRigidDynamicsWorld& world = m_owned->world;
  // Soft bodies ignore world.setGravity and take worldInfo.m_gravity (default (0, -10, 0)); rigid bodies the
  // other way round. Set both.
  world.setGravity(to_bt(gravity));
  // (The world's constructor already gave worldInfo its broadphase, dispatcher and sparse SDF.)
  btSoftBodyWorldInfo& info = world.getWorldInfo();
  info.m_gravity = to_bt(gravity);

  m_owned->body = create_cloth_body(info, settings);
  m_owned->body->setActivationState(DISABLE_DEACTIVATION);
  world.addSoftBody(m_owned->body.get());
  m_body = m_owned->body.get();
  m_substeps = settings.substeps;
  m_world = &world;
  read_topology();
}

BulletCloth::~BulletCloth() {
  restore_masses();  // an attached body outlives us: it keeps its own masses
}

void BulletCloth::read_topology() {
  const btSoftBody& body = *m_body;
  const int m = body.m_nodes.size();
  m_mesh.positions_t0.resize(m);
  for (int i = 0; i < m; ++i)
    m_mesh.positions_t0[i] = to_vec3(body.m_nodes[i].m_x);
  m_mesh.positions_t1 = m_mesh.positions_t0;
  m_predicted = m_mesh.positions_t0;
  m_mesh.triangles.resize(body.m_faces.size());
  for (int f = 0; f < body.m_faces.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      m_mesh.triangles[f][k] = static_cast<Index>(node_index(body, body.m_faces[f].m_n[k]));
  }
  read_inverse_masses();
}

void BulletCloth::read_inverse_masses() {
  const btSoftBody& body = *m_body;
  m_mesh.inverse_masses.resize(body.m_nodes.size());
  for (int i = 0; i < body.m_nodes.size(); ++i)
    m_mesh.inverse_masses[i] = body.m_nodes[i].m_im;
}

void BulletCloth::follow_dry_masses() {
  if (m_dry_inverse_masses.empty()) return;  // not wetted yet: the first set_water_masses reads them all
  const btSoftBody& body = *m_body;
  const std::size_t old_nodes = m_dry_inverse_masses.size();
  // A tear made its new nodes of its old nodes' wet masses (refine scales both ends of a split edge, and
  // halves a node it doubles): an old node keeps its water (the wetting's), and its dry mass scales as
  // Bullet scaled its whole mass; the new nodes, which hold no water, take as dry mass theirs less the
  // share of water that came with it. So the cloth's dry mass and its water stay what they were.
  double moved_water = 0.0, new_mass = 0.0;
  for (std::size_t i = 0; i < old_nodes; ++i) {
    const double dry = m_dry_inverse_masses[i];
    const double left = m_left_inverse_masses[i];
    const btScalar now = body.m_nodes[static_cast<int>(i)].m_im;
    // As drench left it (set_water_masses, or the last tear's follow), or pinned.
    if (!(dry > 0.0) || !(now > 0) || !(left > 0.0) || now == static_cast<btScalar>(left)) continue;
    const double scale = left / static_cast<double>(now);  // its mass now over its mass then
    m_dry_inverse_masses[i] = dry / scale;
    moved_water += (1.0 - scale) * m_last_water[i];
  }
  for (int i = static_cast<int>(old_nodes); i < body.m_nodes.size(); ++i) {
    if (body.m_nodes[i].m_im > 0) new_mass += 1.0 / static_cast<double>(body.m_nodes[i].m_im);
  }
  // Bullet moves no more than it takes: a share of 1 or more (or below 0) is the game's own change of masses,
  // and the new nodes are then taken as dry.
  const double share = new_mass > 0.0 ? moved_water / new_mass : 0.0;
  const double water_share = share >= 0.0 && share < 1.0 ? share : 0.0;
  for (int i = static_cast<int>(old_nodes); i < body.m_nodes.size(); ++i) {
    const double im = body.m_nodes[i].m_im;
    m_dry_inverse_masses.push_back(im > 0.0 ? im / (1.0 - water_share) : 0.0);
  }
  m_last_water.resize(m_dry_inverse_masses.size(), 0.0);
  m_left_inverse_masses.resize(m_dry_inverse_masses.size());
  for (int i = 0; i < body.m_nodes.size(); ++i)
    m_left_inverse_masses[static_cast<std::size_t>(i)] = body.m_nodes[i].m_im;
}

void BulletCloth::begin_step() {
  restore_masses();  // carried masses set for a step that never ran are not the cloth's
  const btSoftBody& body = *m_body;
  if (static_cast<std::size_t>(body.m_nodes.size()) != m_mesh.node_count() ||
      static_cast<std::size_t>(body.m_faces.size()) != m_mesh.triangle_count()) {
    follow_dry_masses();
    read_topology();
  } else {
    read_inverse_masses();
  }
  for (int i = 0; i < body.m_nodes.size(); ++i)
    m_mesh.positions_t0[i] = to_vec3(body.m_nodes[i].m_x);
}

void BulletCloth::apply_impulses(const Vec3Array& impulses) {
  btSoftBody& body = *m_body;
  if (impulses.size() != static_cast<std::size_t>(body.m_nodes.size())) {
    throw std::invalid_argument("BulletCloth::apply_impulses: " + std::to_string(impulses.size()) +
                                " impulses for " + std::to_string(body.m_nodes.size()) + " nodes");
  }
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    btSoftBody::Node& node = body.m_nodes[i];
    node.m_v += to_bt(impulses[i]) * node.m_im;
  }
}

void BulletCloth::set_carried_masses(const ScalarArray& carried) {
  btSoftBody& body = *m_body;
  if (carried.size() != static_cast<std::size_t>(body.m_nodes.size())) {
    throw std::invalid_argument("BulletCloth::set_carried_masses: " + std::to_string(carried.size()) +
                                " masses for " + std::to_string(body.m_nodes.size()) + " nodes");
  }
  restore_masses();
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    btSoftBody::Node& node = body.m_nodes[i];
    if (!(node.m_im > 0.0) || !(carried[i] > 0.0)) continue;
    m_saved_inverse_masses.emplace_back(i, node.m_im);
    node.m_im = 1.0 / (1.0 / node.m_im + carried[i]);
  }
  if (!m_saved_inverse_masses.empty()) body.updateLinkConstants();
}

void BulletCloth::set_water_masses(const ScalarArray& water) {
  btSoftBody& body = *m_body;
  if (water.size() != static_cast<std::size_t>(body.m_nodes.size())) {
    throw std::invalid_argument("BulletCloth::set_water_masses: " + std::to_string(water.size()) +
                                " masses for " + std::to_string(body.m_nodes.size()) + " nodes");
  }
  for (std::size_t i = 0; i < water.size(); ++i) {
    if (!(water[i] >= 0.0) || !std::isfinite(water[i])) {
      throw std::invalid_argument("BulletCloth::set_water_masses: node " + std::to_string(i) + " water " +
                                  format_number(water[i]) + ", must be >= 0 and finite");
    }
  }
  restore_masses();
  if (m_dry_inverse_masses.empty()) {
    m_dry_inverse_masses.resize(water.size());
    for (int i = 0; i < body.m_nodes.size(); ++i)
      m_dry_inverse_masses[i] = body.m_nodes[i].m_im;
  }
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    const double dry = m_dry_inverse_masses[i];
    if (dry > 0.0) body.m_nodes[i].m_im = 1.0 / (1.0 / dry + water[i]);
  }
  m_last_water = water;
  m_left_inverse_masses.resize(water.size());
  for (int i = 0; i < body.m_nodes.size(); ++i)
    m_left_inverse_masses[static_cast<std::size_t>(i)] = body.m_nodes[i].m_im;
  body.updateLinkConstants();
  read_inverse_masses();
}

void BulletCloth::restore_masses() {
  if (m_saved_inverse_masses.empty()) return;
  for (const auto& [i, im] : m_saved_inverse_masses)
    m_body->m_nodes[i].m_im = im;
  m_saved_inverse_masses.clear();
  m_body->updateLinkConstants();
}

void BulletCloth::step(double dt) {
  check_time_step("BulletCloth::step", dt);
  if (m_world != nullptr) {
    // maxSubSteps 0: exactly one step of the given length each time (no accumulator, no interpolation).
    for (int k = 0; k < m_substeps; ++k)
      m_world->stepSimulation(dt / m_substeps, 0);
  }
  capture_end();
}

void BulletCloth::capture_end() {
  restore_masses();
  const btSoftBody& body = *m_body;
  assert(static_cast<std::size_t>(body.m_nodes.size()) == m_mesh.node_count());
  m_predicted.resize(body.m_nodes.size());
  for (int i = 0; i < body.m_nodes.size(); ++i)
    m_predicted[i] = to_vec3(body.m_nodes[i].m_x);
  m_mesh.positions_t1 = m_predicted;
}

void BulletCloth::end_step(double dt) {
  check_time_step("BulletCloth::end_step", dt);
  btSoftBody& body = *m_body;
  assert(static_cast<std::size_t>(body.m_nodes.size()) == m_mesh.node_count());
  bool moved = false;
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    Vec3& corrected = m_mesh.positions_t1[i];
    const Vec3& predicted = m_predicted[i];
    if (corrected == predicted) continue;
    btSoftBody::Node& node = body.m_nodes[i];
    if (!corrected.allFinite()) {
      ++m_non_finite;
      corrected = predicted;
      continue;
    }
    if (!(node.m_im > 0.0)) {
      ++m_ignored_pinned;
      corrected = predicted;
      continue;
    }
    const Vec3 dv = (corrected - predicted) / dt;
    node.m_x = to_bt(corrected);
    node.m_v += to_bt(dv);
    corrected = to_vec3(node.m_x);  // what a single-precision Bullet holds, for the leak audit after this
    moved = true;
  }
  if (moved) {
    body.updateNormals();
    body.activate();
  }
}

Vec3Array BulletCloth::velocities() const {
  const btSoftBody& body = *m_body;
  Vec3Array v(body.m_nodes.size());
  for (int i = 0; i < body.m_nodes.size(); ++i)
    v[i] = to_vec3(body.m_nodes[i].m_v);
  return v;
}

double BulletCloth::total_mass() const {
  return m_body->getTotalMass();
}

ScalarArray BulletCloth::dry_node_masses() const {
  const btSoftBody& body = *m_body;
  const ScalarArray area_share = node_masses_from_area(body, 1.0);  // a third of each face's area (m^2)
  const std::size_t m = area_share.size();
  ScalarArray masses(m, 0.0);
  double moving_mass = 0.0, moving_area = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double im = m_dry_inverse_masses.empty()
                          ? static_cast<double>(body.m_nodes[static_cast<int>(i)].m_im)
                          : m_dry_inverse_masses[i];
    if (!(im > 0.0)) continue;
    masses[i] = 1.0 / im;
    moving_mass += masses[i];
    moving_area += area_share[i];
  }
  const double density = moving_area > 0.0 ? moving_mass / moving_area : ClothSettings{}.area_density;
  double pinned_sum = 0.0;
  std::size_t pinned_faceless = 0;
  for (std::size_t i = 0; i < m; ++i) {
    if (masses[i] > 0.0) continue;
    masses[i] = density * area_share[i];
    if (masses[i] > 0.0) {
      pinned_sum += masses[i];
    } else {
      ++pinned_faceless;
    }
  }
  if (pinned_faceless > 0) {
    // (A body without faces has no node with a share of area: its masses stay 0, which wetting refuses.)
    const double mean =
        (moving_mass + pinned_sum) / static_cast<double>(std::max<std::size_t>(1, m - pinned_faceless));
    for (double& mass : masses)
      if (!(mass > 0.0)) mass = mean;
  }
  return masses;
}

std::unique_ptr<ClothEngine> make_bullet_cloth_engine(const ClothSettings& settings, const Vec3& gravity) {
  return std::make_unique<BulletCloth>(settings, gravity);
}

ClothEngineFactory cloth_engine_factory() {
  return &make_bullet_cloth_engine;
}

}  // namespace drench::bullet
