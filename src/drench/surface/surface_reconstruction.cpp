#include <drench/surface/surface_reconstruction.hpp>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

#include <drench/ccd/exact_predicates.hpp>
#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/surface/anisotropic_kernels.hpp>
#include <drench/surface/particle_cells.hpp>
#include <drench/surface/triangle_bins.hpp>
#include <drench/surface/vdb_mesher.hpp>

namespace drench {
namespace {

std::string number(double x) {
  return format_number(x);
}

void check_input(const Vec3Array& particles, Scalar spacing, const SurfaceSettings& settings,
                 const std::vector<SurfaceObstacle>& obstacles) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw SceneError("surface reconstruction: fluid.particle_spacing must be > 0 and finite, got " +
                     number(spacing));
  }
  if (!(settings.cell_size >= 0.0) || !std::isfinite(settings.cell_size)) {
    throw SceneError("surface.cell_size must be > 0 and finite (or 0 for half the particle spacing), got " +
                     number(settings.cell_size));
  }
  if (!std::isfinite(settings.contact_offset)) {
    throw SceneError("surface.contact_offset must be finite, got " + number(settings.contact_offset));
  }
  if (!(settings.kernel_radius_in_spacings > 0.0) || !(settings.particle_radius_in_spacings > 0.0) ||
      !std::isfinite(settings.kernel_radius_in_spacings) ||
      !std::isfinite(settings.particle_radius_in_spacings)) {
    throw SceneError("surface: the kernel and particle radii must be > 0 and finite");
  }
  if (settings.kernel == SurfaceKernel::ANISOTROPIC) {
    if (settings.field != SurfaceField::DENSITY) {
      throw SceneError(
          "surface.kernel \"anisotropic\" is a kernel of the density field (Yu & Turk 2013): "
          "surface.field must be \"density\"");
    }
    const auto require = [](bool ok, const char* key, const char* range, double value) {
      if (!ok)
        throw SceneError(std::string("surface.") + key + " must be " + range + ", got " + number(value));
    };
    require(settings.smoothing >= 0.0 && settings.smoothing <= 1.0, "smoothing", "in [0, 1]",
            settings.smoothing);
    require(settings.max_anisotropy >= 1.0 && std::isfinite(settings.max_anisotropy), "max_anisotropy",
            ">= 1 and finite", settings.max_anisotropy);
    require(settings.anisotropy_scale > 0.0 && std::isfinite(settings.anisotropy_scale), "anisotropy_scale",
            "> 0 and finite", settings.anisotropy_scale);
    require(settings.isolated_scale > 0.0 && settings.isolated_scale <= 2.0, "isolated_scale", "in (0, 2]",
            settings.isolated_scale);
    require(settings.min_neighbours >= 1, "min_neighbours", ">= 1", settings.min_neighbours);
  }
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (!particles[i].allFinite()) {
      throw SceneError("surface reconstruction: particle " + std::to_string(i) +
                       " has a non-finite position");
    }
  }
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const SurfaceObstacle& o = obstacles[k];
    if (o.positions == nullptr || o.triangles == nullptr) {
      throw SceneError("surface reconstruction: obstacle " + std::to_string(k) + " has no mesh");
    }
    for (std::size_t i = 0; i < o.positions->size(); ++i) {
      if (!(*o.positions)[i].allFinite()) {
        throw SceneError("surface reconstruction: obstacle " + std::to_string(k) + " node " +
                         std::to_string(i) + " has a non-finite position");
      }
    }
    for (std::size_t t = 0; t < o.triangles->size(); ++t) {
      for (Index v : (*o.triangles)[t]) {
        if (v >= o.positions->size()) {
          throw SceneError("surface reconstruction: obstacle " + std::to_string(k) + " triangle " +
                           std::to_string(t) + " names node " + std::to_string(v) + " of " +
                           std::to_string(o.positions->size()));
        }
      }
    }
  }
}

/// Area-weighted mean of the faces' normals at each vertex; a vertex of no face keeps +y.
void compute_vertex_normals(SurfaceMesh& mesh) {
  mesh.normals.assign(mesh.positions.size(), Vec3::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.positions[t[0]];
    const Vec3 n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);
    for (Index v : t)
      mesh.normals[v] += n;
  }
  for (Vec3& n : mesh.normals) {
    const double length = n.norm();
    n = length > 0.0 ? Vec3(n / length) : Vec3::UnitY();
  }
}

