#include <drench/coupling/cloth_mesh.hpp>

#include <cmath>
#include <cstring>
#include <string>

#include <drench/common/error.hpp>

namespace drench {

ClothMesh ClothMesh::rigid(const Vec3Array& positions, std::vector<Triangle> triangles) {
  ClothMesh mesh;
  mesh.positions_t0 = positions;
  mesh.positions_t1 = positions;
  mesh.inverse_masses.assign(positions.size(), 0.0);
  mesh.triangles = std::move(triangles);
  return mesh;
}

ClothMesh ClothMesh::grid(int n, double size, double y, double inverse_mass, double x0, double z0) {
  ClothMesh mesh;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i)
      mesh.positions_t0.emplace_back(x0 + size * i / (n - 1), y, z0 + size * j / (n - 1));
  }
  mesh.positions_t1 = mesh.positions_t0;
  mesh.inverse_masses.assign(mesh.positions_t0.size(), inverse_mass);
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const auto a = static_cast<Index>(j * n + i);
      const Index b = a + 1;
      const Index c = a + static_cast<Index>(n);
      const Index d = c + 1;
      mesh.triangles.push_back({a, c, b});
      mesh.triangles.push_back({b, c, d});
    }
  }
  return mesh;
}

void ClothMesh::validate() const {
  const std::size_t m = positions_t0.size();
  if (positions_t1.size() != m || inverse_masses.size() != m) {
    throw Error(
        "cloth mesh: positions_t0, positions_t1 and inverse_masses must have one entry per node, got " +
        std::to_string(m) + ", " + std::to_string(positions_t1.size()) + " and " +
        std::to_string(inverse_masses.size()));
  }
  for (std::size_t i = 0; i < m; ++i) {
    if (!positions_t0[i].allFinite() || !positions_t1[i].allFinite()) {
      throw Error("cloth mesh: node " + std::to_string(i) + " has a non-finite position");
    }
    if (!(inverse_masses[i] >= 0.0) || !std::isfinite(inverse_masses[i])) {
      throw Error("cloth mesh: node " + std::to_string(i) + " has inverse mass " +
                  format_number(inverse_masses[i]) + ", must be finite and >= 0");
    }
  }
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    for (Index v : t) {
      if (v >= m) {
        throw Error("cloth mesh: triangle " + std::to_string(f) + " has node index " + std::to_string(v) +
                    ", but the mesh has " + std::to_string(m) + " nodes");
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw Error("cloth mesh: triangle " + std::to_string(f) + " repeats a node (" + std::to_string(t[0]) +
                  ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) + ")");
    }
  }
}

bool same_triangles(const std::vector<Triangle>& a, const std::vector<Triangle>& b) {
  static_assert(sizeof(Triangle) == 3 * sizeof(Index), "a triangle is three indices");
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Triangle)) == 0);
}

}  // namespace drench
