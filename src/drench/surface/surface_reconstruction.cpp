#include <drench/surface/surface_reconstruction.hpp>

#include <algorithm>
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
  if (anisotropic) {
    std::vector<int> reaches(particles.size());
    for (std::size_t i = 0; i < reaches.size(); ++i)
      reaches[i] = static_cast<int>(std::ceil(kernels.reaches[i] / cell));
    grid.activate_around(kernels.centres, reaches);
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
  // The anisotropic kernels by slot of their own cells (of the longest reach), each with its particle's
  // volume (the isotropic inverse number density, Yu & Turk's m_j / rho_j) in its amplitude.
  std::optional<ParticleCells> centre_cells;
  std::vector<Eigen::Matrix3d> slot_transforms;
  std::vector<double> slot_amplitudes, slot_reach2;
  if (anisotropic) {
    std::vector<double> volume(particles.size());
    for (std::size_t s = 0; s < sorted.size(); ++s)
      volume[cells.order()[s]] = inverse_density[s];
    // Cells of half the longest reach, two rings around: a node's candidates fill 5^3 / 8 = 16 reach^3,
    // where cells of the reach hold 27 reach^3.
    centre_cells.emplace(kernels.centres, 0.5 * reach, 2);
    const IndexArray& order = centre_cells->order();
    slot_transforms.resize(order.size());
    slot_amplitudes.resize(order.size());
    slot_reach2.resize(order.size());
    for (std::size_t s = 0; s < order.size(); ++s) {
      slot_transforms[s] = kernels.transforms[order[s]];
      slot_amplitudes[s] = kernels.amplitudes[order[s]] * volume[order[s]];
      slot_reach2[s] = kernels.reaches[order[s]] * kernels.reaches[order[s]];
    }
  }
  // The visibility test of an anisotropic kernel skips the faces its segment's box misses: its node's faces
  // within the longest reach are many more than a segment can cross.
  const ObstacleFaceBoxes face_boxes =
      anisotropic && aware ? obstacle_face_boxes(obstacles) : ObstacleFaceBoxes();
  lap(local.seconds_densities);
  std::vector<float> values(nodes.size(), outside);
  const double radius2 = radius * radius;

  // Per chunk of nodes: (occluded, reset), integer sums.
  using Counts = std::pair<std::uint64_t, std::uint64_t>;
  const Counts counts = parallel_reduce(
      nodes.size(), 1024, Counts(0, 0),
      [&](std::size_t begin, std::size_t end) {
        std::uint64_t occluded = 0, reset = 0;
        std::vector<std::pair<Index, Index>> near;  // (obstacle, triangle) within reach of the node
        // The faces within reach of the node's block of 8^3 nodes (OpenVDB's leaf; active_nodes() lists the
        // nodes leaf by leaf), collected once per block and filtered per node: the node's list is the same,
        // without a node's hash lookups and sort (bench_surface jet_on_cloth/contact_aware).
        std::vector<std::pair<Index, Index>> block_near;
        std::vector<std::pair<Index, Index>> near_radius;
        Vec3i block = Vec3i::Constant(std::numeric_limits<int>::min());
        for (std::size_t n = begin; n < end; ++n) {
          const Vec3 x = nodes[n].cast<double>() * cell;
          near.clear();
          if (aware) {
            const Vec3i leaf(nodes[n].x() >> 3, nodes[n].y() >> 3, nodes[n].z() >> 3);
            if (leaf != block) {
              block = leaf;
              const Vec3 lo = (8 * leaf).cast<double>() * cell,
                         hi = (8 * leaf + Vec3i::Constant(7)).cast<double>() * cell;
              bins.collect_box(lo - Vec3::Constant(reach), hi + Vec3::Constant(reach), block_near);
            }
            bins.filter_box(block_near, x - Vec3::Constant(reach), x + Vec3::Constant(reach), near);
            // The anisotropic kernels' longest reach collects more faces than the reset needs: it looks
            // within the kernel radius, as for the isotropic kernels.
            if (anisotropic)
              bins.filter_box(near, x - Vec3::Constant(radius), x + Vec3::Constant(radius), near_radius);
          }
          bool too_close = false;
          // Squared distance to the nearest face; a face outside the box of the kernel radius is farther.
          double clearance2 = anisotropic ? radius * radius : std::numeric_limits<double>::infinity();
          for (const auto& [o, t] : anisotropic ? near_radius : near) {
            const Triangle& tri = (*obstacles[o].triangles)[t];
            const Vec3Array& p = *obstacles[o].positions;
            const Vec3 w = closest_point_barycentric(x, p[tri[0]], p[tri[1]], p[tri[2]]);
            const Vec3 closest = w.x() * p[tri[0]] + w.y() * p[tri[1]] + w.z() * p[tri[2]];
            clearance2 = std::min(clearance2, (closest - x).squaredNorm());
            // The paper's delta, and a drench addition that makes the guarantee exact: a node of any grid
            // cell the face passes through is outside too, so no cell the face meets holds a piece of
            // surface, and OpenVDB's quads, each inside the four cells around one grid edge, cannot cross the
            // face.
            if ((closest - x).squaredNorm() < offset * offset ||
                triangle_overlaps_cube(p[tri[0]], p[tri[1]], p[tri[2]], x, cell * (1.0 + 1e-9))) {
              too_close = true;
              break;
            }
          }
          if (too_close) {  // Fig. 2b
            ++reset;
            continue;
          }
          double weight = 0.0;
          Vec3 mean = Vec3::Zero();
          if (anisotropic) {
            // Yu & Turk 2013's field, the visibility test now from the node to each kernel's centre: a kernel
            // whose long axis reaches across a face to the node is occluded there like a particle.
            const Vec3Array& centres = centre_cells->positions();
            centre_cells->for_each_near(x, [&](Index j) {
              const Vec3 d = x - centres[j];
              if (d.squaredNorm() >= slot_reach2[j]) return;
              const double q = (slot_transforms[j] * d).squaredNorm();
              if (q >= 1.0) return;
              // A segment shorter than the distance to the nearest face crosses none (a margin far above
              // segment_crosses_triangle's tolerance); a longer one stays within the faces collected.
              if (d.squaredNorm() < kClearanceMargin * clearance2) {
                weight += slot_amplitudes[j] * zb_kernel(q);
                return;
              }
              const Vec3 lo = x.cwiseMin(centres[j]), hi = x.cwiseMax(centres[j]);
              for (const auto& [o, t] : near) {
                const Eigen::AlignedBox3d& box = face_boxes[o][t];
                if ((box.min().array() > hi.array()).any() || (box.max().array() < lo.array()).any())
                  continue;
                const Triangle& tri = (*obstacles[o].triangles)[t];
                const Vec3Array& v = *obstacles[o].positions;
                if (segment_crosses_triangle(x, centres[j], v[tri[0]], v[tri[1]], v[tri[2]])) {
                  ++occluded;
                  return;
                }
              }
              weight += slot_amplitudes[j] * zb_kernel(q);
            });
          } else if (near.empty()) {
            // No face in reach, so no visibility test: a lambda this small is inlined into for_each_near's
            // loop, where the one below, with the segment tests, was a call per candidate (perf: the field's
            // lambda out of line, 56% of a reconstruction). Same sums in the same order: the same bits.
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
          if (weight > 0.0 && anisotropic) {
            values[n] = static_cast<float>(
                std::min<double>((kAnisotropicLevel - weight) * particle_spacing, outside));
          } else if (weight > 0.0 && density_field) {
            // The colour field is about 1 inside and 0 far outside; scaled by the spacing, its values near
            // the surface are lengths like the Zhu-Bridson field's, which the mesher's interpolation expects.
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
