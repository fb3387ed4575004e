#include "bullet_adapter/coupled_world.hpp"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/error.hpp"
#include "common/stopwatch.hpp"
#include "scene/simulation.hpp"
#include "sph/boundary_sampling.hpp"

namespace drench::bullet {

namespace {

std::string format_vec3(const Vec3& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

void check_scene(const SceneConfig& scene) {
  if (!(scene.time.dt > 0.0) || !std::isfinite(scene.time.dt)) {
    throw SceneError("time.dt must be > 0 and finite, got " + format_number(scene.time.dt) + " (" +
                     scene.source + ")");
  }
  if (!scene.gravity.allFinite()) {
    throw SceneError("gravity must be finite, got " + format_vec3(scene.gravity) + " (" + scene.source + ")");
  }
}

std::unique_ptr<BulletCloth> attach(btSoftRigidDynamicsWorld& world, btSoftBody& cloth,
                                    const SceneConfig& scene) {
  check_scene(scene);
  const Vec3 soft_gravity = to_vec3(world.getWorldInfo().m_gravity);
  // Soft bodies fall with worldInfo.m_gravity, which world.setGravity does not touch (Bullet's default is
  // (0, -10, 0)); a fluid and a cloth under different gravity would drift apart at rest.
  if ((soft_gravity - scene.gravity).norm() > 1e-12 * std::max(1.0, scene.gravity.norm())) {
    throw SceneError("gravity " + format_vec3(scene.gravity) + " (" + scene.source +
                     ") differs from the Bullet world's soft-body gravity getWorldInfo().m_gravity " +
                     format_vec3(soft_gravity) +
                     "; set world.getWorldInfo().m_gravity to the scene's gravity");
  }
  const btSoftBodyArray& bodies = world.getSoftBodyArray();
  if (bodies.findLinearSearch(&cloth) == bodies.size()) {
    throw SceneError("the cloth soft body is not in the Bullet world: call world.addSoftBody(cloth) first");
  }
  return std::make_unique<BulletCloth>(cloth, &world);
}

std::unique_ptr<BulletCloth> own(const SceneConfig& scene) {
  check_scene(scene);
  if (!scene.cloth) {
    throw SceneError("cloth: the scene has none, and no Bullet cloth was given to couple with (" +
                     scene.source + ")");
  }
  try {
    return std::make_unique<BulletCloth>(*scene.cloth, scene.gravity);
  } catch (const SceneError& e) {
    throw SceneError(std::string(e.what()) + " (" + scene.source + ")");
  }
}

BoundaryParticles sample_boundaries(const SceneConfig& scene) {
  const Scalar s = scene.fluid.particle_spacing;
  BoundaryParticles all;
  for (const auto& b : scene.boundaries) {
    all.append(b.kind == BoundarySettings::Kind::BOX
                   ? sample_box_container(b.min, b.max, s, b.layers, b.open_top)
                   : sample_plane(b.point, b.normal, b.size, s, b.layers));
  }
  return all;
}

}  // namespace

CoupledWorld::CoupledWorld(btSoftRigidDynamicsWorld& world, btSoftBody& cloth, const SceneConfig& scene)
    : CoupledWorld(attach(world, cloth, scene), scene) {}

CoupledWorld::CoupledWorld(const SceneConfig& scene) : CoupledWorld(own(scene), scene) {}

CoupledWorld::CoupledWorld(std::unique_ptr<BulletCloth> cloth, const SceneConfig& scene)
    : m_scene(scene),
      m_cloth(std::move(cloth)),
      m_speed_of_sound(scene.fluid.wcsph.speed_of_sound.value_or(automatic_speed_of_sound(scene))) {
  m_cloth->mesh().validate();
  m_fluid =
      std::make_unique<FluidSolver>(m_scene.fluid, m_scene.gravity, sample_boundaries(m_scene),
                                    m_scene.boundaries, m_scene.has_effect("viscosity"), m_speed_of_sound);
  const Scalar mass = m_fluid->particle_mass();
  for (const auto& e : m_scene.emitters) {
    if (e.kind == EmitterSettings::Kind::BOX) {
      emit_box(e.box, m_scene.fluid.particle_spacing, mass, m_fluid->particles(), m_next_id);
    } else {
      m_nozzles.emplace_back(e.nozzle, m_scene.fluid.particle_spacing);
    }
  }
  if (m_scene.has_effect("coupling")) m_coupler = std::make_unique<Coupler>(m_scene.coupling);
  m_leak_audit = m_scene.has_effect("leak_audit");
}

CoupledWorld::~CoupledWorld() = default;

CoupledStepReport CoupledWorld::step(double dt) {
  assert(dt > 0.0);
  CoupledStepReport report;
  ScopedTimer total(report.seconds.total);
  BulletCloth& cloth = *m_cloth;
  ParticleSet& p = m_fluid->particles();

  cloth.begin_step();
  {
    ScopedTimer timer(report.seconds.emit);
    for (auto& nozzle : m_nozzles)
      report.emitted += nozzle.emit(m_time, dt, m_fluid->particle_mass(), p, m_next_id);
  }
  {
    ScopedTimer timer(report.seconds.fluid);
    report.fluid = m_fluid->step(dt);
  }
  {
    ScopedTimer timer(report.seconds.cloth);
    cloth.step(dt);  // one Bullet step, then the end positions are captured
  }
  const ClothMesh& mesh = cloth.mesh();
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    if (!mesh.positions_t1[i].allFinite()) {
      report.non_finite_node = static_cast<std::int64_t>(i);
      break;
    }
  }
  if (report.ok()) {
    ScopedTimer timer(report.seconds.coupling);
    if (m_coupler) {
      const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses};
      report.coupling = m_coupler->step(view, cloth.mesh(), dt, report.coupling_stats);
      report.coupled = true;
    }
    if (m_leak_audit) audit_leaks(p.positions_t0, p.positions, cloth.mesh(), report.leak_stats);
  }
  cloth.end_step(dt);
  if (!m_scene.kill_regions.empty()) {
    ScopedTimer timer(report.seconds.emit);
    report.removed = remove_killed();
  }
  m_time += dt;
  ++m_steps;
  return report;
}

std::size_t CoupledWorld::remove_killed() {
  ParticleSet& particles = m_fluid->particles();
  std::vector<std::uint8_t> remove(particles.size(), 0);
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const Vec3& x = particles.positions[i];
    for (const auto& region : m_scene.kill_regions) {
      const bool out = region.kind == KillRegionSettings::Kind::PLANE
                           ? (x - region.point).dot(region.normal) < 0.0
                           : ((x.array() < region.min.array()) || (x.array() > region.max.array())).any();
      if (out) {
        remove[i] = 1;
        ++flagged;
        break;
      }
    }
  }
  if (flagged == 0) return 0;
  const std::size_t removed = particles.remove_flagged(remove);
  m_removed += static_cast<std::int64_t>(removed);
  return removed;
}

}  // namespace drench::bullet
