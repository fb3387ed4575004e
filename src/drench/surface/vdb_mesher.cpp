#include <drench/surface/vdb_mesher.hpp>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <mutex>

namespace drench {

struct VdbNodeGrid::Impl {
  openvdb::FloatGrid::Ptr grid;
};

VdbNodeGrid::VdbNodeGrid(Scalar cell, float outside) : m_impl(std::make_unique<Impl>()) {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
  m_impl->grid = openvdb::FloatGrid::create(outside);
  m_impl->grid->setTransform(openvdb::math::Transform::createLinearTransform(cell));
}

VdbNodeGrid::~VdbNodeGrid() = default;

void VdbNodeGrid::activate_around(const Vec3Array& particles, int reach) {
  openvdb::FloatGrid& grid = *m_impl->grid;
  auto accessor = grid.getAccessor();
  const double cell = grid.voxelSize()[0];
  for (const Vec3& p : particles) {
    const openvdb::Coord c(static_cast<int>(std::floor(p.x() / cell)),
                           static_cast<int>(std::floor(p.y() / cell)),
                           static_cast<int>(std::floor(p.z() / cell)));
    accessor.setValueOn(c);
  }
  // The floor node and the one past it both lie next to the particle: reach + 1 covers the kernel's cube.
  openvdb::tools::dilateActiveValues(grid.tree(), reach + 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::EXPAND_TILES);
}

std::vector<Vec3i> VdbNodeGrid::active_nodes() const {
  std::vector<Vec3i> nodes;
  nodes.reserve(m_impl->grid->activeVoxelCount());
  for (auto it = m_impl->grid->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) continue;
    const openvdb::Coord c = it.getCoord();
    nodes.emplace_back(c.x(), c.y(), c.z());
  }
  return nodes;
}

void VdbNodeGrid::set_values(const std::vector<Vec3i>& nodes, const std::vector<float>& values) {
  auto accessor = m_impl->grid->getAccessor();
  for (std::size_t i = 0; i < nodes.size(); ++i)
    accessor.setValue(openvdb::Coord(nodes[i].x(), nodes[i].y(), nodes[i].z()), values[i]);
}

void VdbNodeGrid::mesh(Vec3Array& positions, std::vector<Triangle>& triangles) const {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*m_impl->grid, points, tris, quads, 0.0, 0.0);
  positions.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    positions[i] = Vec3(points[i].x(), points[i].y(), points[i].z());
  triangles.clear();
  triangles.reserve(tris.size() + 2 * quads.size());
  // volumeToMesh already winds its polygons counter-clockwise seen from the positive side, drench's
  // convention (test Surface.SphereOfParticlesGivesAClosedOutwardMesh).
  for (const auto& t : tris)
    triangles.push_back({t[0], t[1], t[2]});
  for (const auto& q : quads) {
    triangles.push_back({q[0], q[1], q[2]});
    triangles.push_back({q[0], q[2], q[3]});
  }
}

}  // namespace drench
