// CarriedWater (CouplingScheme::CARRIED_WATER): which particles a cloth carries through its step (those whose
// impulse it takes), as how much mass on which node, and the exact momentum hand-back afterwards.

#include <gtest/gtest.h>

#include <drench/coupling/carried_water.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

constexpr double kParticleMass = 1.25e-4;   // kg
constexpr double kNodeInverseMass = 1.0e4;  // 1/kg
constexpr double kDt = 0.001;               // s

/// A 3 x 3 grid, 0.2 m wide, in the plane y = 0, node 0 (at x = z = 0) pinned, and four particles (ids
/// 10-13): 10 gave two impulses (the larger to triangle 5), 11 one whose weight is all on the pinned node, 12
/// none (near the cloth, but near is not contact), 13 one to triangle 2.
struct Scene {
  ClothMesh cloth = test::grid_mesh(3, 0.2, 0.0, kNodeInverseMass);
  Vec3Array x{Vec3(0.13, 0.001, 0.07), Vec3(0.0, 0.001, 0.0), Vec3(0.07, 0.001, 0.07),
              Vec3(0.07, -0.002, 0.16)};
  ScalarArray m{kParticleMass, kParticleMass, kParticleMass, 2.0 * kParticleMass};
  std::vector<std::uint32_t> ids{10, 11, 12, 13};
  ImpulseLinks links{{10, 1, Vec3(0.2, 0.3, 0.5), 1e-4},   {13, 2, Vec3(0.6, 0.1, 0.3), 2e-4},
                     {10, 5, Vec3(0.5, 0.25, 0.25), 3e-4}, {11, 0, Vec3(1.0, 0.0, 0.0), 1e-4},
                     {99, 3, Vec3(0.2, 0.3, 0.5), 1e-4},   {13, 800, Vec3(0.2, 0.3, 0.5), 1e-3}};
  Scene() { cloth.inverse_masses[0] = 0.0; }
};

TEST(CarriedWater, CarriesTheParticlesWhoseImpulseTheClothTakes) {
  Scene s;
  ASSERT_EQ(s.cloth.triangles[0][0], 0u) << "triangle 0 starts at the pinned node";
  CarriedWater water;
  water.attach(s.cloth, s.m, s.ids, s.links);
  EXPECT_EQ(water.carried_count(), 2u) << "10 and 13; not 11 (pinned), 12 (no impulse), 99 (absent)";
  ScalarArray expected(s.cloth.node_count(), 0.0);
  const auto add = [&](Index t, const Vec3& w, double mass) {
    for (int i = 0; i < 3; ++i) {
      if (s.cloth.inverse_masses[s.cloth.triangles[t][i]] > 0.0)
        expected[s.cloth.triangles[t][i]] += w[i] * mass;
    }
  };
  add(5, Vec3(0.5, 0.25, 0.25), s.m[0]);  // particle 10's largest impulse
  add(2, Vec3(0.6, 0.1, 0.3), s.m[3]);    // particle 13 (its link to triangle 800 is out of range)
  const ScalarArray& carried = water.carried_masses();
  ASSERT_EQ(carried.size(), s.cloth.node_count());
  EXPECT_EQ(carried[0], 0.0) << "a pinned node carries nothing";
  for (std::size_t i = 0; i < carried.size(); ++i)
    EXPECT_NEAR(carried[i], expected[i], 1e-20) << "node " << i;
  // The links' order does not matter, to the bit.
  ImpulseLinks reversed(s.links.rbegin(), s.links.rend());
  CarriedWater other;
  other.attach(s.cloth, s.m, s.ids, reversed);
  EXPECT_EQ(other.carried_masses(), carried);
}

TEST(CarriedWater, OfEqualImpulsesCarriesByTheLowerTriangleInEitherOrder) {
  Scene s;
  // Particle 13 (index 3) gives triangles 6 and 4 the same largest impulse; its ids need not be in index
  // order.
  s.ids = {12, 10, 11, 13};
  const ImpulseLinks tied{{13, 6, Vec3(0.1, 0.1, 0.8), 5e-4},
                          {13, 4, Vec3(0.3, 0.3, 0.4), 5e-4},
                          {13, 2, Vec3(0.6, 0.1, 0.3), 2e-4}};
  ScalarArray expected(s.cloth.node_count(), 0.0);
  for (int i = 0; i < 3; ++i) {
    const Index node = s.cloth.triangles[4][i];
    if (s.cloth.inverse_masses[node] > 0.0) expected[node] += Vec3(0.3, 0.3, 0.4)[i] * s.m[3];
  }
  for (const bool reverse : {false, true}) {
    const ImpulseLinks links = reverse ? ImpulseLinks(tied.rbegin(), tied.rend()) : tied;
    CarriedWater water;
    water.attach(s.cloth, s.m, s.ids, links);
    EXPECT_EQ(water.carried_count(), 1u) << "reversed: " << reverse;
    for (std::size_t i = 0; i < expected.size(); ++i)
      EXPECT_NEAR(water.carried_masses()[i], expected[i], 1e-20) << "node " << i << ", reversed: " << reverse;
  }
}

