// embed_in_bullet: a water jet and the cloth-fluid coupling added to a Bullet world its user already owns.
//
// The first half is an ordinary Bullet soft-body program: the user's world and the user's cloth (a 0.6 x 0.6
// m patch of 57 x 57 nodes, corners pinned). The second half is all the drench-facing code a game or tool
// needs: describe the fluid as a scene does (demos/scenes/jet_on_cloth.json), wrap world and cloth in a
// drench::bullet::CoupledWorld, and call its step() instead of world.stepSimulation().
//
//   build/demos/embed_in_bullet      prints particles and the cloth centre's sag every 20 ms for 0.2 s

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <cstdio>

#include <drench/bullet/coupled_world.hpp>

int main() {
  // ---- The user's Bullet world and cloth ------------------------------------------------------------------
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, -9.81, 0));
  world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);  // soft bodies ignore setGravity

  const int fixed_corners = 1 + 2 + 4 + 8;
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(world.getWorldInfo(), btVector3(-0.3, 0, -0.3),
                                                     btVector3(0.3, 0, -0.3), btVector3(-0.3, 0, 0.3),
                                                     btVector3(0.3, 0, 0.3), 57, 57, fixed_corners, true);
  cloth->setTotalMass(0.072);                    // 0.2 kg/m^2; corners stay pinned (fromfaces = false)
  cloth->m_cfg.piterations = 4;                  // 1, the default, blows this patch up at dt = 1 ms
  cloth->getCollisionShape()->setMargin(0.005);  // the default is 0.25 m
  world.addSoftBody(cloth);

  // ---- drench: a water jet onto the cloth, coupled both ways ----------------------------------------------
  drench::SceneConfig scene;                  // the fluid part of a scene (docs/scenes.md), here in code
  scene.gravity = drench::Vec3(0, -9.81, 0);  // must equal world.getWorldInfo().m_gravity
  scene.fluid.particle_spacing = 0.005;
  scene.time.dt = 0.001;
  scene.effects = {"viscosity", "coupling"};  // a stage not listed is not built
  drench::EmitterSettings jet;
  jet.kind = drench::EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = drench::Vec3(0, 0.3, 0);
  jet.nozzle.radius = 0.02;
  jet.nozzle.speed = 3.0;
  scene.emitters.push_back(jet);
  drench::KillRegionSettings below;  // forget water that fell half a metre past the cloth
  below.point = drench::Vec3(0, -0.5, 0);
  scene.kill_regions.push_back(below);

  scene.coupling.cloth_thickness = 0.001;  // the paper's h (unit: m)
  drench::bullet::CoupledWorld coupled(world, *cloth, scene);
  const int centre = 28 * 57 + 28;
  for (int step = 1; step <= 200; ++step) {
    const drench::bullet::CoupledStepReport report = coupled.step();  // instead of world.stepSimulation
    if (!report.ok()) {
      std::fprintf(stderr, "stopped at t = %.3f s: %s (cloth node %lld)\n", coupled.time(),
                   report.fluid.describe().c_str(), static_cast<long long>(report.non_finite_node));
      return 2;
    }
    if (step % 20 == 0) {
      std::printf("t = %.3f s  particles %5zu  contacts %5llu  cloth centre sag %6.2f mm\n", coupled.time(),
                  coupled.particles().size(), static_cast<unsigned long long>(report.coupling_stats.contacts),
                  -1000.0 * cloth->m_nodes[centre].m_x.y());
    }
  }
  // ---- end of drench --------------------------------------------------------------------------------------

  world.removeSoftBody(cloth);
  delete cloth;
  return 0;
}
