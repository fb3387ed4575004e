// Static obstacles (coupling/static_obstacles.hpp): the built-in V of Fig. 8, the cloth and obstacles as one
// mesh for the coupling, and a jet into the V through Simulation with no cloth at all.

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/coupling/static_obstacles.hpp>
#include <drench/scene/simulation.hpp>

namespace drench {
namespace {

constexpr double kPi = 3.14159265358979323846;

ObstacleSettings v_plane(double angle_deg = 90.0) {
  ObstacleSettings s;
  s.center = Vec3(0.1, 0.2, -0.05);
  s.angle_deg = angle_deg;
  s.size = 0.2;
  s.width = 0.1;
  s.triangle_size = 0.02;
  return s;
}

/// Height of the V's surface above its edge at horizontal offset dx from it (unit: m).
double v_height(const ObstacleSettings& s, double dx) {
  return std::abs(dx) / std::tan(0.5 * s.angle_deg * kPi / 180.0);
}

TEST(StaticObstacles, VPlaneLiesOnItsTwoPlanesAndSharesItsEdge) {
  for (double angle : {60.0, 90.0, 150.0}) {
    const ObstacleSettings s = v_plane(angle);
    const TriangleMesh mesh = v_plane_mesh(s);
    ASSERT_NO_THROW(validate_triangle_mesh(mesh, "v"));
    // 10 squares along each plane, 5 across, two triangles each.
    EXPECT_EQ(mesh.triangles.size(), 2u * 2u * 10u * 5u) << angle;
    EXPECT_EQ(mesh.positions.size(), 21u * 6u) << angle;
    for (const Vec3& x : mesh.positions) {
      const Vec3 d = x - s.center;
      EXPECT_NEAR(d.y(), v_height(s, d.x()), 1e-12) << angle;
      EXPECT_LE(std::hypot(d.x(), d.y()), s.size + 1e-12) << angle;
      EXPECT_LE(std::abs(d.z()), 0.5 * s.width + 1e-12) << angle;
    }
    // One surface: every interior edge is shared by exactly two triangles, the edge of the V included, so
    // nothing can slip between the planes.
    std::set<std::pair<Index, Index>> once, twice;
    for (const Triangle& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const auto e = std::minmax(t[k], t[(k + 1) % 3]);
        if (!once.insert(e).second) {
          EXPECT_TRUE(twice.insert(e).second) << "an edge in three triangles";
        }
      }
    }
    int edge_of_v = 0;
    for (const auto& [a, b] : twice) {
      if (std::abs(mesh.positions[a].y() - s.center.y()) < 1e-12 &&
          std::abs(mesh.positions[b].y() - s.center.y()) < 1e-12)
        ++edge_of_v;
    }
    EXPECT_EQ(edge_of_v, 5) << "the segments along the V's edge are each shared by both planes";
    // Every normal points into the V (up, towards the middle).
    for (const Triangle& t : mesh.triangles) {
      const Vec3& a = mesh.positions[t[0]];
      const Vec3 n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);
      const Vec3 centroid = (a + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
      EXPECT_GT(n.y(), 0.0);
      EXPECT_LT(n.x() * (centroid.x() - s.center.x()), 0.0);
    }
  }
}

TEST(StaticObstacles, VPlaneSettingsOutOfRangeNameTheKey) {
  ObstacleSettings s = v_plane();
  s.angle_deg = 180.0;
  try {
    v_plane_mesh(s, "obstacles[2]");
    FAIL() << "angle 180 accepted";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "obstacles[2].angle_deg must be in (0, 180), got 180");
  }
  s = v_plane();
  s.triangle_size = std::nan("");
  EXPECT_THROW(v_plane_mesh(s, "obstacles[0]"), SceneError);
  s = v_plane();
  s.size = 0.0;
  EXPECT_THROW(v_plane_mesh(s, "obstacles[0]"), SceneError);
}

TEST(StaticObstacles, InvalidMeshesAreRefusedByName) {
  TriangleMesh flat{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)}, {{0, 1, 2}}};
  try {
    ClothWithObstacles both(nullptr, {v_plane_mesh(v_plane()), flat});
    FAIL() << "a zero-area triangle accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "obstacles[1]: triangle 0 has zero area");
  }
  TriangleMesh out_of_range{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {{0, 1, 3}}};
  EXPECT_THROW(ClothWithObstacles(nullptr, {out_of_range}), Error);
  EXPECT_THROW(ClothWithObstacles(nullptr, {TriangleMesh{}}), Error);
}