// Wetting takes the coupler's links and the obstacle's in two lists: the chosen link must not depend on which
// list a tie came in, nor on the order within one.
TEST(ImpulseLinks, TheLargestImpulseWinsAndATieGoesToTheLowerTriangleInAnyList) {
  KeyIndexTable index_of;
  index_of.build({40, 41, 42});
  const ImpulseLinks coupler{{41, 6, Vec3(0.2, 0.3, 0.5), 3e-4},   // tied with the obstacle's triangle 2
                             {42, 1, Vec3(0.5, 0.5, 0.0), 1e-4},   // beaten by the obstacle's larger one
                             {99, 0, Vec3(1.0, 0.0, 0.0), 9e-4},   // a particle no longer present
                             {40, 8, Vec3(1.0, 0.0, 0.0), 9e-4}};  // an obstacle face, not the cloth's
  const ImpulseLinks obstacle{{41, 2, Vec3(0.1, 0.1, 0.8), 3e-4}, {42, 5, Vec3(0.3, 0.3, 0.4), 2e-4}};
  for (const bool coupler_first : {true, false}) {
    std::vector<const ImpulseLink*> best(3, nullptr);
    keep_largest_links(coupler_first ? coupler : obstacle, 8, index_of, best);
    keep_largest_links(coupler_first ? obstacle : coupler, 8, index_of, best);
    EXPECT_EQ(best[0], nullptr) << "coupler first: " << coupler_first;
    ASSERT_NE(best[1], nullptr);
    EXPECT_EQ(best[1]->triangle, 2u) << "coupler first: " << coupler_first;
    ASSERT_NE(best[2], nullptr);
    EXPECT_EQ(best[2]->triangle, 5u) << "coupler first: " << coupler_first;
  }
}

TEST(CarriedWater, HandsBackExactlyTheWatersShareOfTheClothsMomentumChange) {
  Scene s;
  CarriedWater water;
  water.attach(s.cloth, s.m, s.ids, s.links);
  const std::size_t nodes = s.cloth.node_count();
  Vec3Array before(nodes), end(nodes);
  for (std::size_t i = 0; i < nodes; ++i) {
    before[i] = Vec3(0.1 * i, -0.2, 0.05);
    end[i] = before[i] + Vec3(0.01 * i, 0.3 - 0.02 * i, -0.01);
  }
  end[0] = before[0] = Vec3::Zero();  // pinned
  Vec3Array x = s.x;
  Vec3Array v(s.x.size(), Vec3(0.0, -1.0, 0.0));
  const Vec3 given = water.hand_back(before, end, s.cloth, kDt, x, v, s.m);
  // The engine moved node i as m_i + carried_i; the water's part of that momentum change is what the
  // particles receive, no more and no less.
  Vec3 held = Vec3::Zero();
  for (std::size_t i = 0; i < nodes; ++i)
    held += water.carried_masses()[i] * (end[i] - before[i]);
  EXPECT_LT((given - held).norm(), 1e-18);
  Vec3 received = Vec3::Zero();
  for (std::size_t p = 0; p < x.size(); ++p) {
    received += s.m[p] * (v[p] - Vec3(0.0, -1.0, 0.0));
    EXPECT_LT((x[p] - s.x[p] - kDt * (v[p] - Vec3(0.0, -1.0, 0.0))).norm(), 1e-15)
        << "particle " << p << " moves by its velocity change over the step";
  }
  EXPECT_LT((received - held).norm(), 1e-18);
  // Each carried particle gets the velocity change of its link's point on the cloth.
  const auto point_change = [&](Index t, const Vec3& w) {
    Vec3 dv = Vec3::Zero();
    for (int i = 0; i < 3; ++i)
      dv += w[i] * (end[s.cloth.triangles[t][i]] - before[s.cloth.triangles[t][i]]);
    return dv;
  };
  EXPECT_LT((v[0] - Vec3(0.0, -1.0, 0.0) - point_change(5, Vec3(0.5, 0.25, 0.25))).norm(), 1e-15);
  EXPECT_LT((v[3] - Vec3(0.0, -1.0, 0.0) - point_change(2, Vec3(0.6, 0.1, 0.3))).norm(), 1e-15);
  EXPECT_EQ(v[1], Vec3(0.0, -1.0, 0.0)) << "its impulse went to the pinned node: untouched";
  EXPECT_EQ(v[2], Vec3(0.0, -1.0, 0.0)) << "no impulse: untouched";
}

}  // namespace
}  // namespace drench
