// The soft bodies the adapter builds from ClothSettings: topology, masses, pins, and the two builders that
// replace Bullet helpers with quadratic memory, compared link by link with those helpers.

#include <drench/bullet/soft_body_builder.hpp>

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../temp_dir.hpp"
#include "bullet_test_helpers.hpp"

namespace drench::bullet {
namespace {

using test::as_bullet;
using test::bullet_tolerance;
using test::expect_scene_error;
using test::patch_settings;

int material_index(const btSoftBody& body, const btSoftBody::Material* m) {
  return body.m_materials.findLinearSearch(const_cast<btSoftBody::Material*>(m));
}

// Same links in the same order: end nodes, rest length (bitwise), bending flag, material.
void expect_same_links(const btSoftBody& a, const btSoftBody& b) {
  ASSERT_EQ(a.m_links.size(), b.m_links.size());
  for (int l = 0; l < a.m_links.size(); ++l) {
    const auto& la = a.m_links[l];
    const auto& lb = b.m_links[l];
    ASSERT_EQ(node_index(a, la.m_n[0]), node_index(b, lb.m_n[0])) << "link " << l;
    ASSERT_EQ(node_index(a, la.m_n[1]), node_index(b, lb.m_n[1])) << "link " << l;
    ASSERT_EQ(la.m_rl, lb.m_rl) << "link " << l;
    ASSERT_EQ(la.m_bbending, lb.m_bbending) << "link " << l;
    ASSERT_EQ(material_index(a, la.m_material), material_index(b, lb.m_material)) << "link " << l;
  }
}

// An irregular mesh: a 7 x 6 grid with diagonals in both directions and a fan of 5 triangles around an extra
// vertex glued to one edge, orientation mixed.
TriangleMesh irregular_mesh() {
  TriangleMesh mesh;
  const int nx = 7, nz = 6;
  for (int k = 0; k < nz; ++k) {
    for (int i = 0; i < nx; ++i)
      mesh.positions.emplace_back(0.1 * i + 0.01 * k * k, 0.02 * std::sin(i + k), 0.1 * k);
  }
  auto id = [&](int i, int k) { return static_cast<Index>(k * nx + i); };
  for (int k = 0; k + 1 < nz; ++k) {
    for (int i = 0; i + 1 < nx; ++i) {
      if ((i * 3 + k) % 4 == 0) {
        mesh.triangles.push_back({id(i, k), id(i + 1, k), id(i + 1, k + 1)});
        mesh.triangles.push_back({id(i, k), id(i, k + 1), id(i + 1, k + 1)});  // clockwise
      } else {
        mesh.triangles.push_back({id(i, k + 1), id(i, k), id(i + 1, k)});
        mesh.triangles.push_back({id(i, k + 1), id(i + 1, k), id(i + 1, k + 1)});
      }
    }
  }
  const Index hub = static_cast<Index>(mesh.positions.size());
  mesh.positions.emplace_back(0.3, 0.0, -0.15);
  for (int i = 0; i < 5; ++i)
    mesh.triangles.push_back({hub, id(i + 1, 0), id(i, 0)});
  return mesh;
}

TEST(SoftBodyBuilder, PatchHasTwoTrianglesPerGridCellWithValidIndices) {
  btSoftBodyWorldInfo info;
  for (auto [nx, nz] : {std::pair{57, 57}, std::pair{2, 2}, std::pair{5, 3}}) {
    const auto body = create_cloth_body(info, patch_settings(nx, nz));
    ASSERT_EQ(body->m_nodes.size(), nx * nz);
    ASSERT_EQ(body->m_faces.size(), 2 * (nx - 1) * (nz - 1));
    for (int f = 0; f < body->m_faces.size(); ++f) {
      int idx[3];
      for (int k = 0; k < 3; ++k) {
        idx[k] = node_index(*body, body->m_faces[f].m_n[k]);
        ASSERT_GE(idx[k], 0);
        ASSERT_LT(idx[k], nx * nz);
      }
      ASSERT_TRUE(idx[0] != idx[1] && idx[1] != idx[2] && idx[0] != idx[2]) << "face " << f;
    }
  }
  EXPECT_EQ(create_cloth_body(info, patch_settings(57, 57))->m_faces.size(), 6272);
}

TEST(SoftBodyBuilder, PatchNodesLieOnTheGridInThePlaneOfTheCentre) {
  btSoftBodyWorldInfo info;
  const ClothSettings s = patch_settings(9, 5);
  const auto body = create_cloth_body(info, s);
  const double dx = s.size_x / (s.nodes_x - 1), dz = s.size_z / (s.nodes_z - 1);
  for (int k = 0; k < s.nodes_z; ++k) {
    for (int i = 0; i < s.nodes_x; ++i) {
      const Vec3 expected = s.center + Vec3(-0.5 * s.size_x + i * dx, 0.0, -0.5 * s.size_z + k * dz);
      const Vec3 x = to_vec3(body->m_nodes[k * s.nodes_x + i].m_x);
      EXPECT_LT((x - expected).norm(), bullet_tolerance(1e-15, expected.norm()))
          << "node (" << i << ", " << k << ")";  // lerp rounding (m)
      EXPECT_EQ(x.y(), as_bullet(s.center.y()));
    }
  }
}

TEST(SoftBodyBuilder, NodeMassesAreAreaDensityTimesAdjacentAreaOverThree) {
  btSoftBodyWorldInfo info;
  const ClothSettings s = patch_settings(57, 57, "none");
  const auto body = create_cloth_body(info, s);
  const double cell = s.size_x / (s.nodes_x - 1) * (s.size_z / (s.nodes_z - 1));
  std::vector<int> adjacent(body->m_nodes.size(), 0);
  for (int f = 0; f < body->m_faces.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      ++adjacent[node_index(*body, body->m_faces[f].m_n[k])];
  }
  const ScalarArray set = node_masses_from_area(*body, s.area_density);
  // The areas come from corners Bullet stores rounded: an edge of length l between points of size |x| is off
  // by about |x| / l units of rounding.
  const double area_ulps = 4.0 * (s.center.norm() + s.size_x) / (s.size_z / (s.nodes_z - 1));
  double total = 0;
  for (int i = 0; i < body->m_nodes.size(); ++i) {
    const double expected = s.area_density * adjacent[i] * (0.5 * cell) / 3.0;
    const double im = body->m_nodes[i].m_im;
    EXPECT_EQ(im, as_bullet(1.0 / as_bullet(set[i]))) << "node " << i;  // setMass stores exactly 1 / mass
    EXPECT_NEAR(1.0 / im, expected, bullet_tolerance(1e-12 * expected, expected, area_ulps)) << "node " << i;
    EXPECT_NEAR(body->getMass(i), expected, bullet_tolerance(1e-12 * expected, expected, area_ulps))
        << "node " << i;
    total += 1.0 / im;
  }
  const double cloth_mass = s.area_density * s.size_x * s.size_z;
  // A sum of n rounded terms is within n units of rounding of the total.
  const double n = body->m_nodes.size();
  EXPECT_NEAR(total, cloth_mass, bullet_tolerance(1e-12 * cloth_mass, cloth_mass, area_ulps + n));
  EXPECT_NEAR(body->getTotalMass(), cloth_mass,
              bullet_tolerance(1e-12 * cloth_mass, cloth_mass, area_ulps + n));
}

TEST(SoftBodyBuilder, PinnedNodesHaveInverseMassZeroAndNoOtherDoes) {
  btSoftBodyWorldInfo info;
  const int nx = 6, nz = 4;
  const std::vector<std::pair<std::string, std::vector<int>>> cases = {
      {"corners", {0, nx - 1, (nz - 1) * nx, nz * nx - 1}}, {"corner", {0}}, {"none", {}}};
  for (const auto& [pinned, expected] : cases) {
    const auto body = create_cloth_body(info, patch_settings(nx, nz, pinned));
    EXPECT_EQ(pinned_nodes(*body, pinned), expected) << pinned;
    for (int i = 0; i < body->m_nodes.size(); ++i) {
      const bool is_pinned = std::find(expected.begin(), expected.end(), i) != expected.end();
      if (is_pinned) {
        EXPECT_EQ(body->m_nodes[i].m_im, 0.0) << pinned << " node " << i;
      } else {
        EXPECT_GT(body->m_nodes[i].m_im, 0.0) << pinned << " node " << i;
      }
    }
  }
}

TEST(SoftBodyBuilder, CorneredPatchIsNotUnpinnedByItsSetup) {
  // setTotalMass(m, true) would un-pin every node; the builder sets masses node by node. The corners of the
  // 2 x 2 patch are all its nodes: every one stays pinned.
  btSoftBodyWorldInfo info;
  const auto body = create_cloth_body(info, patch_settings(2, 2, "corners"));
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(body->m_nodes[i].m_im, 0.0);
  EXPECT_EQ(body->getTotalMass(), 0.0);
}

TEST(SoftBodyBuilder, SettingsReachTheBody) {
  btSoftBodyWorldInfo info;
  ClothSettings s = patch_settings(8, 8);
  s.position_iterations = 7;
  s.stretch_stiffness = 0.8;
  s.bending_stiffness = 0.3;
  s.damping = 0.05;
  const auto body = create_cloth_body(info, s);
  EXPECT_EQ(body->getCollisionShape()->getMargin(), as_bullet(CLOTH_COLLISION_MARGIN));
  EXPECT_EQ(body->m_cfg.piterations, 7);
  EXPECT_EQ(body->m_cfg.kDP, as_bullet(0.05));
  EXPECT_EQ(body->m_cfg.collisions, int(btSoftBody::fCollision::SDF_RS));
  ASSERT_EQ(body->m_materials.size(), 2);
  EXPECT_EQ(body->m_materials[0]->m_kLST, as_bullet(0.8));
  EXPECT_EQ(body->m_materials[1]->m_kLST, as_bullet(0.3));
  int bending = 0;
  for (int l = 0; l < body->m_links.size(); ++l) {
    const bool is_bending = body->m_links[l].m_bbending != 0;
    bending += is_bending;
    EXPECT_EQ(body->m_links[l].m_material, body->m_materials[is_bending ? 1 : 0]) << "link " << l;
  }
  EXPECT_GT(bending, 0);

  s.bending_stiffness = 0.0;
  const auto flat = create_cloth_body(info, s);
  EXPECT_EQ(flat->m_materials.size(), 1);
  for (int l = 0; l < flat->m_links.size(); ++l)
    EXPECT_EQ(flat->m_links[l].m_bbending, 0) << "link " << l;
}

TEST(SoftBodyBuilder, BendingLinksEqualBulletsGenerateBendingConstraints) {
  btSoftBodyWorldInfo info;
  auto patch = [&](int nx, int nz) {
    return std::unique_ptr<btSoftBody>(btSoftBodyHelpers::CreatePatch(info, btVector3(0, 0, 0),
                                                                      btVector3(1, 0, 0), btVector3(0, 0, 1),
                                                                      btVector3(1, 0, 1), nx, nz, 0, true));
  };
  for (auto [nx, nz] : {std::pair{9, 7}, std::pair{57, 57}}) {
    auto ours = patch(nx, nz);
    auto bullets = patch(nx, nz);
    const int appended = append_bending_links(*ours, ours->appendMaterial());
    const int generated = bullets->generateBendingConstraints(2, bullets->appendMaterial());
    EXPECT_EQ(appended, generated);
    EXPECT_GT(appended, 0);
    expect_same_links(*ours, *bullets);
  }
  // An irregular mesh, with links in CreateFromTriMesh's shuffled order.
  const TriangleMesh mesh = irregular_mesh();
  auto ours = create_from_triangles(info, mesh);
  auto bullets = create_from_triangles(info, mesh);
  EXPECT_EQ(append_bending_links(*ours, ours->appendMaterial()),
            bullets->generateBendingConstraints(2, bullets->appendMaterial()));
  expect_same_links(*ours, *bullets);
}

TEST(SoftBodyBuilder, FromTrianglesEqualsBulletsCreateFromTriMesh) {
  btSoftBodyWorldInfo info;
  const TriangleMesh mesh = irregular_mesh();
  std::vector<btScalar> vertices;
  for (const Vec3& x : mesh.positions)
    vertices.insert(vertices.end(), {btScalar(x.x()), btScalar(x.y()), btScalar(x.z())});
  std::vector<int> indices;
  for (const Triangle& t : mesh.triangles)
    indices.insert(indices.end(), {int(t[0]), int(t[1]), int(t[2])});
  const std::unique_ptr<btSoftBody> bullets(btSoftBodyHelpers::CreateFromTriMesh(
      info, vertices.data(), indices.data(), static_cast<int>(mesh.triangles.size()), true));
  const auto ours = create_from_triangles(info, mesh);

  ASSERT_EQ(ours->m_nodes.size(), bullets->m_nodes.size());
  for (int i = 0; i < ours->m_nodes.size(); ++i) {
    EXPECT_EQ(ours->m_nodes[i].m_x, bullets->m_nodes[i].m_x) << "node " << i;
    EXPECT_EQ(ours->m_nodes[i].m_im, bullets->m_nodes[i].m_im) << "node " << i;
  }
  expect_same_links(*ours, *bullets);
  ASSERT_EQ(ours->m_faces.size(), bullets->m_faces.size());
  for (int f = 0; f < ours->m_faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(node_index(*ours, ours->m_faces[f].m_n[k]), node_index(*bullets, bullets->m_faces[f].m_n[k]))
          << "face " << f;
    }
  }
}

TEST(SoftBodyBuilder, ObjMeshIsTriangulatedAndUnusedVerticesDropped) {
  // A 2 x 1 strip of quads (6 vertices) plus a vertex no face uses, in two objects.
  const drench::test::TempDir dir;
  const std::string path = dir.write("strip.obj",
                                     "# strip\n"
                                     "o left\n"
                                     "v 0 1 0\nv 0.5 1 0\nv 1 1 0\n"
                                     "v 9 9 9\n"
                                     "v 0 1 0.5\nv 0.5 1 0.5\nv 1 1 0.5\n"
                                     "f 1 2 6 5\n"
                                     "o right\n"
                                     "f 2 3 7 6\n");
  const TriangleMesh mesh = load_obj_mesh(path);
  ASSERT_EQ(mesh.positions.size(), 6u);
  ASSERT_EQ(mesh.triangles.size(), 4u);
  for (const Vec3& x : mesh.positions)
    EXPECT_NE(x, Vec3(9, 9, 9));
  EXPECT_EQ(mesh.positions[3], Vec3(0, 1, 0.5));  // file vertex 5 after the unused vertex 4

  ClothSettings s;
  s.mesh = path;
  s.area_density = 0.3;
  s.pinned = "none";
  btSoftBodyWorldInfo info;
  const auto body = create_cloth_body(info, s);
  EXPECT_EQ(body->m_nodes.size(), 6);
  EXPECT_EQ(body->m_faces.size(), 4);
  const double cloth_mass = 0.3 * 1.0 * 0.5;
  EXPECT_NEAR(body->getTotalMass(), cloth_mass, bullet_tolerance(1e-12 * cloth_mass, cloth_mass, 6));

  s.pinned = "corners";  // the nodes extreme in -x-z, x-z, -x+z, x+z: the strip's four corners
  const auto pinned = create_cloth_body(info, s);
  EXPECT_EQ(pinned_nodes(*pinned, "corners"), (std::vector<int>{0, 2, 3, 5}));
}

TEST(SoftBodyBuilder, BadSettingsThrowSceneErrorNamingTheSetting) {
  btSoftBodyWorldInfo info;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto expect_bad = [&](const std::function<void(ClothSettings&)>& change,
                        std::initializer_list<std::string> parts) {
    ClothSettings s = patch_settings(5, 5);
    change(s);
    expect_scene_error([&] { validate_cloth_settings(s); }, parts);
    expect_scene_error([&] { create_cloth_body(info, s); }, parts);
  };
  expect_bad([](ClothSettings& s) { s.size_x = -1; }, {"cloth.size_x must be > 0", "got -1"});
  expect_bad([](ClothSettings& s) { s.size_z = 0; }, {"cloth.size_z must be > 0", "got 0"});
  expect_bad([&](ClothSettings& s) { s.size_x = nan; }, {"cloth.size_x", "nan"});
  expect_bad([](ClothSettings& s) { s.nodes_x = 1; }, {"cloth.nodes_x must be >= 2", "got 1"});
  expect_bad([](ClothSettings& s) { s.nodes_z = -3; }, {"cloth.nodes_z must be >= 2", "got -3"});
  expect_bad([](ClothSettings& s) { s.nodes_x = s.nodes_z = 100000; }, {"cloth.nodes_x", "nodes_z"});
  expect_bad([&](ClothSettings& s) { s.center.y() = nan; }, {"cloth.center must be finite", "nan"});
  expect_bad([](ClothSettings& s) { s.area_density = 0; }, {"cloth.area_density must be > 0", "got 0"});
  expect_bad([&](ClothSettings& s) { s.area_density = nan; }, {"cloth.area_density", "nan"});
  expect_bad([](ClothSettings& s) { s.pinned = "edges"; }, {"cloth.pinned must be one of", "\"edges\""});
  expect_bad([](ClothSettings& s) { s.position_iterations = 1; },
             {"cloth.position_iterations must be in [4, 1000]", "got 1"});
  expect_bad([](ClothSettings& s) { s.position_iterations = 1001; },
             {"cloth.position_iterations must be in [4, 1000]", "got 1001"});
  expect_bad([](ClothSettings& s) { s.substeps = 0; }, {"cloth.substeps must be in [1, 1000]", "got 0"});
  expect_bad([](ClothSettings& s) { s.substeps = 1001; },
             {"cloth.substeps must be in [1, 1000]", "got 1001"});
  expect_bad([](ClothSettings& s) { s.stretch_stiffness = 0; },
             {"cloth.stretch_stiffness must be in (0, 1]"});
  expect_bad([](ClothSettings& s) { s.bending_stiffness = 1.5; }, {"cloth.bending_stiffness", "got 1.5"});
  expect_bad([](ClothSettings& s) { s.damping = -0.1; }, {"cloth.damping must be in [0, 1]", "got -0.1"});
  expect_bad([](ClothSettings& s) { s.mesh = ""; }, {"cloth.mesh"});
}

TEST(SoftBodyBuilder, BadObjFilesThrowSceneErrorNamingTheFile) {
  btSoftBodyWorldInfo info;
  const drench::test::TempDir dir;
  auto expect_bad_obj = [&](const std::string& text, const std::string& problem) {
    const std::string path = dir.write("bad.obj", text);
    ClothSettings s;
    s.mesh = path;
    expect_scene_error([&] { create_cloth_body(info, s); }, {"cloth.mesh", path, problem});
  };
  {
    ClothSettings s;
    s.mesh = "/nonexistent/cloth.obj";
    expect_scene_error([&] { create_cloth_body(info, s); },
                       {"cloth.mesh", "/nonexistent/cloth.obj", "cannot be read", "No such file"});
  }
  expect_bad_obj("", "has no faces");
  expect_bad_obj("# only vertices\nv 0 0 0\nv 1 0 0\nv 0 0 1\n", "has no faces");
  expect_bad_obj("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2\n", "line 4: a face needs at least 3 vertices, got 2");
  expect_bad_obj("v nan 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n",
                 "line 1: vertex coordinate \"nan\" is not a finite");
  expect_bad_obj("v 0 0 0\nv 1 abc 0\nv 0 0 1\nf 1 2 3\n", "line 2: vertex coordinate \"abc\"");
  expect_bad_obj("v 0 0 0\nv 1 0\n", "line 2: a vertex needs 3 coordinates");
  expect_bad_obj("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 7\n", "vertex index 7 out of range 1..3");
  expect_bad_obj("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 1 2\n", "face 1 that repeats a vertex (1 1 2)");
  expect_bad_obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "face 1 of zero area");
}

}  // namespace
}  // namespace drench::bullet