/// A cloth engine that records what the composite hands it.
class RecordingCloth final : public ClothEngine {
 public:
  RecordingCloth() { m_mesh = ClothMesh::grid(3, 0.1, 0.5, 2.0); }
  void begin_step() override { m_mesh.positions_t0 = m_mesh.positions_t1; }
  void apply_impulses(const Vec3Array& impulses) override { received = impulses; }
  void set_carried_masses(const ScalarArray& carried) override { carried_received = carried; }
  void step(double dt) override {
    for (Vec3& x : m_mesh.positions_t1)
      x.y() -= 0.1 * dt;
  }
  ClothMesh& mesh() override { return m_mesh; }
  void end_step(double) override { ended_with = m_mesh.positions_t1; }
  Vec3Array velocities() const override { return Vec3Array(m_mesh.node_count(), Vec3(0, -0.1, 0)); }
  double total_mass() const override { return 4.5; }

  Vec3Array received, ended_with;
  ScalarArray carried_received;

 private:
  ClothMesh m_mesh;
};

TEST(StaticObstacles, CompositeHandsTheClothItsOwnNodesOnly) {
  RecordingCloth cloth;
  const TriangleMesh v = v_plane_mesh(v_plane());
  ClothWithObstacles both(&cloth, {v});
  const std::size_t m = cloth.mesh().node_count();
  const std::size_t total = m + v.positions.size();
  both.begin_step();
  ASSERT_EQ(both.mesh().node_count(), total);
  ASSERT_EQ(both.mesh().triangle_count(), cloth.mesh().triangle_count() + v.triangles.size());
  ASSERT_NO_THROW(both.mesh().validate());
  for (std::size_t i = m; i < total; ++i)
    EXPECT_EQ(both.mesh().inverse_masses[i], 0.0);
  both.apply_impulses(Vec3Array(total, Vec3(1, 2, 3)));
  EXPECT_EQ(cloth.received.size(), m);
  both.set_carried_masses(ScalarArray(total, 0.5));
  EXPECT_EQ(cloth.carried_received.size(), m);
  both.step(0.01);
  for (std::size_t i = 0; i < m; ++i)
    EXPECT_EQ(both.mesh().positions_t1[i], cloth.mesh().positions_t1[i]);
  // The coupler corrects the end positions of the composite; the cloth's end_step must see them.
  both.mesh().positions_t1[1].y() += 0.25;
  const Vec3 corrected = both.mesh().positions_t1[1];
  both.end_step(0.01);
  EXPECT_EQ(cloth.ended_with[1], corrected);
  for (std::size_t i = 0; i < v.positions.size(); ++i)
    EXPECT_EQ(both.mesh().positions_t1[m + i], v.positions[i]) << "obstacle node " << i << " moved";
  EXPECT_EQ(both.velocities().size(), total);
  EXPECT_EQ(both.velocities()[total - 1], Vec3::Zero());
  EXPECT_EQ(both.total_mass(), 4.5);
}

/// A jet into the V of ObstacleSettings at `dt`, with no cloth: the obstacle alone is coupled.
SceneConfig jet_into_v(double dt) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0.03, 0.1, 0);
  jet.nozzle.radius = 0.01;
  jet.nozzle.speed = 2.0;
  jet.nozzle.max_particles = 1500;
  c.emitters.push_back(jet);
  KillRegionSettings kill;
  kill.point = Vec3(0, -0.3, 0);
  c.kill_regions.push_back(kill);
  ObstacleSettings v;
  v.center = Vec3(0, -0.1, 0);
  v.size = 0.15;
  v.width = 0.1;
  v.triangle_size = 0.01;
  c.obstacles.push_back(v);
  c.time.dt = dt;
  c.time.duration = 0.2;
  c.effects = {"coupling", "leak_audit"};
  return c;
}

TEST(StaticObstacles, JetIntoAVNeverLeaks) {
  for (double dt : {0.001, 0.004}) {
    const SceneConfig config = jet_into_v(dt);
    Simulation sim(config);
    ASSERT_EQ(sim.cloth(), nullptr);
    ASSERT_EQ(sim.obstacles().size(), 1u);
    while (!sim.finished())
      ASSERT_TRUE(sim.step().ok()) << "dt " << dt;
    EXPECT_EQ(sim.leak_stats().leaks, 0u) << "dt " << dt;
    EXPECT_GT(sim.coupling_stats().contacts, 0u) << "dt " << dt;
    // Every particle over the V's footprint is above its surface, less the cloth thickness the coupling
    // keeps particles within (sec. 3.1).
    const ObstacleSettings& v = config.obstacles[0];
    const double half_span = v.size * std::sin(0.5 * v.angle_deg * kPi / 180.0);
    std::size_t over = 0;
    for (const Vec3& x : sim.particles().positions) {
      const Vec3 d = x - v.center;
      if (std::abs(d.x()) < half_span && std::abs(d.z()) < 0.5 * v.width) {
        ++over;
        EXPECT_GT(d.y(), v_height(v, d.x()) - config.coupling.cloth_thickness) << "dt " << dt;
      }
    }
    EXPECT_GT(over, 100u) << "dt " << dt << ": the V holds water";
  }
}

}  // namespace
}  // namespace drench
