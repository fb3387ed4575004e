#include <drench/bullet/bullet_conversions.hpp>

namespace drench::bullet {

btVector3 to_bt(const Vec3& v) {
  return btVector3(static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z()));
}

}  // namespace drench::bullet
