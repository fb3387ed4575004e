#include <drench/coupling/rigid_boundary.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include <drench/common/error.hpp>
#include <drench/sph/cubic_spline_kernel.hpp>
#include <drench/sph/neighbor_search.hpp>

namespace drench {

namespace {

Vec3 outward_normal(const Vec3Array& x, const Triangle& t) {
  const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
  const Scalar length = n.norm();
  return length > 0.0 ? Vec3(n / length) : Vec3::Zero();
}

/// How far a resting fluid lattice's first layer sits from a plane of boundary samples with Akinci et al.
/// 2012 eq. 4's volumes, as a fraction of the spacing: where its density, fluid half-space plus samples, is
/// the rest density (where its pressure starts). The volumes make it the same for any sample spacing; for
/// the cubic spline it is 1.10 (a plane of lattice-cell volumes, as boundary_sampling.hpp's walls, gives 1).
Scalar resting_distance_in_spacings() {
  const CubicSplineKernel kernel(1.0);
  const auto w = [&](Scalar x, Scalar y, Scalar z) { return kernel.value(std::sqrt(x * x + y * y + z * z)); };
  Scalar plane_sum = 0.0;
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j)
      plane_sum += w(i, 0, j);
  const Scalar volume = 1.0 / plane_sum;  // eq. 4 on a plane of unit spacing
  Scalar fluid = 0.0;                     // the first layer's own half-space, unit mass and spacing
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j)
      for (int k = 0; k <= 3; ++k)
        fluid += w(i, k, j);
  const auto density = [&](Scalar d) {
    Scalar boundary = 0.0;
    for (int i = -3; i <= 3; ++i)
      for (int j = -3; j <= 3; ++j)
        boundary += volume * w(i, d, j);
    return fluid + boundary;
  };
  Scalar lo = 0.5, hi = 2.0;  // density(lo) > 1 > density(hi)
  for (int it = 0; it < 60; ++it) {
    const Scalar mid = 0.5 * (lo + hi);
    (density(mid) > 1.0 ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

RigidBoundary::RigidBoundary(Scalar spacing) : m_spacing(spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument("RigidBoundary: the spacing must be > 0 and finite");
  // The water's volume ends half a spacing beyond its first layer: the samples sit so far inside the face
  // that a resting first layer lies half a spacing outside it, and the body displaces its own volume (a
  // part thinner than twice the inset displaces more: inset()).
  static const Scalar resting = resting_distance_in_spacings();
  m_inset = (resting - 0.5) * spacing;
}

namespace {

/// The sub-triangles per edge of a face's uniform sampling: its longest edge over the spacing, at least 1.
double face_steps(const Vec3Array& x, const Triangle& t, Scalar spacing) {
  const Scalar longest =
      std::max({(x[t[1]] - x[t[0]]).norm(), (x[t[2]] - x[t[1]]).norm(), (x[t[0]] - x[t[2]]).norm()});
  return std::max(1.0, std::ceil(longest / spacing - 1e-9));
}

/// Calls `emit` with the barycentric weights of samples of a sliver face `t` laid from the corner A opposite
/// its shortest edge BC: rows a spacing or less apart along the face's length (u, from A), each row across
/// the face (t, from AB to AC) in pieces of a spacing or less, a sample at each piece's middle. Every point
/// of the face is then within about a spacing of a sample, none lies on an edge, and their count is the
/// face's rows plus about its area over half a square spacing: a sliver's similar sub-triangles were
/// thousands of times that.
template <class Emit>
void sample_sliver(const Vec3Array& x, const Triangle& t, Scalar spacing, Emit&& emit) {
  int a = 0;
  Scalar shortest = INFINITY;
  for (int k = 0; k < 3; ++k) {
    const Scalar l = (x[t[(k + 2) % 3]] - x[t[(k + 1) % 3]]).norm();
    if (l < shortest) {
      shortest = l;
      a = k;
    }
  }
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const Scalar length = std::max((x[t[b]] - x[t[a]]).norm(), (x[t[c]] - x[t[a]]).norm());
  const int rows = std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
  for (int i = 0; i < rows; ++i) {
    const Scalar u = (i + 0.5) / rows;
    const int pieces = std::max(1, static_cast<int>(std::ceil(u * shortest / spacing - 1e-9)));
    for (int j = 0; j < pieces; ++j) {
      const Scalar across = (j + 0.5) / pieces;
      Vec3 w;
      w[a] = 1.0 - u;
      w[b] = u * (1.0 - across);
      w[c] = u * across;
      emit(w);
    }
  }
}

/// The distance t in (0, reach] along the unit direction d from p at which the ray meets triangle abc, or
/// reach when it does not (Möller & Trumbore 1997). A ray in the triangle's plane does not meet it.
Scalar ray_distance(const Vec3& p, const Vec3& d, Scalar reach, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 q = d.cross(e2);
  const Scalar det = e1.dot(q);
  if (!(std::abs(det) > 1e-30)) return reach;
  const Vec3 s = p - a;
  const Scalar u = s.dot(q) / det;
  if (u < 0.0 || u > 1.0) return reach;
  const Vec3 r = s.cross(e1);
  const Scalar v = d.dot(r) / det;
  if (v < 0.0 || u + v > 1.0) return reach;
  const Scalar t = e2.dot(r) / det;
  return t > 0.0 && t < reach ? t : reach;
}

/// The body's own depth behind each point, along its inward normal, up to `reach` (unit: m): the nearest
/// other face the ray -n from it meets. points[k] lies on face faces[k]; normals[k] is that face's outward
/// unit normal. Faces are binned in a hierarchy of grids, cells of reach, 16 reach, 256 reach and so on,
/// each face in the first where it covers at most 64 cells, so a ray, shorter than any cell, looks at the
/// faces of at most 8 cells per level: a body's large sides would otherwise be tested by every ray (a body of
/// 1,000 one-metre faces at 1 cm particles took about 4e9 tests).
std::vector<Scalar> depths_behind(const RigidSurface& surface, const Vec3Array& points,
                                  const std::vector<Index>& faces, const Vec3Array& normals, Scalar reach) {
  const Vec3Array& x = surface.positions_t0;
  using Cell = Eigen::Vector3<std::int64_t>;
  struct Level {
    Scalar inverse_cell;
    std::unordered_map<std::uint64_t, std::vector<Index>> bins;
  };
  constexpr int kLevels = 6;  // cells up to 16^5 reach: 12 km at 1 cm particles
  std::vector<Level> levels;
  for (int l = 0; l < kLevels; ++l)
    levels.push_back({1.0 / (reach * std::pow(16.0, l)), {}});
  // Cell coordinates stay far inside int64: a point beyond this many cells from the origin is not binned
  // (a body that far is refused elsewhere; its samples keep the whole inset).
  constexpr double kMaxCell = 1e15;
  const auto binnable = [&](const Vec3& p) {
    return p.allFinite() && (p.cwiseAbs() * levels[0].inverse_cell).maxCoeff() <= kMaxCell;
  };
  const auto cell = [](const Level& level, const Vec3& p) {
    return Cell(static_cast<std::int64_t>(std::floor(p.x() * level.inverse_cell)),
                static_cast<std::int64_t>(std::floor(p.y() * level.inverse_cell)),
                static_cast<std::int64_t>(std::floor(p.z() * level.inverse_cell)));
  };
  const auto key = [](const Cell& c) {
    return static_cast<std::uint64_t>(c.x()) * 73856093u ^ static_cast<std::uint64_t>(c.y()) * 19349663u ^
           static_cast<std::uint64_t>(c.z()) * 83492791u;
  };
  const auto for_cells = [&](const Level& level, const Vec3& lo, const Vec3& hi, auto&& visit) {
    const Cell a = cell(level, lo), b = cell(level, hi);
    for (std::int64_t i = a.x(); i <= b.x(); ++i)
      for (std::int64_t j = a.y(); j <= b.y(); ++j)
        for (std::int64_t k = a.z(); k <= b.z(); ++k)
          visit(key({i, j, k}));
  };
  std::vector<Index> everywhere;  // faces over 64 cells of the coarsest level: tested by every ray
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& t = surface.triangles[f];
    const Vec3 lo = x[t[0]].cwiseMin(x[t[1]]).cwiseMin(x[t[2]]);
    const Vec3 hi = x[t[0]].cwiseMax(x[t[1]]).cwiseMax(x[t[2]]);
    if (!binnable(lo) || !binnable(hi)) continue;
    bool filed = false;
    for (Level& level : levels) {
      const Cell a = cell(level, lo), b = cell(level, hi);
      if (((b - a).array() + 1).cast<double>().prod() > 64.0) continue;
      for_cells(level, lo, hi, [&](std::uint64_t k) { level.bins[k].push_back(static_cast<Index>(f)); });
      filed = true;
      break;
    }
    if (!filed) everywhere.push_back(static_cast<Index>(f));
  }
  std::vector<Scalar> depth(points.size(), reach);
  for (std::size_t s = 0; s < points.size(); ++s) {
    const Vec3 d = -normals[s];
    const auto test = [&](Index f) {
      if (f == faces[s]) return;
      const Triangle& t = surface.triangles[f];
      depth[s] = std::min(depth[s], ray_distance(points[s], d, reach, x[t[0]], x[t[1]], x[t[2]]));
    };
    for (Index f : everywhere)
      test(f);
    const Vec3 end = points[s] + reach * d;
    if (!binnable(points[s]) || !binnable(end)) continue;
    for (const Level& level : levels) {
      if (level.bins.empty()) continue;
      for_cells(level, points[s].cwiseMin(end), points[s].cwiseMax(end), [&](std::uint64_t k) {
        const auto found = level.bins.find(k);
        if (found == level.bins.end()) return;
        for (Index f : found->second)
          test(f);
      });
    }
  }
  return depth;
}

}  // namespace

RigidBoundary::Body RigidBoundary::sample(const RigidSurface& surface) const {
  Body body;
  body.instance = surface.instance;
  body.nodes = surface.positions_t0.size();
  body.triangles = surface.triangles.size();
  const Vec3Array& x = surface.positions_t0;
  // Samples inside each face only, at the centroids of its steps^2 sub-triangles: a sample on a shared edge
  // or corner would push along the normal of whichever face claimed it first, off the line through the other
  // faces' pressure, and on a floating ball such pushes added up to a steady torque that spun it up (7.8
  // rad/s in 0.3 s at 1 cm, 500 kg/m^3; test RigidBodies.AFloatingBallDoesNotSpinUp).
  // A face of steps^2 similar sub-triangles has samples a spacing apart along its longest edge but far
  // closer across a sliver, thousands of times what its area needs (test
  // RigidBoundary.ASliverFaceTakesSamplesByItsAreaAndIsCoveredByThem). A sliver is sampled in rows across it
  // instead (sample_sliver), about its area over half a square spacing plus its length; a face the steps suit
  // keeps them (the same samples as before). Per face: its steps, and whether it is a sliver (its steps^2
  // more than twice its rows plus its area over half a square spacing, what sample_sliver takes), decided
  // once for the count and the sampling.
  std::vector<double> steps(surface.triangles.size());
  std::vector<bool> sliver(surface.triangles.size());
  double expected = 0.0;
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& t = surface.triangles[f];
    steps[f] = face_steps(x, t, m_spacing);
    const double area = 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
    const double sliver_count = steps[f] + 2.0 * area / (m_spacing * m_spacing);
    sliver[f] = steps[f] * steps[f] > 2.0 * sliver_count;
    expected += sliver[f] ? sliver_count : steps[f] * steps[f];
  }
  if (!(expected <= kMaxSamplesPerBody)) {
    throw Error("a dynamic body's " + std::to_string(surface.triangles.size()) + " faces would take about " +
                format_number(std::ceil(expected)) + " boundary samples at the fluid's spacing " +
                format_number(m_spacing) + " m, more than kMaxSamplesPerBody = " +
                format_number(kMaxSamplesPerBody) + ": a body this large for the water should be static");
  }
  Vec3Array points, normals;  // the samples on their faces, and the faces' outward normals
  std::vector<Index> faces;
  const auto add = [&](std::size_t f, const Vec3& w, const Vec3& n) {
    const Triangle& t = surface.triangles[f];
    body.samples.push_back({static_cast<Index>(f), w, 0.0, m_inset});
    points.push_back(w[0] * x[t[0]] + w[1] * x[t[1]] + w[2] * x[t[2]]);
    normals.push_back(n);
    faces.push_back(static_cast<Index>(f));
  };
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& t = surface.triangles[f];
    const Vec3 n = outward_normal(x, t);
    if (n.squaredNorm() == 0.0) continue;
    if (sliver[f]) {
      sample_sliver(x, t, m_spacing, [&](const Vec3& w) { add(f, w, n); });
      continue;
    }
    const int whole = static_cast<int>(steps[f]);
    for (int i = 0; i < whole; ++i) {
      for (int j = 0; i + j < whole; ++j) {
        // The sub-triangle pointing like the face, then (where there is one) the one pointing the other way.
        for (const Scalar third : {Scalar(1.0 / 3.0), Scalar(2.0 / 3.0)}) {
          if (third > 0.5 && i + j + 2 > whole) continue;
          const Scalar a = (i + third) / whole, b = (j + third) / whole;
          add(f, Vec3(1.0 - a - b, a, b), n);
        }
      }
    }
  }
  // A sample deeper than half the body behind it would stand outside the opposite face, in the water there:
  // a 2 mm plank's samples 6 mm inside its faces hung 4 mm under it and pushed the water as it came near,
  // which threw the 14 g plank up at 18 m/s (RigidBoundary.EverySampleLiesInsideAThinBody).
  const std::vector<Scalar> depth = depths_behind(surface, points, faces, normals, 2.0 * m_inset);
  for (std::size_t k = 0; k < points.size(); ++k) {
    body.samples[k].inset = std::min(m_inset, 0.5 * depth[k]);
    points[k] -= body.samples[k].inset * normals[k];
  }
  // Akinci et al. 2012 eq. 4: a sample where samples crowd (edges, corners) stands for less volume.
  const CubicSplineKernel kernel(m_spacing);
  NeighborSearch search(kernel.support_radius());
  search.build(points);
  NeighborList neighbors;
  search.find(points, neighbors, /*exclude_self=*/true);
  for (std::size_t b = 0; b < points.size(); ++b) {
    Scalar sum = kernel.value(0.0);
    for (const Index* k = neighbors.begin(b); k != neighbors.end(b); ++k)
      sum += kernel.value((points[b] - points[*k]).norm());
    body.samples[b].volume = 1.0 / sum;
  }
  return body;
}