/// Zhu & Bridson 2005's kernel, (1 - s^2)^3 for s = distance / radius < 1.
inline double zb_kernel(double s2) {
  const double t = 1.0 - s2;
  return t > 0.0 ? t * t * t : 0.0;
}

/// The colour field's level of the surface. Müller et al. 2003 leave it to the user; 0.6 is where the field
/// of a flat lattice (kernel radius 2 spacings, the default) crosses its physical surface, half a spacing
/// beyond its last layer, so that a ball keeps its volume (tests/surface: Fields/SurfaceOfABall).
constexpr double kColourLevel = 0.6;
/// The same for the anisotropic kernels (Yu & Turk 2013 leave the level to the user too): where a ball of 10
/// spacings' radius keeps its volume (0.10: +0.5%, 0.15: -0.4%; tests/surface: Fields/SurfaceOfABall),
/// low because a free surface's kernels are flattened along its normal and their centres smoothed inwards.
constexpr double kAnisotropicLevel = 0.12;

/// Fraction of the squared distance to the nearest face below which a segment needs no crossing test.
constexpr double kClearanceMargin = 1.0 - 1e-6;

/// 1 / sum_j k(|x_i - x_j| / radius) for every particle i (itself included, so >= 1 and finite): the
/// inverse of its number density in kernel units, by slot of `cells` (ParticleCells::positions()). Onderik et
/// al. 2011 divide each particle's Zhu-Bridson weight by it; as SPH's m / rho it is also the particle's
/// volume in the colour field (an interior particle of a regular lattice sums to about 1 there).
std::vector<double> inverse_number_densities(const ParticleCells& cells, Scalar radius) {
  const Vec3Array& particles = cells.positions();
  std::vector<double> inverse(particles.size());
  const double radius2 = radius * radius;
  parallel_for(particles.size(), kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      double sum = 0.0;
      cells.for_each_near(particles[i], [&](Index j) {
        const double d2 = (particles[j] - particles[i]).squaredNorm();
        if (d2 < radius2) sum += zb_kernel(d2 / radius2);
      });
      inverse[i] = 1.0 / sum;
    }
  });
  return inverse;
}

using Faces = std::vector<std::pair<Index, Index>>;  // (obstacle, triangle)

/// Fig. 2b for the node at x: whether it is within `offset` of one of `faces` or one of them passes through
/// a grid cell next to it (a drench addition that makes the guarantee exact: no cell a face meets then holds
/// a piece of surface, and OpenVDB's quads, each inside the four cells around one grid edge, cannot cross
/// the face). Lowers `clearance2` to the squared distance to the nearest face (unit: m^2) until the first
/// face that resets the node.
bool node_is_reset(const Vec3& x, const Faces& faces, const std::vector<SurfaceObstacle>& obstacles,
                   double offset, double cell, double& clearance2) {
  for (const auto& [o, t] : faces) {
    const Triangle& tri = (*obstacles[o].triangles)[t];
    const Vec3Array& p = *obstacles[o].positions;
    const Vec3 w = closest_point_barycentric(x, p[tri[0]], p[tri[1]], p[tri[2]]);
    const Vec3 closest = w.x() * p[tri[0]] + w.y() * p[tri[1]] + w.z() * p[tri[2]];
    clearance2 = std::min(clearance2, (closest - x).squaredNorm());
    if ((closest - x).squaredNorm() < offset * offset ||
        triangle_overlaps_cube(p[tri[0]], p[tri[1]], p[tri[2]], x, cell * (1.0 + 1e-9)))
      return true;
  }
  return false;
}

/// The anisotropic kernels by slot (in the order of ParticleCells over their centres, cells of half the
/// longest reach): what a grid node needs to add one to its field.
struct SlotKernels {
  const Vec3Array* centres = nullptr;       ///< smoothed centres (unit: m)
  std::vector<Eigen::Matrix3d> transforms;  ///< G (unit: 1/m)
  std::vector<double> amplitudes;           ///< det(G) R^3 times the particle's volume in kernel units
  std::vector<double> reach2;               ///< squared longest semi-axis (unit: m^2)
  /// The box of grid node indices that holds the kernel's support, a node wider on every side than its
  /// bounding box (half-widths: the row norms of G^-1), so no rounding leaves a node of the support out.
  std::vector<Vec3i> lo, hi;
};

