#pragma once
// Shared by the adapter tests: settings of small patches, OBJ files in a temporary folder, error checks.

#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/common/error.hpp>
#include <drench/coupling/cloth_engine.hpp>

namespace drench::bullet::test {

/// Bullet's unit roundoff: 2^-52 with BT_USE_DOUBLE_PRECISION, 2^-23 in single precision.
inline constexpr double kBulletEpsilon = std::numeric_limits<btScalar>::epsilon();

/// A value as Bullet stores it: itself with double Bullet, rounded to float with single.
inline double as_bullet(double x) {
  return static_cast<double>(static_cast<btScalar>(x));
}
inline Vec3 as_bullet(const Vec3& v) {
  return to_vec3(to_bt(v));
}

/// The tolerance of an expectation on a value of about `magnitude` that went through Bullet's storage or
/// arithmetic: the one the double build is held to, or `ulps` units of Bullet's rounding of the magnitude,
/// whichever is larger. The double build keeps its tolerance; a single-precision build is held to its own
/// rounding, not excused from the check.
inline double bullet_tolerance(double double_tolerance, double magnitude, double ulps = 4.0) {
  return std::max(double_tolerance, ulps * kBulletEpsilon * magnitude);
}

/// A btSoftRigidDynamicsWorld with Bullet's usual parts, as a game builds one; the tests' worlds add their
/// bodies to it.
struct SoftRigidWorld {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
};

/// Cuts `body` along the plane x = `x` as Bullet's own cutting does (btSoftBody::refine with cut: the edges
/// across the plane are split where they cross it and the nodes there doubled, one for each side), which
/// adds nodes and faces to the cloth and moves some of its mass to the new nodes: a game's tear.
inline void refine_across(btSoftBody& body, double x) {
  struct Plane : btSoftBody::ImplicitFn {
    btScalar x = 0;
    btScalar Eval(const btVector3& p) override { return p.x() - x; }
  } plane;
  plane.x = static_cast<btScalar>(x);
  body.refine(&plane, static_cast<btScalar>(1e-4), true);
}

inline ClothSettings patch_settings(int nodes_x, int nodes_z, const std::string& pinned = "corners") {
  ClothSettings s;
  s.center = Vec3(0.1, 0.5, -0.2);
  s.size_x = 0.6;
  s.size_z = 0.4;
  s.nodes_x = nodes_x;
  s.nodes_z = nodes_z;
  s.area_density = 0.2;
  s.pinned = pinned;
  return s;
}

/// Expects `f` to throw SceneError whose message contains every one of `parts`.
inline void expect_scene_error(const std::function<void()>& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no SceneError thrown";
  } catch (const SceneError& e) {
    const std::string message = e.what();
    for (const auto& part : parts)
      EXPECT_NE(message.find(part), std::string::npos) << "message: " << message << "\nexpected: " << part;
  }
}

}  // namespace drench::bullet::test
