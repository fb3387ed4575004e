// A user's program: a Bullet world and a pinned cloth of its own, a water jet added through drench. Runs 0.1
// s and exits 0 only if the water reached the cloth, the cloth sagged under it more than under its own weight
// alone, and no particle crossed the cloth (the leak audit's count).

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <cstdint>
#include <cstdio>

#include <drench/bullet/coupled_world.hpp>

namespace {

/// Steps `steps` coupled steps of 1 ms with or without the jet; returns the cloth centre's sag (m), or a
/// negative value after printing why the run failed.
double run(bool with_jet, int steps, std::uint64_t& contacts, std::uint64_t& leaks) {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, -9.81, 0));
  world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);

  const int n = 21;
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(world.getWorldInfo(), btVector3(-0.1, 0, -0.1),
                                                     btVector3(0.1, 0, -0.1), btVector3(-0.1, 0, 0.1),
                                                     btVector3(0.1, 0, 0.1), n, n, 1 + 2 + 4 + 8, true);
  cloth->setTotalMass(0.008);  // 0.2 kg/m^2
  cloth->m_cfg.piterations = 4;
  cloth->getCollisionShape()->setMargin(0.005);
  world.addSoftBody(cloth);

  drench::SceneConfig scene;
  scene.gravity = drench::Vec3(0, -9.81, 0);
  scene.fluid.particle_spacing = 0.005;
  scene.time.dt = 0.001;
  scene.effects = {"viscosity", "coupling", "leak_audit"};
  if (with_jet) {
    drench::EmitterSettings jet;
    jet.kind = drench::EmitterSettings::Kind::NOZZLE;
    jet.nozzle.center = drench::Vec3(0, 0.05, 0);
    jet.nozzle.radius = 0.015;
    jet.nozzle.speed = 2.0;
    scene.emitters.push_back(jet);
  }
  drench::bullet::CoupledWorld coupled(world, *cloth, scene);
  contacts = 0;
  leaks = 0;
  for (int step = 0; step < steps; ++step) {
    const drench::bullet::CoupledStepReport report = coupled.step();
    if (!report.ok()) {
      std::fprintf(stderr, "stopped at t = %.3f s: %s\n", coupled.time(), report.fluid.describe().c_str());
      return -1.0;
    }
    contacts += report.coupling_stats.contacts;
    leaks += report.leak_stats.leaks;
  }
  const double sag = -static_cast<double>(cloth->m_nodes[(n / 2) * n + n / 2].m_x.y());
  world.removeSoftBody(cloth);
  delete cloth;
  return sag;
}

}  // namespace

int main() {
  std::uint64_t contacts = 0, leaks = 0, dry_contacts = 0, dry_leaks = 0;
  const double dry = run(false, 100, dry_contacts, dry_leaks);
  const double wet = run(true, 100, contacts, leaks);
  std::printf("0.1 s: cloth centre sag %.2f mm dry, %.2f mm under the jet; %llu contacts, %llu leaks\n",
              1000 * dry, 1000 * wet, static_cast<unsigned long long>(contacts),
              static_cast<unsigned long long>(leaks));
  if (dry < 0.0 || wet < 0.0) return 2;
  if (contacts == 0) return std::fprintf(stderr, "the water never reached the cloth\n"), 1;
  if (leaks != 0)
    return std::fprintf(stderr, "%llu particles leaked through the cloth\n",
                        static_cast<unsigned long long>(leaks)),
           1;
  // The water's weight must show: more sag than the cloth's own, by at least a tenth of a millimetre.
  if (!(wet > dry + 1e-4)) return std::fprintf(stderr, "the cloth did not sag under the water\n"), 1;
  return 0;
}
