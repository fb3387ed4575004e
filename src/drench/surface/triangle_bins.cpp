#include <drench/surface/triangle_bins.hpp>

#include <algorithm>
#include <cmath>

namespace drench {

TriangleBins::TriangleBins(const std::vector<SurfaceObstacle>& obstacles, Scalar cell) : m_cell(cell) {
  m_boxes.resize(obstacles.size());
  for (std::size_t o = 0; o < obstacles.size(); ++o) {
    const Vec3Array& p = *obstacles[o].positions;
    const std::vector<Triangle>& triangles = *obstacles[o].triangles;
    m_boxes[o].resize(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Triangle& tri = triangles[t];
      Box& box = m_boxes[o][t];
      box.lo = p[tri[0]].cwiseMin(p[tri[1]]).cwiseMin(p[tri[2]]);
      box.hi = p[tri[0]].cwiseMax(p[tri[1]]).cwiseMax(p[tri[2]]);
      // The finest level where the box spans at most 2 cells along each axis: at most 8 bins a triangle.
      std::size_t level = 0;
      Scalar size = m_cell;
      Vec3i lo = cell_of(box.lo, size), hi = cell_of(box.hi, size);
      while ((hi - lo).maxCoeff() > 1) {
        ++level;
        size *= 2.0;
        lo = cell_of(box.lo, size);
        hi = cell_of(box.hi, size);
      }
      if (level >= m_levels.size()) m_levels.resize(level + 1);
      for (int z = lo.z(); z <= hi.z(); ++z)
        for (int y = lo.y(); y <= hi.y(); ++y)
          for (int x = lo.x(); x <= hi.x(); ++x)
            m_levels[level][key(Vec3i(x, y, z))].emplace_back(static_cast<Index>(o), static_cast<Index>(t));
      m_empty = false;
    }
  }
}

std::size_t TriangleBins::entry_count() const {
  std::size_t count = 0;
  for (const Bins& bins : m_levels)
    for (const auto& bin : bins)
      count += bin.second.size();
  return count;
}

Vec3i TriangleBins::cell_of(const Vec3& x, Scalar size) {
  // Clamped before the cast, which is undefined past int: cells that far out share bins, whose boxes the
  // queries still test.
  constexpr Scalar kFar = 0x1p30;
  return (x / size).array().floor().max(-kFar).min(kFar).cast<int>();
}

std::uint64_t TriangleBins::key(const Vec3i& c) {
  const auto part = [](int v) {
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v + (1 << 20))) & 0x1fffff;
  };
  return part(c.x()) | (part(c.y()) << 21) | (part(c.z()) << 42);
}

void TriangleBins::collect_box(const Vec3& lo, const Vec3& hi,
                               std::vector<std::pair<Index, Index>>& out) const {
  out.clear();
  Scalar size = m_cell;
  for (const Bins& bins : m_levels) {
    const Vec3i a = cell_of(lo, size), b = cell_of(hi, size);
    size *= 2.0;
    if (bins.empty()) continue;
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) {
          const auto it = bins.find(key(Vec3i(x, y, z)));
          if (it == bins.end()) continue;
          for (const auto& ot : it->second) {
            const Box& box = m_boxes[ot.first][ot.second];
            if ((box.lo.array() <= hi.array()).all() && (lo.array() <= box.hi.array()).all())
              out.push_back(ot);
          }
        }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void TriangleBins::filter_box(const std::vector<std::pair<Index, Index>>& candidates, const Vec3& lo,
                              const Vec3& hi, std::vector<std::pair<Index, Index>>& out) const {
  out.clear();
  for (const auto& ot : candidates) {
    const Box& box = m_boxes[ot.first][ot.second];
    if ((box.lo.array() <= hi.array()).all() && (lo.array() <= box.hi.array()).all()) out.push_back(ot);
  }
}

}  // namespace drench