bool RigidBoundary::place(const std::vector<RigidSurface>& surfaces) {
  m_placed.assign(surfaces.size(), nullptr);
  bool resampled = false;  // a body sampled afresh: its volumes are new, though its key was there before
  std::vector<std::uint64_t> keys;  // the dynamic bodies in order: their samples' layout
  std::unordered_set<std::uint64_t> seen;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const RigidSurface& surface = surfaces[s];
    if (surface.motion != RigidMotion::DYNAMIC) continue;
    seen.insert(surface.key);
    keys.push_back(surface.key);
    auto it = m_bodies.find(surface.key);
    if (it == m_bodies.end() || it->second.nodes != surface.positions_t0.size() ||
        it->second.triangles != surface.triangles.size() || it->second.instance != surface.instance) {
      it = m_bodies.insert_or_assign(surface.key, sample(surface)).first;
      resampled = true;
    }
    m_placed[s] = &it->second;
  }
  // Bodies gone from the world: a new body at the same address is sampled afresh.
  for (auto it = m_bodies.begin(); it != m_bodies.end();) {
    it = seen.count(it->first) ? std::next(it) : m_bodies.erase(it);
  }
  // A body that came, went or changed its place in the list changes the layout though none moved: then every
  // body is placed again (the same bits for those at rest) and the volumes, the bodies' own from their
  // sampling, are written again.
  const bool same_layout = keys == m_placed_keys && !resampled;
  if (!same_layout) {
    m_placed_keys = std::move(keys);
    std::size_t count = 0;
    for (const Body* body : m_placed)
      count += body ? body->samples.size() : 0;
    m_positions.resize(count);
    m_normals.resize(count);
    m_volumes.resize(count);
    std::size_t first = 0;
    for (const Body* body : m_placed) {
      if (!body) continue;
      for (std::size_t k = 0; k < body->samples.size(); ++k)
        m_volumes[first + k] = body->samples[k].volume;
      first += body->samples.size();
    }
  }
  bool changed = !same_layout;
  std::size_t first = 0;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (!m_placed[s]) continue;
    Body& body = *m_placed[s];
    const std::size_t at = first;
    first += body.samples.size();
    const Vec3Array& x = surfaces[s].positions_t0;
    // Bit for bit where it was placed last (a body at rest, which its engine does not move): its samples in
    // positions() are those a placing would give. A NaN node compares unequal, so such a body is placed
    // again and the fluid names it.
    if (same_layout && body.placed_at == x) continue;
    changed = true;
    body.placed_at = x;
    place_samples(surfaces[s], body, at);
  }
  return changed;
}

