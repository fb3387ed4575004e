#include <drench/coupling/leak_audit.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>

namespace drench {
namespace {

using leak_audit_detail::Bounds;

/// The box of `first` and `rest`, taken in that order. A fixed count of points, inline: the list of pointers
/// it took before cost a call of 125 instructions per moved face in issue 41's level.
template <class... Rest>
inline Bounds bounds_of(const Vec3& first, const Rest&... rest) {
  Bounds b{first, first};
  const auto extend = [&b](const Vec3& p) {
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  };
  (extend(rest), ...);
  return b;
}

/// True when eq. 6, f(t) = det[b - a, c - a, p - a](t), certainly keeps one sign on [0, 1]: its Bernstein
/// coefficients, from the blossom of the trilinear determinant, are all certainly of that sign. Then the
/// point never reaches the triangle's plane, and cannot cross the triangle. The eight determinants
/// det[b, c, p] = p . (b x c) share four cross products; six dot products give the coefficients (times 3).
/// Along every term the inputs round once (the differences), a cross product twice and the sum of two once,
/// a dot product three times, the last sum or the factor 3 once: at most 10 roundings, so 10 u (1 + 10 u) of
/// the terms' magnitude (the same products in absolute values) bounds the error; 16 u covers it.
bool certainly_one_signed(const Vec3* x0, const Vec3* x1) {
  // x[0] = p, x[1..3] = a, b, c. Plain doubles: Eigen's small temporaries cost a third more here.
  using D3 = std::array<double, 3>;
  const auto diff = [](const Vec3& u, const Vec3& v) { return D3{u[0] - v[0], u[1] - v[1], u[2] - v[2]}; };
  const auto cross = [](const D3& u, const D3& v) {
    return D3{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  const auto dot = [](const D3& u, const D3& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  const auto sum = [](const D3& u, const D3& v) { return D3{u[0] + v[0], u[1] + v[1], u[2] + v[2]}; };
  const D3 b0 = diff(x0[2], x0[1]), c0 = diff(x0[3], x0[1]), p0 = diff(x0[0], x0[1]);
  const D3 b1 = diff(x1[2], x1[1]), c1 = diff(x1[3], x1[1]), p1 = diff(x1[0], x1[1]);
  const D3 n00 = cross(b0, c0), n11 = cross(b1, c1), mixed = sum(cross(b0, c1), cross(b1, c0));
  const double coef[4] = {3 * dot(p0, n00), dot(p0, mixed) + dot(p1, n00), dot(p1, mixed) + dot(p0, n11),
                          3 * dot(p1, n11)};
  const bool positive = coef[0] > 0.0 && coef[1] > 0.0 && coef[2] > 0.0 && coef[3] > 0.0;
  const bool negative = coef[0] < 0.0 && coef[1] < 0.0 && coef[2] < 0.0 && coef[3] < 0.0;
  if (!positive && !negative) return false;
  const auto abs3 = [](const D3& v) { return D3{std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}; };
  const auto abs_cross = [](const D3& u, const D3& v) {  // of absolute values
    return D3{u[1] * v[2] + u[2] * v[1], u[2] * v[0] + u[0] * v[2], u[0] * v[1] + u[1] * v[0]};
  };
  const D3 ab0 = abs3(b0), ac0 = abs3(c0), ap0 = abs3(p0), ab1 = abs3(b1), ac1 = abs3(c1), ap1 = abs3(p1);
  const D3 m00 = abs_cross(ab0, ac0), m11 = abs_cross(ab1, ac1),
           m_mixed = sum(abs_cross(ab0, ac1), abs_cross(ab1, ac0));
  const double magnitude[4] = {3 * dot(ap0, m00), dot(ap0, m_mixed) + dot(ap1, m00),
                               dot(ap1, m_mixed) + dot(ap0, m11), 3 * dot(ap1, m11)};
  for (int k = 0; k < 4; ++k) {
    if (!(std::abs(coef[k]) > 16.0 * 0x1p-53 * magnitude[k] * (1.0 + 1e-10) + 0x1p-1000)) return false;
  }
  return true;
}

/// True when the point certainly stays outside the triangle at every time of the step, beside one of its
/// edges: for a fixed direction d (an edge's outward normal in the triangle's plane, at the start or the end
/// of the step), d . (p - v) > 0 for every vertex v at both ends. Each d . (p(t) - v(t)) is linear in t, so
/// its ends decide it on [0, 1], and the point is then on the far side of the whole triangle along d at every
/// time: it cannot cross it. Any d serves (it need not be exactly the normal), so only the six dot products
/// round: each by at most 4 u of its terms' magnitude, covered twice. This decides the pairs that
/// certainly_one_signed cannot, a particle crossing the plane of a triangle beside it in a curved cloth: most
/// of those the exact reference was called for in the playground level (issue 41), 2 in 3.
bool certainly_beside(const Vec3* x0, const Vec3* x1) {
  const Vec3* x[2] = {x0, x1};
  for (const Vec3* frame : x) {
    const Vec3 normal = (frame[2] - frame[1]).cross(frame[3] - frame[1]);
    for (int e = 0; e < 3; ++e) {
      const Vec3 edge = frame[1 + (e + 1) % 3] - frame[1 + e];
      const Vec3 d = edge.cross(normal);  // points away from the third vertex
      bool beside = true;
      for (int end = 0; end < 2 && beside; ++end) {
        for (int v = 1; v <= 3 && beside; ++v) {
          const Vec3 diff = x[end][0] - x[end][v];
          const double value = d.dot(diff);
          const double margin = 8.0 * 0x1p-53 * d.cwiseAbs().dot(diff.cwiseAbs()) + 0x1p-1000;
          beside = value > margin;
        }
      }
      if (beside) return true;
    }
  }
  return false;
}

/// std::floor(c), up to the sign of a zero, without a call: without SSE4.1 std::floor is a library call,
/// and the audit's cells take six per moved face and three per particle and pair (issue 41's profile).
/// A -0 is not told from a 0 anywhere a cell coordinate is used (compared, converted to an integer).
inline double floor_of(double c) {
  if (!(std::abs(c) < 0x1p52)) return std::floor(c);  // also a NaN or an infinity
  const auto truncated = static_cast<double>(static_cast<std::int64_t>(c));
  return truncated > c ? truncated - 1.0 : truncated;
}

/// The cell coordinates of `x` for cells of edge `cell` (unit: m), as floor(x / cell) per axis.
inline Eigen::Array3d cell_coordinates(const Vec3& x, double cell) {
  return {floor_of(x[0] / cell), floor_of(x[1] / cell), floor_of(x[2] / cell)};
}

/// The grid's key of a cell (integer coordinates as doubles).
std::uint64_t cell_key(const Eigen::Array3d& c) {
  return static_cast<std::uint64_t>(
      (static_cast<std::int64_t>(c[0]) * 1000003LL + static_cast<std::int64_t>(c[1])) * 1000033LL +
      static_cast<std::int64_t>(c[2]));
}

}  // namespace

std::uint64_t audit_leaks(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                          const ClothMesh& cloth, LeakAuditStats& stats, std::vector<std::uint8_t>* leaked) {
  LeakAudit audit;
  return audit.audit(particles_t0, particles_t1, cloth, stats, leaked);
}

std::uint64_t audit_face_jumps(const Vec3Array& particles, const std::vector<Triangle>& triangles,
                               const Vec3Array& end, const Vec3Array& start, LeakAuditStats& stats,
                               std::vector<std::uint8_t>* leaked) {
  if (end.size() != start.size()) {
    throw std::invalid_argument("audit_face_jumps: " + std::to_string(end.size()) + " end and " +
                                std::to_string(start.size()) + " start positions");
  }
  const auto begin = std::chrono::steady_clock::now();
  if (leaked) leaked->assign(particles.size(), 0);
  // A face whose nodes all start where they ended sweeps nothing: only the others are audited. Most steps
  // start every node where it ended, which one comparison of the bytes shows; a node whose bytes are the
  // same but hold a NaN is passed over with them, as its faces' boxes meet no particle's in any case.
  std::vector<Index> jumped;
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "a position is three doubles");
  if (!end.empty() && std::memcmp(end.data(), start.data(), end.size() * sizeof(Vec3)) != 0) {
    // Per node first: a node is in about six faces, and comparing its positions in each costs more.
    std::vector<std::uint8_t> moved(end.size());
    for (std::size_t i = 0; i < end.size(); ++i)
      moved[i] = static_cast<std::uint8_t>(end[i] != start[i]);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Triangle& tri = triangles[t];
      if (moved[tri[0]] || moved[tri[1]] || moved[tri[2]]) jumped.push_back(static_cast<Index>(t));
    }
  }
  std::uint64_t count = 0;
  if (!jumped.empty() && !particles.empty()) {
    ClothMesh faces;
    faces.positions_t0 = end;
    faces.positions_t1 = start;
    faces.inverse_masses.assign(end.size(), 0.0);
    faces.triangles.reserve(jumped.size());
    for (const Index t : jumped)
      faces.triangles.push_back(triangles[t]);
    LeakAuditStats jump;
    count = audit_leaks(particles, particles, faces, jump, leaked);
    stats.leaks += count;
    stats.jump_leaks += count;
    stats.pairs += jump.pairs;
    stats.exact_checks += jump.exact_checks;
    if (count > 0) {
      stats.leak_particle = jump.leak_particle;
      stats.leak_triangle = jumped[static_cast<std::size_t>(jump.leak_triangle)];
    }
  }
  stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return count;
}

void LeakAudit::update_grid(const ClothMesh& cloth) {
  // Triangles filed in every cell their box meets, cells the median triangle's size: one large face (a
  // table's top beside a cloth's small ones) then does not make every cell large, which made every particle
  // near a body test all its faces (test RigidBodies.ABallOfTwiceTheWatersDensitySinks). A triangle over
  // 4,096 cells is tested by every particle instead.
  // Nothing moved since the last step (bit for bit): the grid stands.
  if (m_built_for.same_as_last(cloth, &m_moved)) return;
  const std::size_t f = cloth.triangles.size();
  // Only the faces with a moved node get new boxes: most of a game's level never moves, and every face's
  // box was a third of the upkeep (issue 41's profile).
  const bool all_faces = m_boxes.size() != f || m_sizes.size() != f || m_ranges.size() != f;
  m_boxes.resize(f);
  m_sizes.resize(f);
  m_face_moved.assign(f, 0);
  const Vec3Array& a = cloth.positions_t0;
  const Vec3Array& b = cloth.positions_t1;
  for (std::size_t t = 0; t < f; ++t) {
    const Triangle& tri = cloth.triangles[t];
    if (!all_faces && !m_moved[tri[0]] && !m_moved[tri[1]] && !m_moved[tri[2]]) continue;
    m_face_moved[t] = 1;
    m_boxes[t] = bounds_of(a[tri[0]], a[tri[1]], a[tri[2]], b[tri[0]], b[tri[1]], b[tri[2]]);
    const double size = (m_boxes[t].hi - m_boxes[t].lo).maxCoeff();
    if (!all_faces) {
      --m_size_classes[size_class(m_sizes[t])];
      ++m_size_classes[size_class(size)];
    }
    m_sizes[t] = size;
  }
  // The cell stays while the median size is within a factor 2 of it, which the count of the sizes on each
  // side of that range decides without finding the median: the sorted sizes' middle one, s[f / 2], is at
  // least half the cell when at most f / 2 are below that, and at most twice the cell when over f / 2 are.
  // A partial sort of every size per step was a twentieth of the grid's upkeep in bench_game_frame's
  // level (callgrind). A NaN size, or a cell at the 1e-9 floor, takes the median itself.
  const std::size_t middle = f / 2;
  bool keep_cell = false;
  const bool counted = !all_faces && m_size_classes[kUnordered] == 0 && m_cell > 2e-9;
  if (counted) {
    keep_cell =
        m_size_classes[kSmaller] <= middle && m_size_classes[kSmaller] + m_size_classes[kWithin] > middle;
  }
  double median = m_cell;
  if (!counted) {
    median = median_size();
    keep_cell = !all_faces && median <= 2.0 * m_cell && median >= 0.5 * m_cell;
  } else if (!keep_cell) {
    median = median_size();
  }
  if (!keep_cell) {
    m_cell = median;
    m_size_classes.fill(0);
    for (std::size_t t = 0; t < f; ++t)
      ++m_size_classes[size_class(m_sizes[t])];
    m_grid.clear();
    m_oversized.clear();
    m_ranges.resize(f);
    for (std::size_t t = 0; t < f; ++t) {
      m_ranges[t] = cell_range(m_boxes[t]);
      file(static_cast<Index>(t), m_ranges[t]);
    }
    return;
  }
  // A triangle is filed again only when its box now covers other cells: a cloth's triangle moves by a small
  // part of a cell per step, and a moving body's box by a few cells, so most keep their cells even when
  // their boxes changed. It leaves the lists of its old cells and joins those of its new ones, each list
  // kept ascending: the filing is the one a fresh grid of the same cell would make.
  for (std::size_t t = 0; t < f; ++t) {
    if (!m_face_moved[t]) continue;
    const CellRange range = cell_range(m_boxes[t]);
    // A box with a NaN has a NaN range, which never equals itself: always filed again (as oversized, where
    // no test passes).
    if ((range.lo == m_ranges[t].lo).all() && (range.hi == m_ranges[t].hi).all()) continue;
    refile(static_cast<Index>(t), m_ranges[t], range);
    m_ranges[t] = range;
  }
}

double LeakAudit::median_size() {
  const std::size_t f = m_sizes.size();
  m_median_scratch = m_sizes;
  std::nth_element(m_median_scratch.begin(), m_median_scratch.begin() + static_cast<long>(f / 2),
                   m_median_scratch.end());
  const double median = m_median_scratch[f / 2];
  return median > 1e-9 ? median : 1e-9;  // also a NaN median
}

int LeakAudit::size_class(double size) const {
  if (size < 0.5 * m_cell) return kSmaller;
  if (size <= 2.0 * m_cell) return kWithin;
  if (size > 2.0 * m_cell) return kLarger;
  return kUnordered;
}

LeakAudit::CellRange LeakAudit::cell_range(const Bounds& box) const {
  return {cell_coordinates(box.lo, m_cell), cell_coordinates(box.hi, m_cell)};
}

bool LeakAudit::oversized(const CellRange& range) {
  // `!(... <= ...)` also holds for a box with a NaN, where its bounds test never passes.
  return !((range.hi - range.lo + 1.0).prod() <= 4096.0);
}

void LeakAudit::file(Index t, const CellRange& range) {
  const Eigen::Array3d& lo = range.lo;
  const Eigen::Array3d& hi = range.hi;
  if (oversized(range)) {
    m_oversized.insert(std::upper_bound(m_oversized.begin(), m_oversized.end(), t), t);
    return;
  }
  for (double z = lo[2]; z <= hi[2]; z += 1.0)
    for (double y = lo[1]; y <= hi[1]; y += 1.0)
      for (double x = lo[0]; x <= hi[0]; x += 1.0)
        m_grid.add(cell_key(Eigen::Array3d(x, y, z)), t);
}

void LeakAudit::unfile(Index t, const CellRange& range) {
  const Eigen::Array3d& lo = range.lo;
  const Eigen::Array3d& hi = range.hi;
  if (oversized(range)) {
    m_oversized.erase(std::lower_bound(m_oversized.begin(), m_oversized.end(), t));
    return;
  }
  for (double z = lo[2]; z <= hi[2]; z += 1.0)
    for (double y = lo[1]; y <= hi[1]; y += 1.0)
      for (double x = lo[0]; x <= hi[0]; x += 1.0)
        m_grid.remove(cell_key(Eigen::Array3d(x, y, z)), t);
}

void LeakAudit::refile(Index t, const CellRange& from, const CellRange& to) {
  if (oversized(from) || oversized(to)) {
    unfile(t, from);
    file(t, to);
    return;
  }
  // Visits the keys of the cells of `range` that `other` does not cover.
  const auto for_cells_outside = [](const CellRange& range, const CellRange& other, const auto& visit) {
    const auto inside = [&](double c, int axis) { return c >= other.lo[axis] && c <= other.hi[axis]; };
    for (double z = range.lo[2]; z <= range.hi[2]; z += 1.0) {
      const bool z_inside = inside(z, 2);
      for (double y = range.lo[1]; y <= range.hi[1]; y += 1.0) {
        const bool yz_inside = z_inside && inside(y, 1);
        for (double x = range.lo[0]; x <= range.hi[0]; x += 1.0) {
          if (!(yz_inside && inside(x, 0))) visit(cell_key(Eigen::Array3d(x, y, z)));
        }
      }
    }
  };
  for_cells_outside(from, to, [&](std::uint64_t key) { m_grid.remove(key, t); });
  for_cells_outside(to, from, [&](std::uint64_t key) { m_grid.add(key, t); });
}

std::uint64_t LeakAudit::audit(const Vec3Array& particles_t0, const Vec3Array& particles_t1,
                               const ClothMesh& cloth, LeakAuditStats& stats,
                               std::vector<std::uint8_t>* leaked) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = particles_t0.size();
  if (leaked) leaked->assign(n, 0);
  std::uint64_t count = 0;
  if (n == 0 || cloth.triangles.empty()) return 0;
  update_grid(cloth);
  const double cell = m_cell;
  const auto cell_of = [cell](const Vec3& x) { return cell_coordinates(x, cell); };
  const std::vector<Bounds>& boxes = m_boxes;
  const std::vector<CellRange>& ranges = m_ranges;

