#pragma once
/// Bullet's vectors to drench's and back, and the check that Bullet's headers are compiled in the precision
/// the linked adapter was built with (drench::bullet_double or drench::bullet_single; drench::bullet is the
/// one of DRENCH_BULLET_PRECISION). Every header of the adapter includes this one, so a translation unit that
/// sees Bullet's headers in the other precision fails to compile instead of linking silently against
/// libraries whose btScalar differs. A program compiled in the right precision can still link the other
/// Bullet's libraries too (FindBullet's BULLET_LIBRARIES beside drench::bullet): the configure
/// (cmake/bullet_precision_check.cmake) and the link (bullet_adapter/bullet_link_guard/) refuse that.

#include <LinearMath/btMatrix3x3.h>
#include <LinearMath/btScalar.h>
#include <LinearMath/btVector3.h>

#include <drench/common/types.hpp>

#ifndef DRENCH_BULLET_DOUBLE
#error "DRENCH_BULLET_DOUBLE is not defined: link the CMake target drench::bullet (or use drench-bullet.pc)"
#endif

#if DRENCH_BULLET_DOUBLE
static_assert(
    sizeof(btScalar) == sizeof(double),
    "drench::bullet_double (DRENCH_BULLET_PRECISION=double) is linked, but Bullet's headers are "
    "compiled here in single precision: add -DBT_USE_DOUBLE_PRECISION (linking drench::bullet_double, "
    "or pkg-config bullet-float64, does), or link drench::bullet_single (drench-bullet-single.pc)");
#else
static_assert(sizeof(btScalar) == sizeof(float),
              "drench::bullet_single (DRENCH_BULLET_PRECISION=single) is linked, but Bullet's headers are "
              "compiled here with BT_USE_DOUBLE_PRECISION: drop that define, or link drench::bullet_double "
              "(drench-bullet-double.pc)");
#endif

namespace drench::bullet {

/// Exact in both precisions: a float widens to a double without rounding.
inline Vec3 to_vec3(const btVector3& v) {
  return Vec3(v.x(), v.y(), v.z());
}

/// A Bullet rotation (a transform's basis) as Eigen's, exact in both precisions.
inline Eigen::Matrix3d to_matrix3(const btMatrix3x3& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out(r, c) = m[r][c];
  return out;
}

/// Exact with double Bullet; with float Bullet each coordinate rounds to the nearest float (a relative error
/// of at most 2^-24), which is why BulletCloth reads back what it wrote before the leak audit sees it. Out of
/// line on purpose: g++ 12 at -O2 vectorizes an inlined to_vec3(to_bt(v)) into a copy of x and y that skips
/// the rounding (test BulletConversions.ToBulletRoundsEveryCoordinate).
btVector3 to_bt(const Vec3& v);

}  // namespace drench::bullet