/// A leaf of OpenVDB's tree: 8^3 nodes, whose active ones active_nodes() lists together.
struct LeafRun {
  Vec3i leaf;              ///< node index / 8
  std::size_t begin, end;  ///< its nodes in the active node list
};

struct LeafHash {
  std::size_t operator()(const Vec3i& c) const {
    return (static_cast<std::size_t>(static_cast<std::uint32_t>(c.x())) * 73856093u) ^
           (static_cast<std::size_t>(static_cast<std::uint32_t>(c.y())) * 19349663u) ^
           (static_cast<std::size_t>(static_cast<std::uint32_t>(c.z())) * 83492791u);
  }
};

Vec3i leaf_of(const Vec3i& node) {
  return Vec3i(node.x() >> 3, node.y() >> 3, node.z() >> 3);
}

int offset_in_leaf(int x, int y, int z) {
  return ((x & 7) << 6) | ((y & 7) << 3) | (z & 7);
}

/// Yu & Turk 2013's field at every node of `nodes` (listed leaf by leaf, as active_nodes() lists them) into
/// `values`, contact-aware (sec. 4): a node within the contact offset of a face is reset (Fig. 2b), and a
/// kernel adds to a node only if the segment from the node to its centre crosses no face (Fig. 2a). Each
/// kernel is spread over the nodes of its own support, leaf by leaf, row by row of the grid (the row's
/// interval from the quadratic |G (x - c)|^2 < 1), where a node gathering from every centre within the
/// longest reach tested 37 candidates for each kernel whose support holds it (the V's frames: 68 million
/// for 8.6 million within reach and 1.8 million in a support). A node still receives its kernels in slot
/// order, each term computed as a gathering node computed it: the same sums to the bit. A node's reset test
/// runs when the first kernel reaches it. Returns (occluded pairs, reset nodes).
std::pair<std::uint64_t, std::uint64_t> anisotropic_field(const std::vector<Vec3i>& nodes, Scalar cell,
                                                          Scalar radius, Scalar reach, Scalar offset,
                                                          Scalar particle_spacing, const SlotKernels& kernels,
                                                          const TriangleBins* bins,
                                                          const std::vector<SurfaceObstacle>& obstacles,
                                                          const ObstacleFaceBoxes& face_boxes, float outside,
                                                          std::vector<float>& values) {
  std::vector<LeafRun> runs;
  std::unordered_map<Vec3i, Index, LeafHash> run_of;
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const Vec3i leaf = leaf_of(nodes[n]);
    if (runs.empty() || runs.back().leaf != leaf) {
      assert(run_of.count(leaf) == 0 && "active_nodes() lists a leaf's nodes together");
      run_of.emplace(leaf, static_cast<Index>(runs.size()));
      runs.push_back({leaf, n, n});
    }
    runs.back().end = n + 1;
  }
  // Each leaf's kernels (those whose node box meets it), in slot order: counted, then filled.
  const std::size_t slots = kernels.transforms.size();
  std::vector<std::size_t> first(runs.size() + 1, 0);
  IndexArray leaf_kernels;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::size_t> next(first.begin(), first.end() - 1);
    for (std::size_t s = 0; s < slots; ++s) {
      const Vec3i a = leaf_of(kernels.lo[s]), b = leaf_of(kernels.hi[s]);
      for (int z = a.z(); z <= b.z(); ++z)
        for (int y = a.y(); y <= b.y(); ++y)
          for (int x = a.x(); x <= b.x(); ++x) {
            const auto it = run_of.find(Vec3i(x, y, z));
            if (it == run_of.end()) continue;
            if (pass == 0)
              ++first[it->second + 1];
            else
              leaf_kernels[next[it->second]++] = static_cast<Index>(s);
          }
    }
    if (pass == 0) {
      for (std::size_t r = 1; r < first.size(); ++r)
        first[r] += first[r - 1];
      leaf_kernels.resize(first.back());
    }
  }
  const Vec3Array& centres = *kernels.centres;
  // The reset looks within the kernel radius, as for the isotropic kernels (and no farther than the reach,
  // as the faces a node collects for its segments).
  const Scalar reset_reach = std::min(reach, radius);

  using Counts = std::pair<std::uint64_t, std::uint64_t>;
  return parallel_reduce(
      runs.size(), 8, Counts(0, 0),
      [&](std::size_t begin, std::size_t end) {
        std::uint64_t occluded = 0, reset = 0;
        // Per offset in the leaf: its node (or -1: inactive), whether the reset test has run and found it
        // outside (Fig. 2b), the squared distance to its nearest face, its field.
        std::array<int, 512> local;
        std::array<signed char, 512> state;  // 0: not tested yet, 1: reset, 2: open
        std::array<double, 512> weight, clearance2;
        // A node's faces within the longest reach, for its segments' tests: collected for the leaf and
        // filtered for the node only when a segment is longer than the distance to the nearest face.
        std::vector<Faces> near(512);
        std::array<bool, 512> near_ready;
        Faces block_reset, block_reach, faces;
        for (std::size_t r = begin; r < end; ++r) {
          const LeafRun& run = runs[r];
          const Vec3i origin = 8 * run.leaf;
          const Vec3 leaf_lo = origin.cast<double>() * cell,
                     leaf_hi = (origin + Vec3i::Constant(7)).cast<double>() * cell;
          local.fill(-1);
          near_ready.fill(false);
          bool reset_collected = false, reach_collected = false;
          for (std::size_t n = run.begin; n < run.end; ++n) {
            const int k = offset_in_leaf(nodes[n].x(), nodes[n].y(), nodes[n].z());
            local[k] = static_cast<int>(n);
            state[k] = 0;
            weight[k] = 0.0;
          }
          // The reset test of a node no kernel reaches would change nothing (it stays outside): it runs when
          // the first kernel does.
          const auto is_open = [&](int k, const Vec3& x) {
            if (state[k] == 0) {
              // A face outside the box of the kernel radius is farther than it.
              clearance2[k] = bins ? radius * radius : std::numeric_limits<double>::infinity();
              state[k] = 2;
              if (bins) {
                if (!reset_collected) {
                  bins->collect_box(leaf_lo - Vec3::Constant(reset_reach),
                                    leaf_hi + Vec3::Constant(reset_reach), block_reset);
                  reset_collected = true;
                }
                bins->filter_box(block_reset, x - Vec3::Constant(reset_reach),
                                 x + Vec3::Constant(reset_reach), faces);
                if (node_is_reset(x, faces, obstacles, offset, cell, clearance2[k])) {
                  state[k] = 1;
                  ++reset;
                }
              }
            }
            return state[k] == 2;
          };
          for (std::size_t e = first[r]; e < first[r + 1]; ++e) {
            const Index s = leaf_kernels[e];
            const Vec3& c = centres[s];
            const Eigen::Matrix3d& g = kernels.transforms[s];
            const Vec3i lo = kernels.lo[s].cwiseMax(origin),
                        hi = kernels.hi[s].cwiseMin(origin + Vec3i::Constant(7));
            // Along a row x(t) = x0 + t cell e_x: |G (x(t) - c)|^2 = |u|^2 + 2 t u.v + t^2 |v|^2, below 1 on
            // an interval; widened by 1e-6 in q so that rounding never drops a node of the support.
            const int i0 = static_cast<int>(std::floor(c.x() / cell));
            const Vec3 v = cell * g.col(0);
            const double vv = v.squaredNorm();
            for (int z = lo.z(); z <= hi.z(); ++z) {
              for (int y = lo.y(); y <= hi.y(); ++y) {
                const Vec3 u = g * (Vec3i(i0, y, z).cast<double>() * cell - c);
                const double uv = u.dot(v);
                const double discriminant = uv * uv - vv * (u.squaredNorm() - (1.0 + 1e-6));
                if (discriminant < 0.0) continue;
                const double root = std::sqrt(discriminant);
                const int x0 = std::max(lo.x(), i0 + static_cast<int>(std::floor((-uv - root) / vv)));
                const int x1 = std::min(hi.x(), i0 + static_cast<int>(std::ceil((-uv + root) / vv)));
                for (int i = x0; i <= x1; ++i) {
                  const int k = offset_in_leaf(i, y, z);
                  if (local[k] < 0) continue;
                  // As a node gathering its kernels computes them, to the bit.
                  const Vec3 x = Vec3i(i, y, z).cast<double>() * cell;
                  const Vec3 d = x - c;
                  if (d.squaredNorm() >= kernels.reach2[s]) continue;
                  const double q = (g * d).squaredNorm();
                  if (q >= 1.0) continue;
                  if (!is_open(k, x)) continue;
                  // A segment shorter than the distance to the nearest face crosses none (a margin far
                  // above segment_crosses_triangle's tolerance); a longer one stays within the faces of
                  // the node's reach.
                  if (bins && d.squaredNorm() >= kClearanceMargin * clearance2[k]) {
                    if (!near_ready[k]) {
                      if (!reach_collected) {
                        bins->collect_box(leaf_lo - Vec3::Constant(reach), leaf_hi + Vec3::Constant(reach),
                                          block_reach);
                        reach_collected = true;
                      }
                      bins->filter_box(block_reach, x - Vec3::Constant(reach), x + Vec3::Constant(reach),
                                       near[k]);
                      near_ready[k] = true;
                    }
                    if (segment_crosses_faces(x, c, near[k], obstacles, face_boxes)) {
                      ++occluded;
                      continue;
                    }
                  }
                  weight[k] += kernels.amplitudes[s] * zb_kernel(q);
                }
              }
            }
          }
          for (std::size_t n = run.begin; n < run.end; ++n) {
            const int k = offset_in_leaf(nodes[n].x(), nodes[n].y(), nodes[n].z());
            if (state[k] == 2 && weight[k] > 0.0)
              values[n] = static_cast<float>(
                  std::min<double>((kAnisotropicLevel - weight[k]) * particle_spacing, outside));
          }
        }
        return Counts(occluded, reset);
      },
      [](const Counts& a, const Counts& b) { return Counts(a.first + b.first, a.second + b.second); });
}

}  // namespace

