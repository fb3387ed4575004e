#include <drench/surface/vdb_mesher.hpp>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>

#include <drench/common/error.hpp>

namespace drench {

namespace {

/// A figure in a message, to 4 digits.
std::string show(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

/// Runs `body`, turning an OpenVDB exception (e.g. ArithmeticError for a transform of a cell too small to
/// invert) into a drench::Error that names the stage and the cell size, so that it never aborts the program.
template <class Body>
void vdb_call(const char* stage, double cell, Body&& body) {
  try {
    body();
  } catch (const openvdb::Exception& e) {
    throw Error("surface: OpenVDB failed to " + std::string(stage) + " at surface cell size " + show(cell) +
                " m: " + e.what() + " (choose a larger surface.cell_size)");
  }
}

/// Largest |coordinate| / cell a node may have: OpenVDB's coordinates are int32, and the dilation and the
/// kernel's reach add a few nodes on either side.
constexpr double kMaxNodeIndex = 0x1p30;

}  // namespace

struct VdbNodeGrid::Impl {
  openvdb::FloatGrid::Ptr grid;
};

VdbNodeGrid::VdbNodeGrid(Scalar cell, float outside) : m_impl(std::make_unique<Impl>()) {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
  vdb_call("build its grid", cell, [&] {
    m_impl->grid = openvdb::FloatGrid::create(outside);
    m_impl->grid->setTransform(openvdb::math::Transform::createLinearTransform(cell));
  });
}

VdbNodeGrid::~VdbNodeGrid() = default;

void VdbNodeGrid::activate_around(const Vec3Array& particles, int reach) {
  openvdb::FloatGrid& grid = *m_impl->grid;
  auto accessor = grid.getAccessor();
  const double cell = grid.voxelSize()[0];
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const Vec3 node = (particles[i] / cell).array().floor().matrix();
    if (!(node.cwiseAbs().maxCoeff() <= kMaxNodeIndex)) {
      throw Error("surface: particle " + std::to_string(i) + " at (" + show(particles[i].x()) + ", " +
                  show(particles[i].y()) + ", " + show(particles[i].z()) +
                  ") m is beyond the surface grid's int32 coordinates at cell size " + show(cell) +
                  " m (|x| / cell <= 2^30); choose a larger surface.cell_size");
    }
    accessor.setValueOn(
        openvdb::Coord(static_cast<int>(node.x()), static_cast<int>(node.y()), static_cast<int>(node.z())));
  }
  // The floor node and the one past it both lie next to the particle: reach + 1 covers the kernel's cube.
  vdb_call("dilate its active nodes", cell, [&] {
    openvdb::tools::dilateActiveValues(grid.tree(), reach + 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::EXPAND_TILES);
  });
}

void VdbNodeGrid::activate_around(const Vec3Array& particles, const std::vector<int>& reaches) {
  // Dilation distributes over union: each reach's particles dilated on their own grid, then merged.
  std::map<int, Vec3Array> groups;
  for (std::size_t i = 0; i < particles.size(); ++i)
    groups[reaches[i]].push_back(particles[i]);
  if (groups.size() == 1) {
    activate_around(particles, groups.begin()->first);
    return;
  }
  const double cell = m_impl->grid->voxelSize()[0];
  const float outside = m_impl->grid->background();
  for (const auto& [reach, points] : groups) {
    VdbNodeGrid part(cell, outside);
    try {
      part.activate_around(points, reach);
    } catch (const Error&) {
      activate_around(particles, reach);  // names the particle by its index in `particles`
      throw;
    }
    vdb_call("merge its active nodes", cell, [&] { m_impl->grid->topologyUnion(*part.m_impl->grid); });
  }
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
  vdb_call("mesh the surface", m_impl->grid->voxelSize()[0],
           [&] { openvdb::tools::volumeToMesh(*m_impl->grid, points, tris, quads, 0.0, 0.0); });
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
