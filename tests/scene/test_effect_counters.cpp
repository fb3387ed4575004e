// EffectCounters (scene/effect_counters.hpp): every effect a scene may list has a counter, so the summary's
// effect_passes and the tests of issue 28 cover each one; and the "friction" effect decides alone whether
// the coupler has friction.

#include <drench/scene/effect_counters.hpp>

#include <gtest/gtest.h>

#include <set>

#include <drench/common/error.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/scene/simulation.hpp>

namespace drench {
namespace {

TEST(Effects, EveryKnownEffectHasItsOwnCounter) {
  EffectCounters counters;
  std::set<const EffectCounter*> seen;
  for (const std::string& name : known_effects()) {
    const EffectCounter* c = counters.find(name);
    ASSERT_NE(c, nullptr) << name << " has no counter in EffectCounters::find";
    EXPECT_TRUE(seen.insert(c).second) << name << " shares a counter";
  }
  EXPECT_EQ(counters.find("substep_obstacle"), nullptr) << "not an effect name";
  EXPECT_EQ(counters.find("viscosityy"), nullptr);
}

// Without the "friction" effect the coupler is built without its friction stage, so tangential settings made
// in code would be ignored: Simulation refuses them as the loader does, naming the key that asks.
TEST(Effects, TangentialSettingsWithoutTheFrictionEffectAreAnError) {
  for (const bool no_slip : {false, true}) {
    SceneConfig config;
    if (no_slip) {
      config.coupling.slip = SlipCondition::NO_SLIP;
    } else {
      config.coupling.friction_coefficient = 0.3;
    }
    config.obstacles.emplace_back();  // the V: what the coupling needs
    config.effects = {"coupling"};
    try {
      Simulation simulation(config);
      ADD_FAILURE() << "no SceneError";
    } catch (const SceneError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find(no_slip ? "coupling.slip asks" : "coupling.friction_coefficient asks"), 0u)
          << message;
      EXPECT_NE(message.find("but effects does not list \"friction\""), std::string::npos) << message;
      EXPECT_NE(message.find("(<code>)"), std::string::npos) << message;
    }
    config.effects = {"coupling", "friction"};
    EXPECT_NO_THROW(Simulation{config});
  }
}

}  // namespace
}  // namespace drench
