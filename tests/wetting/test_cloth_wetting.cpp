// The water inside a cloth (wetting/cloth_wetting.hpp): mass conservation of every transfer, the diffusion's
// maximum principle at any step, gravity drainage, absorption and dripping.
#include <drench/wetting/cloth_wetting.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <gtest/gtest.h>

#include <drench/common/error.hpp>
#include <drench/coupling/cloth_mesh.hpp>

namespace drench {
namespace {

constexpr double kAreaDensity = 0.2;  // kg/m^2, the scenes' default cloth

struct Patch {
  ClothMesh mesh;
  ScalarArray dry_masses;
};

// n x n nodes over size x size in the plane y = 0; `vertical` turns it into the plane z = 0 hanging along -y
// (row 0 at the top).
Patch patch(int n, double size, bool vertical = false) {
  Patch p{ClothMesh::grid(n, size, 0.0, 1.0), {}};
  if (vertical) {
    for (Vec3& x : p.mesh.positions_t0)
      x = Vec3(x.x(), -x.z(), 0.0);
    p.mesh.positions_t1 = p.mesh.positions_t0;
  }
  const double cell = size / (n - 1);
  p.dry_masses.assign(p.mesh.node_count(), kAreaDensity * cell * cell);
  return p;
}

double sum(const ScalarArray& a) {
  return std::accumulate(a.begin(), a.end(), 0.0);
}

TEST(ClothWetting, DiffusionOfAWetSpotConservesMassAndEvensOutWithinCapacityAtAnyStep) {
  for (const double dt : {1e-3, 0.05, 2.0}) {
    SCOPED_TRACE("dt " + std::to_string(dt));
    const Patch p = patch(21, 0.2);
    WettingSettings settings;
    settings.diffusion = 1e-3;
    ClothWetting wetting(settings, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
    ScalarArray water(p.mesh.node_count(), 0.0);
    const std::size_t centre = 10 * 21 + 10;
    water[centre] = wetting.capacities()[centre];  // one saturated node
    wetting.set_water(water);
    const double total = wetting.held();
    WettingStepStats stats;
    const int steps = static_cast<int>(std::lround(60.0 / dt));
    double max_saturation_seen = 0.0;
    for (int s = 0; s < steps; ++s) {
      wetting.spread(p.mesh.positions_t0, Vec3(0, -9.81, 0), dt, stats);  // flat: gravity does not drain
      for (std::size_t i = 0; i < water.size(); ++i) {
        ASSERT_GE(wetting.water()[i], 0.0) << "node " << i;
        max_saturation_seen = std::max(max_saturation_seen, wetting.water()[i] / wetting.capacities()[i]);
      }
    }
    EXPECT_LE(max_saturation_seen, 1.0 + 1e-12);  // the maximum principle
    EXPECT_NEAR(wetting.held(), total, 1e-12 * total);
    // 60 s of D = 1e-3 m^2/s spreads over sqrt(D t) = 0.24 m, the patch's size: uniform within 1%.
    const double uniform = total / sum(wetting.capacities());
    for (std::size_t i = 0; i < water.size(); ++i)
      ASSERT_NEAR(wetting.water()[i] / wetting.capacities()[i], uniform, 0.01 * uniform) << "node " << i;
  }
}

TEST(ClothWetting, WaterRunsDownAHangingClothAndEndsWetterAtItsLowerEdge) {
  const int n = 11;
  const Patch p = patch(n, 0.2, /*vertical=*/true);
  ClothWetting wetting(WettingSettings{}, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  ScalarArray water(p.mesh.node_count(), 0.0);
  for (int i = 0; i < n; ++i)
    water[i] = 0.9 * wetting.capacities()[i];  // the top row (y = 0) wet
  wetting.set_water(water);
  const double total = wetting.held();
  WettingStepStats stats;
  for (int s = 0; s < 4000; ++s)  // 4 s: water running at 5 cm/s crosses the 0.2 m cloth
    wetting.spread(p.mesh.positions_t0, Vec3(0, -9.81, 0), 1e-3, stats);
  double top = 0.0, bottom = 0.0;
  for (int i = 0; i < n; ++i) {
    top += wetting.water()[i];
    bottom += wetting.water()[(n - 1) * n + i];
  }
  EXPECT_GT(bottom, 2.0 * top) << "top row " << top << " kg, bottom row " << bottom << " kg";
  EXPECT_NEAR(wetting.held(), total, 1e-12 * total);
  // Without gravity the same water only diffuses: the top stays wetter.
  ClothWetting still(WettingSettings{}, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  still.set_water(water);
  for (int s = 0; s < 4000; ++s)
    still.spread(p.mesh.positions_t0, Vec3::Zero(), 1e-3, stats);
  EXPECT_GT(still.water()[0], still.water()[(n - 1) * n]);
}

TEST(ClothWetting, AbsorptionMovesMassFromParticlesIntoTheTouchedNodesOnly) {
  const Patch p = patch(3, 0.02);
  WettingSettings settings;
  settings.absorption_rate = 100.0;
  ClothWetting wetting(settings, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  const double particle = 1.25e-4;  // a 5 mm water particle, heavier than a node's capacity (2e-5 kg)
  ScalarArray masses{particle, particle};
  std::vector<std::uint8_t> remove(2, 0);
  const std::vector<WettingContact> contacts{{0, 0, Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3)}};
  WettingStepStats stats;
  wetting.absorb(contacts, masses, remove, 1e-3 * particle, 1e-3, stats);
  EXPECT_NEAR(masses[0], particle * (1.0 - 0.1), 1e-18);  // a dry cloth: absorption_rate dt of the mass
  EXPECT_EQ(masses[1], particle);
  EXPECT_NEAR(sum(masses) + wetting.held(), 2 * particle, 1e-18);
  const Triangle& t = p.mesh.triangles[0];
  for (std::size_t i = 0; i < p.mesh.node_count(); ++i) {
    const bool touched = i == t[0] || i == t[1] || i == t[2];
    EXPECT_EQ(wetting.water()[i] > 0.0, touched) << "node " << i;
  }
  // Until the nodes are full; then the particle keeps the rest.
  for (int s = 0; s < 1000; ++s)
    wetting.absorb(contacts, masses, remove, 1e-3 * particle, 1e-3, stats);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(wetting.water()[t[k]], wetting.capacities()[t[k]], 1e-9 * wetting.capacities()[t[k]]);
  EXPECT_EQ(remove[0], 0);
  EXPECT_NEAR(sum(masses) + wetting.held(), 2 * particle, 1e-18);
  EXPECT_NEAR(stats.absorbed_kg, wetting.held(), 1e-12 * wetting.held());  // summed in another order
}

TEST(ClothWetting, AParticleAbsorbedWholeIsFlaggedAndItsLastMassKept) {
  const Patch p = patch(3, 0.2);  // big nodes: capacity 2e-3 kg each
  WettingSettings settings;
  settings.absorption_rate = 1000.0;  // all of it in one step of 1 ms
  ClothWetting wetting(settings, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  ScalarArray masses{1.25e-4};
  std::vector<std::uint8_t> remove(1, 0);
  WettingStepStats stats;
  wetting.absorb({{0, 1, Vec3(0.2, 0.3, 0.5)}}, masses, remove, 1e-6, 1e-3, stats);
  EXPECT_EQ(remove[0], 1);
  EXPECT_EQ(masses[0], 0.0);
  EXPECT_EQ(stats.particles_absorbed, 1u);
  EXPECT_NEAR(wetting.held(), 1.25e-4, 1e-18);
}

TEST(ClothWetting, AnOverfullNodeDripsOneParticleBelowTheClothUnlessTheSpotIsTaken) {
  const Patch p = patch(5, 0.2);
  ClothWetting wetting(WettingSettings{}, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  const double particle = 1.25e-4;
  ScalarArray water(p.mesh.node_count(), 0.0);
  const std::size_t centre = 2 * 5 + 2;
  water[centre] = wetting.capacities()[centre] + 1.5 * particle;
  wetting.set_water(water);
  const double before = wetting.held();
  Vec3Array velocities(p.mesh.node_count(), Vec3(0.0, -0.5, 0.0));
  const Vec3 gravity(0, -9.81, 0);
  const double offset = 0.004, clearance = 0.0025;
  WettingStepStats stats;
  // A particle sits where the drop would go: nothing drips.
  const Vec3 below = p.mesh.positions_t0[centre] + Vec3(0, -offset, 0);
  EXPECT_TRUE(wetting
                  .drip(p.mesh.positions_t0, velocities, gravity, particle, offset,
                        {below + Vec3(0.001, 0, 0)}, clearance, stats)
                  .empty());
  EXPECT_EQ(wetting.held(), before);
  const std::vector<WettingDrop> drops =
      wetting.drip(p.mesh.positions_t0, velocities, gravity, particle, offset, {}, clearance, stats);
  ASSERT_EQ(drops.size(), 1u);
  EXPECT_EQ(drops[0].node, centre);
  EXPECT_LT((drops[0].position - below).norm(), 1e-15);  // on the side gravity pulls to
  EXPECT_EQ(drops[0].velocity, Vec3(0.0, -0.5, 0.0));
  EXPECT_NEAR(wetting.held() + particle, before, 1e-18);
  // 0.5 particle over capacity left: no second drop.
  EXPECT_TRUE(
      wetting.drip(p.mesh.positions_t0, velocities, gravity, particle, offset, {}, clearance, stats).empty());
}

// Settings built in code are held to the scene file's ranges: a diffusion of 1e6 m^2/s ran the explicit
// spread for minutes a step, and one past about 1e19 overflowed its sub-step count and spread nothing.
TEST(ClothWetting, SettingsOutOfRangeAreNamedBeforeTheMeshIsRead) {
  const Patch p = patch(3, 0.1);
  const auto refused = [&](const WettingSettings& settings, const std::string& message) {
    try {
      ClothWetting(settings, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
    } catch (const SceneError& e) {
      return std::string(e.what()).find(message) != std::string::npos;
    }
    return false;
  };
  WettingSettings s;
  s.diffusion = 1e6;
  EXPECT_TRUE(refused(s, "wetting.diffusion must be in [0, 1], got 1000000"));
  s = {};
  s.gravity_flow = 11.0;
  EXPECT_TRUE(refused(s, "wetting.gravity_flow must be in [0, 10], got 11"));
  s = {};
  s.absorption_rate = std::nan("");
  EXPECT_TRUE(refused(s, "wetting.absorption_rate must be >= 0, got nan"));
  s = {};
  s.max_saturation = 0.0;
  EXPECT_TRUE(refused(s, "wetting.max_saturation must be > 0, got 0"));
}

// At the largest diffusion a scene may ask for, one game step of 1/60 s on a fine patch (2.5 mm edges)
// spreads a wet spot over the whole 10 cm patch (sqrt(D dt) = 13 cm), conserving the water and keeping every
// node within its capacity, in a bounded count of explicit sub-steps.
TEST(ClothWetting, TheLargestDiffusionSpreadsAcrossThePatchInOneGameStep) {
  const Patch p = patch(41, 0.1);
  WettingSettings settings;
  settings.diffusion = kMaxWettingDiffusion;
  ClothWetting wetting(settings, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  ScalarArray water(p.mesh.node_count(), 0.0);
  const std::size_t centre = 20 * 41 + 20;
  water[centre] = wetting.capacities()[centre];
  wetting.set_water(water);
  const double total = wetting.held();
  WettingStepStats stats;
  wetting.spread(p.mesh.positions_t0, Vec3(0, -9.81, 0), 1.0 / 60.0, stats);
  EXPECT_NEAR(wetting.held(), total, 1e-12 * total);
  const double uniform = total / sum(wetting.capacities());
  for (std::size_t i = 0; i < water.size(); ++i) {
    ASSERT_LE(wetting.water()[i], wetting.capacities()[i] * (1.0 + 1e-12)) << "node " << i;
    ASSERT_NEAR(wetting.water()[i] / wetting.capacities()[i], uniform, 0.05 * uniform) << "node " << i;
  }
  // dt x (the fastest node's rate, about 8 D / edge^2) / 0.5: about 4e4.
  EXPECT_LT(stats.spread_substeps, 100000u);
}

TEST(ClothWetting, BadMeshesAndMassesAreNamed) {
  const Patch p = patch(3, 0.1);
  ScalarArray masses = p.dry_masses;
  masses[4] = 0.0;
  try {
    ClothWetting(WettingSettings{}, p.mesh.triangles, p.mesh.positions_t0, masses);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("node 4"), std::string::npos) << e.what();
  }
  std::vector<Triangle> triangles = p.mesh.triangles;
  triangles[2][1] = 99;
  try {
    ClothWetting(WettingSettings{}, triangles, p.mesh.positions_t0, p.dry_masses);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 2"), std::string::npos) << e.what();
  }
  Vec3Array positions = p.mesh.positions_t0;
  positions[1] = positions[0];
  EXPECT_THROW(ClothWetting(WettingSettings{}, p.mesh.triangles, positions, p.dry_masses), Error);
  ClothWetting wetting(WettingSettings{}, p.mesh.triangles, p.mesh.positions_t0, p.dry_masses);
  EXPECT_THROW(wetting.set_water(ScalarArray(9, -1.0)), Error);
  EXPECT_THROW(wetting.set_water(ScalarArray(3, 0.0)), Error);
}

// Two cloths of 3 x 3 nodes in one mesh; the first is torn (a node added off its edge, with a face of its
// own): each node's water and capacity move with it, the new node holds none, the water held stays what it
// was, and the spread after it still conserves it.
TEST(ClothWetting, ATornClothsWaterStaysWithItsNodes) {
  const Patch one = patch(3, 0.1);
  ClothMesh two;
  Vec3Array positions;
  ScalarArray dry;
  for (int c = 0; c < 2; ++c) {
    const auto offset = static_cast<Index>(9 * c);
    for (const Triangle& t : one.mesh.triangles)
      two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    for (const Vec3& x : one.mesh.positions_t0)
      positions.push_back(x + Vec3(0.5 * c, 0.0, 0.0));
    dry.insert(dry.end(), one.dry_masses.begin(), one.dry_masses.end());
  }
  WettingSettings settings;
  ClothWetting wetting(settings, two.triangles, positions, dry);
  ScalarArray water(18);
  for (std::size_t i = 0; i < 18; ++i)
    water[i] = 0.01 * static_cast<double>(i + 1) * wetting.capacities()[i];
  wetting.set_water(water);
  const ScalarArray capacities = wetting.capacities();
  const double held = wetting.held();

  // Node 9 of the new layout is cloth 0's new node, just off its edge between nodes 0 and 1; cloth 1's
  // nodes are 10-18 now.
  std::vector<Triangle> torn;
  for (const Triangle& t : one.mesh.triangles)
    torn.push_back(t);
  torn.push_back({0, 9, 1});
  for (const Triangle& t : one.mesh.triangles)
    torn.push_back({t[0] + 10, t[1] + 10, t[2] + 10});
  Vec3Array now(positions.begin(), positions.begin() + 9);
  now.push_back(0.5 * (positions[0] + positions[1]) + Vec3(0.0, 0.0, -0.02));
  now.insert(now.end(), positions.begin() + 9, positions.end());
  ScalarArray dry_now(dry.begin(), dry.begin() + 9);
  dry_now.push_back(0.5 * dry[0]);
  dry_now.insert(dry_now.end(), dry.begin() + 9, dry.end());
  const ClothLayoutChange change({{0, 9, 0, 8}, {9, 9, 8, 8}}, {{0, 10, 0, 9}, {10, 9, 9, 8}});

  // A new node without a mass is refused, and nothing changes.
  ScalarArray massless = dry_now;
  massless[9] = 0.0;
  try {
    wetting.follow(change, torn, now, massless);
    FAIL() << "a new node of mass 0";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cloth node 9 has mass 0"), std::string::npos) << e.what();
  }
  ASSERT_EQ(wetting.water(), water);

  wetting.follow(change, torn, now, dry_now);
  ASSERT_EQ(wetting.water().size(), 19u);
  for (std::size_t old = 0; old < 18; ++old) {
    const std::size_t i = old < 9 ? old : old + 1;
    EXPECT_EQ(wetting.water()[i], water[old]) << old;
    EXPECT_EQ(wetting.capacities()[i], capacities[old]) << old;
  }
  EXPECT_EQ(wetting.water()[9], 0.0);
  EXPECT_EQ(wetting.capacities()[9], settings.max_saturation * dry_now[9]);
  EXPECT_EQ(wetting.held(), held);
  WettingStepStats stats;
  for (int s = 0; s < 100; ++s)
    wetting.spread(now, Vec3(0, -9.81, 0), 0.01, stats);
  EXPECT_NEAR(wetting.held(), held, 1e-12 * held);
  EXPECT_GT(wetting.water()[9], 0.0) << "the new node takes water from its neighbours";
  // Each cloth's water stays in it (they share no edge): cloth 0's nodes, the new one included, and cloth
  // 1's, now at 10-18.
  const ScalarArray& after = wetting.water();
  const double cloth0 = std::accumulate(water.begin(), water.begin() + 9, 0.0);
  EXPECT_NEAR(std::accumulate(after.begin(), after.begin() + 10, 0.0), cloth0, 1e-12 * cloth0);
  const double cloth1 = std::accumulate(water.begin() + 9, water.end(), 0.0);
  EXPECT_NEAR(std::accumulate(after.begin() + 10, after.end(), 0.0), cloth1, 1e-12 * cloth1);
}

}  // namespace
}  // namespace drench
