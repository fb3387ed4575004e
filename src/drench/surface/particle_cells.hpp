#pragma once
/// Particles binned in cubic cells for the surface's neighbour queries (Huber et al. 2013 sec. 4): a grid
/// node's particles within the kernel radius, and a particle's neighbours for the anisotropic kernels.

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// Particles sorted into cubic cells of the kernel radius (or of a fraction of a reach, searched `rings`
/// cells around), so that a node finds every particle within the radius in the 27 cells around its own. The
/// particles are copied in cell order (z, then y, then x, then index), so that a node's candidates lie
/// together in memory: for_each_near passes slots of positions(). Where the cells' bounding box is small (it
/// is for any fluid that holds together), a dense table of each cell's first slot replaces the hash map; the
/// three cells along x of a row are then one run of slots, visited in the same order, so both give the same
/// sums to the bit.
class ParticleCells {
 public:
  /// `rings` (>= 1) cells on each side of a point's own are its neighbourhood: a radius of `rings` cells.
  ParticleCells(const Vec3Array& particles, Scalar cell, int rings = 1) : m_cell(cell), m_rings(rings) {
    const std::size_t n = particles.size();
    std::vector<Vec3i> cells(n);
    for (std::size_t i = 0; i < n; ++i)
      cells[i] = cell_of(particles[i]);
    m_min = m_max = cells.empty() ? Vec3i::Zero() : cells[0];
    for (const Vec3i& c : cells) {
      m_min = m_min.cwiseMin(c);
      m_max = m_max.cwiseMax(c);
    }
    const Eigen::Vector3d extent = (m_max - m_min).cast<double>() + Eigen::Vector3d::Ones();
    // Up to 8 table entries per particle (or 16 MB): a splash spread far needs the hash map instead.
    m_dense = !cells.empty() && extent.prod() <= std::max(8.0 * static_cast<double>(n), double(1 << 21));
    IndexArray order(n);  // slot -> particle
    if (m_dense) {
      m_dims = (m_max - m_min) + Vec3i::Ones();
      // A counting sort: within a cell the particles stay in index order, as sorting (key, index) leaves
      // them.
      m_first.assign(static_cast<std::size_t>(m_dims.prod()) + 1, 0);
      for (const Vec3i& c : cells)
        ++m_first[slot_of(c) + 1];
      for (std::size_t k = 1; k < m_first.size(); ++k)
        m_first[k] += m_first[k - 1];
      std::vector<std::size_t> next(m_first.begin(), m_first.end() - 1);
      for (std::size_t i = 0; i < n; ++i)
        order[next[slot_of(cells[i])]++] = static_cast<Index>(i);
    } else {
      std::vector<std::pair<std::uint64_t, Index>> keyed(n);
      for (std::size_t i = 0; i < n; ++i)
        keyed[i] = {key(cells[i]), static_cast<Index>(i)};
      std::sort(keyed.begin(), keyed.end());
      for (std::size_t i = 0; i < n; ++i) {
        order[i] = keyed[i].second;
        if (i == 0 || keyed[i].first != keyed[i - 1].first) m_runs[keyed[i].first] = {i, i};
        m_runs[keyed[i].first].second = i + 1;
      }
    }
    m_positions.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      m_positions[k] = particles[order[k]];
    m_order = std::move(order);
  }
  Vec3i cell_of(const Vec3& x) const { return (x / m_cell).array().floor().cast<int>(); }
  /// The particles' positions in cell order, by slot.
  const Vec3Array& positions() const { return m_positions; }
  /// The particle (index into the constructor's array) at each slot.
  const IndexArray& order() const { return m_order; }
  /// Calls f(slot) for every particle in the (2 rings + 1)^3 cells around x's (27 for one ring), in a fixed
  /// order: cells by z, y, x, each cell's particles by index.
  template <class F>
  void for_each_near(const Vec3& x, F&& f) const {
    const Vec3i c = cell_of(x);
    if (m_dense) {
      const Vec3i local = c - m_min;
      const int x0 = std::max(local.x() - m_rings, 0), x1 = std::min(local.x() + m_rings, m_dims.x() - 1);
      if (x0 > x1) return;
      for (int z = local.z() - m_rings; z <= local.z() + m_rings; ++z) {
        if (z < 0 || z >= m_dims.z()) continue;
        for (int y = local.y() - m_rings; y <= local.y() + m_rings; ++y) {
          if (y < 0 || y >= m_dims.y()) continue;
          const std::size_t row = (static_cast<std::size_t>(z) * m_dims.y() + y) * m_dims.x();
          for (std::size_t k = m_first[row + x0], end = m_first[row + x1 + 1]; k < end; ++k)
            f(static_cast<Index>(k));
        }
      }
      return;
    }
    for (int dz = -m_rings; dz <= m_rings; ++dz)
      for (int dy = -m_rings; dy <= m_rings; ++dy)
        for (int dx = -m_rings; dx <= m_rings; ++dx) {
          const auto it = m_runs.find(key(c + Vec3i(dx, dy, dz)));
          if (it == m_runs.end()) continue;
          for (std::size_t k = it->second.first; k < it->second.second; ++k)
            f(static_cast<Index>(k));
        }
  }

 private:
  static std::uint64_t key(const Vec3i& c) {
    const auto part = [](int v) {
      return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v + (1 << 20))) & 0x1fffff;
    };
    return part(c.x()) | (part(c.y()) << 21) | (part(c.z()) << 42);
  }
  std::size_t slot_of(const Vec3i& c) const {
    const Vec3i l = c - m_min;
    return (static_cast<std::size_t>(l.z()) * m_dims.y() + l.y()) * m_dims.x() + l.x();
  }
  Scalar m_cell;
  int m_rings;
  Vec3Array m_positions;
  IndexArray m_order;  // slot -> particle
  bool m_dense = false;
  Vec3i m_min, m_max, m_dims;
  std::vector<std::size_t> m_first;  // dense: slot of each cell's first particle, then the total
  std::unordered_map<std::uint64_t, std::pair<std::size_t, std::size_t>> m_runs;  // sparse: key -> slots
};

}  // namespace drench
