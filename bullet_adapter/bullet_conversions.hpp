#pragma once
/// Bullet's vectors to drench's and back, and the check that Bullet was compiled in double precision. Every
/// header of the adapter includes this one, so a translation unit that sees Bullet's headers without
/// BT_USE_DOUBLE_PRECISION (which the bullet-float64 pkg-config module, linked PUBLIC by drench::bullet, puts
/// on the compile line) fails to compile instead of linking silently against the double libraries.

#include <LinearMath/btScalar.h>
#include <LinearMath/btVector3.h>

#include "common/types.hpp"

static_assert(sizeof(btScalar) == sizeof(double),
              "drench::bullet needs Bullet's double-precision build: compile with -DBT_USE_DOUBLE_PRECISION "
              "(link drench::bullet, or pkg-config bullet-float64, which add it)");

namespace drench::bullet {

/// Exact: both sides hold doubles.
inline Vec3 to_vec3(const btVector3& v) {
  return Vec3(v.x(), v.y(), v.z());
}
inline btVector3 to_bt(const Vec3& v) {
  return btVector3(v.x(), v.y(), v.z());
}

}  // namespace drench::bullet