SurfaceMesh reconstruct_surface(const Vec3Array& particles, Scalar particle_spacing,
                                const SurfaceSettings& settings,
                                const std::vector<SurfaceObstacle>& obstacles, SurfaceStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  check_input(particles, particle_spacing, settings, obstacles);
  SurfaceMesh mesh;
  SurfaceStats local;
  if (particles.empty()) {
    if (stats) *stats = local;
    return mesh;
  }
  const Scalar cell = settings.resolved_cell_size(particle_spacing);
  const Scalar radius = settings.kernel_radius_in_spacings * particle_spacing;
  const Scalar particle_radius = settings.particle_radius_in_spacings * particle_spacing;
  const Scalar offset = settings.resolved_contact_offset(particle_spacing);
  // Nodes nobody reaches, and reset nodes, are one cell outside: far enough that the surface passes between
  // them and an inside node, near enough that marching cubes puts it close to the inside node.
  const float outside = static_cast<float>(cell);

  // Each stage's end is the next one's start: their times add up to the whole but for the input check.
  auto stage_start = std::chrono::steady_clock::now();
  const auto lap = [&stage_start](double& seconds) {
    const auto now = std::chrono::steady_clock::now();
    seconds = std::chrono::duration<double>(now - stage_start).count();
    stage_start = now;
  };
  const bool aware = settings.contact_aware && !obstacles.empty();
  const TriangleBins bins = aware ? TriangleBins(obstacles, radius) : TriangleBins();
  const bool anisotropic = settings.kernel == SurfaceKernel::ANISOTROPIC;
  AnisotropicKernels kernels;
  // How far a node looks for particles (unit: m): the kernel radius, or the longest anisotropic kernel's
  // reach.
  Scalar reach = radius;
  if (anisotropic) {
    kernels = anisotropic_kernels_yu_turk(particles, radius, settings, obstacles, aware ? &bins : nullptr);
    reach = *std::max_element(kernels.reaches.begin(), kernels.reaches.end());
    local.anisotropic = kernels.anisotropic;
  }
  lap(local.seconds_kernels);
  VdbNodeGrid grid(cell, outside);
  // Per particle, the box of nodes its anisotropic kernel's support can touch.
  std::vector<Vec3i> box_lo, box_hi;
  if (anisotropic) {
    grid.check_range(kernels.centres);
    box_lo.resize(particles.size());
    box_hi.resize(particles.size());
    for (std::size_t i = 0; i < particles.size(); ++i) {
      // The support |G d| < 1 is d = G^-1 w for |w| < 1: its half-width along axis k is row k's norm. A
      // node more on every side, so no rounding leaves a node of the support out.
      const Vec3 half = kernels.transforms[i].inverse().rowwise().norm();
      const Vec3& c = kernels.centres[i];
      box_lo[i] = ((c - half) / cell).array().floor().cast<int>() - 1;
      box_hi[i] = ((c + half) / cell).array().ceil().cast<int>() + 1;
    }
    grid.activate_boxes(box_lo, box_hi);
  } else {
    grid.activate_around(particles, static_cast<int>(std::ceil(radius / cell)));
  }
  const std::vector<Vec3i> nodes = grid.active_nodes();
  local.nodes = nodes.size();
  lap(local.seconds_grid);

  const ParticleCells cells(particles, radius);
  const std::vector<double> inverse_density = inverse_number_densities(cells, radius);
  const Vec3Array& sorted = cells.positions();
  const bool density_field = settings.field == SurfaceField::DENSITY;
  // The anisotropic kernels by slot of their own cells (of half the longest reach), each with its particle's
  // volume (the isotropic inverse number density, Yu & Turk's m_j / rho_j) in its amplitude. The cells give
  // the order a node sums its kernels in (that of the surfaces made before the kernels were spread: the
  // same bits) and neighbouring kernels neighbouring slots.
  std::optional<ParticleCells> centre_cells;
  SlotKernels slot_kernels;
  if (anisotropic) {
    std::vector<double> volume(particles.size());
    for (std::size_t s = 0; s < sorted.size(); ++s)
      volume[cells.order()[s]] = inverse_density[s];
    centre_cells.emplace(kernels.centres, 0.5 * reach, 2);
    const IndexArray& order = centre_cells->order();
    slot_kernels.centres = &centre_cells->positions();
    slot_kernels.transforms.resize(order.size());
    slot_kernels.amplitudes.resize(order.size());
    slot_kernels.reach2.resize(order.size());
    slot_kernels.lo.resize(order.size());
    slot_kernels.hi.resize(order.size());
    for (std::size_t s = 0; s < order.size(); ++s) {
      slot_kernels.transforms[s] = kernels.transforms[order[s]];
      slot_kernels.amplitudes[s] = kernels.amplitudes[order[s]] * volume[order[s]];
      slot_kernels.reach2[s] = kernels.reaches[order[s]] * kernels.reaches[order[s]];
      slot_kernels.lo[s] = box_lo[order[s]];
      slot_kernels.hi[s] = box_hi[order[s]];
    }
  }
  // The visibility test of an anisotropic kernel skips the faces its segment's box misses: its node's faces
  // within the longest reach are many more than a segment can cross.
  const ObstacleFaceBoxes face_boxes =
      anisotropic && aware ? obstacle_face_boxes(obstacles) : ObstacleFaceBoxes();
  lap(local.seconds_densities);
  std::vector<float> values(nodes.size(), outside);
  const double radius2 = radius * radius;

  // (occluded, reset), integer sums.
  using Counts = std::pair<std::uint64_t, std::uint64_t>;
  Counts counts;
  if (anisotropic) {
    counts = anisotropic_field(nodes, cell, radius, reach, offset, particle_spacing, slot_kernels,
                               aware ? &bins : nullptr, obstacles, face_boxes, outside, values);
  } else {
    counts = parallel_reduce(
        nodes.size(), 1024, Counts(0, 0),
        [&](std::size_t begin, std::size_t end) {
          std::uint64_t occluded = 0, reset = 0;
          Faces near;  // within the kernel radius of the node
          // The faces within reach of the node's block of 8^3 nodes (OpenVDB's leaf; active_nodes() lists
          // the nodes leaf by leaf), collected once per block and filtered per node: the node's list is the
          // same, without a node's hash lookups and sort (bench_surface jet_on_cloth/contact_aware).
          Faces block_near;
          Vec3i block = Vec3i::Constant(std::numeric_limits<int>::min());
          for (std::size_t n = begin; n < end; ++n) {
            const Vec3 x = nodes[n].cast<double>() * cell;
            near.clear();
            if (aware) {
              const Vec3i leaf = leaf_of(nodes[n]);
              if (leaf != block) {
                block = leaf;
                const Vec3 lo = (8 * leaf).cast<double>() * cell,
                           hi = (8 * leaf + Vec3i::Constant(7)).cast<double>() * cell;
                bins.collect_box(lo - Vec3::Constant(radius), hi + Vec3::Constant(radius), block_near);
              }
              bins.filter_box(block_near, x - Vec3::Constant(radius), x + Vec3::Constant(radius), near);
            }
            double clearance2 = std::numeric_limits<double>::infinity();
            if (!near.empty() && node_is_reset(x, near, obstacles, offset, cell, clearance2)) {  // Fig. 2b
              ++reset;
              continue;
            }
            double weight = 0.0;
            Vec3 mean = Vec3::Zero();
            if (near.empty()) {
              // No face in reach, so no visibility test: a lambda this small is inlined into
              // for_each_near's loop, where the one below, with the segment tests, was a call per candidate
              // (perf: the field's lambda out of line, 56% of a reconstruction). Same sums in the same
              // order: the same bits.
              cells.for_each_near(x, [&](Index i) {
                const Vec3& p = sorted[i];
                const double d2 = (p - x).squaredNorm();
                if (d2 >= radius2) return;
                const double w = zb_kernel(d2 / radius2) * inverse_density[i];
                weight += w;
                mean += w * p;
              });
            } else {
              cells.for_each_near(x, [&](Index i) {
                const Vec3& p = sorted[i];
                const double d2 = (p - x).squaredNorm();
                if (d2 >= radius2) return;
                for (const auto& [o, t] : near) {  // Fig. 2a: only particles the node sees
                  const Triangle& tri = (*obstacles[o].triangles)[t];
                  const Vec3Array& q = *obstacles[o].positions;
                  if (segment_crosses_triangle(x, p, q[tri[0]], q[tri[1]], q[tri[2]])) {
                    ++occluded;
                    return;
                  }
                }
                const double w = zb_kernel(d2 / radius2) * inverse_density[i];
                weight += w;
                mean += w * p;
              });
            }
            if (weight > 0.0 && density_field) {
              // The colour field is about 1 inside and 0 far outside; scaled by the spacing, its values near
              // the surface are lengths like the Zhu-Bridson field's, which the mesher's interpolation
              // expects.
              values[n] =
                  static_cast<float>(std::min<double>((kColourLevel - weight) * particle_spacing, outside));
            } else if (weight > 0.0) {
              mean /= weight;
              values[n] = static_cast<float>(std::min<double>((x - mean).norm() - particle_radius, outside));
            }
          }
          return Counts(occluded, reset);
        },
        [](const Counts& a, const Counts& b) { return Counts(a.first + b.first, a.second + b.second); });
  }
  lap(local.seconds_field);
  local.occluded = counts.first;
  local.reset_nodes = counts.second;
  grid.set_values(nodes, values);
  grid.mesh(mesh.positions, mesh.triangles);
  compute_vertex_normals(mesh);
  lap(local.seconds_mesh);
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return mesh;
}