  // Per particle, 1 + the first triangle it crosses, or 0.
  std::vector<std::uint64_t> flags(n, 0);
  std::vector<std::uint64_t> pairs_per(n, 0), exact_per(n, 0);
  parallel_for(n, 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      const Bounds box = bounds_of(particles_t0[p], particles_t1[p]);
      // True when particle p crosses triangle t (their boxes known to overlap).
      const auto crosses = [&](Index t) {
        ++pairs_per[p];
        const Triangle& tri = cloth.triangles[t];
        const Vec3 x0[4] = {particles_t0[p], cloth.positions_t0[tri[0]], cloth.positions_t0[tri[1]],
                            cloth.positions_t0[tri[2]]};
        const Vec3 x1[4] = {particles_t1[p], cloth.positions_t1[tri[0]], cloth.positions_t1[tri[1]],
                            cloth.positions_t1[tri[2]]};
        if (certainly_one_signed(x0, x1) || certainly_beside(x0, x1)) return false;
        const ccd::VertexFaceQuery q{x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3]};
        ccd::CcdPath path = ccd::CcdPath::FILTER;
        const bool crossing = ccd::transversal_crossing(q, &path);
        exact_per[p] += path == ccd::CcdPath::EXACT;
        return crossing;
      };
      // Written so that a box with a NaN is apart from every other.
      const auto apart = [&](const Bounds& tb) {
        return !((box.hi.array() >= tb.lo.array()).all() && (tb.hi.array() >= box.lo.array()).all());
      };
      for (Index t : m_oversized) {
        if (apart(boxes[t])) continue;
        if (crosses(t)) {
          flags[p] = 1 + static_cast<std::uint64_t>(t);
          break;
        }
      }
      const Eigen::Array3d lo = cell_of(box.lo);
      const Eigen::Array3d hi = cell_of(box.hi);
      if (!((hi - lo + 1.0).prod() <= 1e6))
        continue;  // a particle flying kilometres: not a cloth contact question
      for (double z = lo[2]; z <= hi[2] && !flags[p]; z += 1.0) {
        for (double y = lo[1]; y <= hi[1] && !flags[p]; y += 1.0) {
          for (double x = lo[0]; x <= hi[0] && !flags[p]; x += 1.0) {
            const Eigen::Array3d here(x, y, z);
            const std::vector<Index>* list = m_grid.find(cell_key(here));
            if (!list) continue;
            for (const Index t : *list) {
              const Bounds& tb = boxes[t];
              if (apart(tb)) continue;
              // The pair's one cell: where the overlap of the two boxes begins, the larger of the two
              // boxes' first cells per axis, as floor(x / cell) never decreases with x (the cell of the
              // larger lower corner took three divisions per candidate).
              if ((lo.max(ranges[t].lo) != here).any()) continue;
              if (crosses(t)) {
                flags[p] = 1 + static_cast<std::uint64_t>(t);
                break;
              }
            }
          }
        }
      }
    }
  });
  for (std::size_t p = 0; p < n; ++p) {
    if (flags[p] != 0) {
      if (count == 0) {
        stats.leak_particle = static_cast<std::int64_t>(p);
        stats.leak_triangle = static_cast<std::int64_t>(flags[p] - 1);
      }
      ++count;
      if (leaked) (*leaked)[p] = 1;
    }
    stats.pairs += pairs_per[p];
    stats.exact_checks += exact_per[p];
  }
  stats.leaks += count;
  stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return count;
}

}  // namespace drench