void RigidBoundary::place_samples(const RigidSurface& surface, const Body& body, std::size_t first) {
  const Vec3Array& x = surface.positions_t0;
  // One normal per face, not per sample: a face carries a dozen samples or more, and the cross product
  // and square root per sample were most of placing them (issue 41's profile). The same bits either way.
  m_face_normals.resize(surface.triangles.size());
  for (std::size_t f = 0; f < surface.triangles.size(); ++f)
    m_face_normals[f] = outward_normal(x, surface.triangles[f]);
  // Written where the fluid reads them, body after body: placing them in arrays of their body's and copying
  // those over was a third more work in issue 41's level, whose three bodies move every frame (callgrind).
  Vec3* positions = m_positions.data() + first;
  Vec3* normals = m_normals.data() + first;
  // A face's samples come one after another (sample()): its nodes and its normal are fetched once per face,
  // not per sample.
  const Sample* samples = body.samples.data();  // read once: the stores below could alias the vector
  const std::size_t count = body.samples.size();
  Index face = static_cast<Index>(-1);
  Vec3 x0 = Vec3::Zero(), x1 = x0, x2 = x0, n = x0;
  for (std::size_t k = 0; k < count; ++k) {
    const Sample& sample = samples[k];
    if (sample.triangle != face) {
      face = sample.triangle;
      const Triangle& t = surface.triangles[face];
      x0 = x[t[0]];
      x1 = x[t[1]];
      x2 = x[t[2]];
      n = m_face_normals[face];
    }
    positions[k] =
        sample.weights[0] * x0 + sample.weights[1] * x1 + sample.weights[2] * x2 - sample.inset * n;
    normals[k] = n;
  }
}

void RigidBoundary::spread(const std::vector<RigidSurface>& surfaces, const Vec3Array& sample_impulses,
                           const std::vector<std::size_t>& first_node, Vec3Array& node_impulses) const {
  std::size_t k = 0;
  for (std::size_t s = 0; s < surfaces.size() && s < m_placed.size(); ++s) {
    if (!m_placed[s]) continue;
    for (const Sample& sample : m_placed[s]->samples) {
      if (k >= sample_impulses.size()) return;
      const Vec3& impulse = sample_impulses[k++];
      // Most samples lie where no water reached them: their impulse is zero, and adding w times zero changes
      // no node but one at -0 (to +0); Simulation's start at +0, which sums never turn into -0.
      if (impulse.x() == 0.0 && impulse.y() == 0.0 && impulse.z() == 0.0) continue;
      const Triangle& t = surfaces[s].triangles[sample.triangle];
      for (int i = 0; i < 3; ++i)
        node_impulses[first_node[s] + t[i]] += sample.weights[i] * impulse;
    }
  }
}

}  // namespace drench
