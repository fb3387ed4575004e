// The automatic WCSPH speed of sound: ten times the fastest speed the scene's fluid can reach, so that the
// Tait equation keeps density errors near 1% (Becker & Teschner 2007: c = 10 v_max).

#include <gtest/gtest.h>

#include <cmath>

#include <drench/scene/simulation.hpp>

namespace drench {
namespace {

SceneConfig jet(double nozzle_height, double speed) {
  SceneConfig c;
  EmitterSettings e;
  e.kind = EmitterSettings::Kind::NOZZLE;
  e.nozzle.center = Vec3(0.0, nozzle_height, 0.0);
  e.nozzle.speed = speed;
  c.emitters.push_back(e);
  return c;
}

TEST(AutomaticSpeedOfSound, CountsTheFallFromTheNozzleToAPatchCloth) {
  // A jet onto a cloth 0.3 m below: it lands at 3 + sqrt(2 g 0.3) m/s, not at 3 m/s.
  SceneConfig scene = jet(0.3, 3.0);
  EXPECT_DOUBLE_EQ(automatic_speed_of_sound(scene), 10.0 * 3.0);  // no cloth: the nozzle alone spans nothing
  ClothSettings cloth;
  cloth.center = Vec3(0.0, 0.0, 0.0);
  scene.cloth = cloth;
  EXPECT_NEAR(automatic_speed_of_sound(scene), 10.0 * (3.0 + std::sqrt(2.0 * 9.81 * 0.3)), 1e-12);
}

TEST(AutomaticSpeedOfSound, IgnoresAnObjClothsUnknownExtent) {
  SceneConfig scene = jet(0.3, 3.0);
  ClothSettings cloth;
  cloth.mesh = "sheet.obj";
  cloth.center = Vec3(0.0, -5.0, 0.0);  // unused by an OBJ cloth
  scene.cloth = cloth;
  EXPECT_DOUBLE_EQ(automatic_speed_of_sound(scene), 10.0 * 3.0);
}

}  // namespace
}  // namespace drench
