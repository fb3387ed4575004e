#include <drench/surface/vdb_mesher.hpp>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

#include <drench/common/error.hpp>
#include <drench/surface/surface_settings.hpp>

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

void VdbNodeGrid::check_range(const Vec3Array& points) const {
  const double cell = m_impl->grid->voxelSize()[0];
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3 node = (points[i] / cell).array().floor().matrix();
    if (!(node.cwiseAbs().maxCoeff() <= kMaxSurfaceGridCells)) {
      throw Error("surface: particle " + std::to_string(i) + " at (" + show(points[i].x()) + ", " +
                  show(points[i].y()) + ", " + show(points[i].z()) +
                  ") m is beyond the surface grid's int32 coordinates at cell size " + show(cell) +
                  " m (|x| / cell <= 2^30); choose a larger surface.cell_size");
    }
  }
}

void VdbNodeGrid::activate_boxes(const std::vector<Vec3i>& lo, const std::vector<Vec3i>& hi) {
  using Leaf = openvdb::FloatGrid::TreeType::LeafNodeType;
  static_assert(Leaf::DIM == 8, "a leaf's value mask: one 64-bit word of (y, z) bits per x");
  auto accessor = m_impl->grid->getAccessor();
  const auto leaf_of = [](int v) { return v >> 3; };
  // bits[k]: nodes k, k + 1, ..., 7 of a leaf's row along z (or, times 0x0101..., along y).
  const auto from = [](int k) { return 0xffu & (0xffu << k); };
  vdb_call("activate its nodes", m_impl->grid->voxelSize()[0], [&] {
    for (std::size_t i = 0; i < lo.size(); ++i) {
      for (int lx = leaf_of(lo[i].x()); lx <= leaf_of(hi[i].x()); ++lx)
        for (int ly = leaf_of(lo[i].y()); ly <= leaf_of(hi[i].y()); ++ly)
          for (int lz = leaf_of(lo[i].z()); lz <= leaf_of(hi[i].z()); ++lz) {
            const openvdb::Coord origin(8 * lx, 8 * ly, 8 * lz);
            const openvdb::Coord a =
                openvdb::Coord::maxComponent(openvdb::Coord(lo[i].x(), lo[i].y(), lo[i].z()), origin) -
                origin;
            const openvdb::Coord b =
                openvdb::Coord::minComponent(openvdb::Coord(hi[i].x(), hi[i].y(), hi[i].z()),
                                             origin.offsetBy(7)) -
                origin;
            // Offset in a leaf: x << 6 | y << 3 | z, so word x holds the (y, z) plane, y a byte of it.
            const std::uint64_t z_bits = from(a.z()) & ~from(b.z() + 1);
            std::uint64_t plane = 0;
            for (int y = a.y(); y <= b.y(); ++y)
              plane |= z_bits << (8 * y);
            auto& mask = accessor.touchLeaf(origin)->getValueMask();
            for (int x = a.x(); x <= b.x(); ++x)
              mask.template getWord<std::uint64_t>(x) |= plane;
          }
    }
  });
}

void VdbNodeGrid::activate_around(const Vec3Array& particles, int reach) {
  openvdb::FloatGrid& grid = *m_impl->grid;
  auto accessor = grid.getAccessor();
  const double cell = grid.voxelSize()[0];
  check_range(particles);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const Vec3 node = (particles[i] / cell).array().floor().matrix();
    accessor.setValueOn(
        openvdb::Coord(static_cast<int>(node.x()), static_cast<int>(node.y()), static_cast<int>(node.z())));
  }
  // The floor node and the one past it both lie next to the particle: reach + 1 covers the kernel's cube.
  vdb_call("dilate its active nodes", cell, [&] {
    openvdb::tools::dilateActiveValues(grid.tree(), reach + 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::EXPAND_TILES);
  });
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