std::uint64_t count_surface_intersections(const SurfaceMesh& surface,
                                          const std::vector<SurfaceObstacle>& obstacles) {
  if (surface.triangles.empty() || obstacles.empty()) return 0;
  double edges = 0.0;
  for (const Triangle& t : surface.triangles)
    edges += (surface.positions[t[1]] - surface.positions[t[0]]).norm();
  const double cell = std::max(4.0 * edges / static_cast<double>(surface.triangles.size()), 1e-6);
  const TriangleBins bins(obstacles, cell);
  return parallel_reduce(
      surface.triangles.size(), 256, std::uint64_t{0},
      [&](std::size_t begin, std::size_t end) {
        std::uint64_t found = 0;
        std::vector<std::pair<Index, Index>> near;
        for (std::size_t s = begin; s < end; ++s) {
          const Triangle& st = surface.triangles[s];
          const Vec3& a = surface.positions[st[0]];
          const Vec3& b = surface.positions[st[1]];
          const Vec3& c = surface.positions[st[2]];
          bins.collect_box(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c), near);
          for (const auto& [o, t] : near) {
            const Triangle& ot = (*obstacles[o].triangles)[t];
            const Vec3Array& q = *obstacles[o].positions;
            if (ccd::triangles_meet_exact(a, b, c, q[ot[0]], q[ot[1]], q[ot[2]])) ++found;
          }
        }
        return found;
      },
      std::plus<std::uint64_t>());
}

}  // namespace drench
