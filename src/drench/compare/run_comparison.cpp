#include <drench/compare/run_comparison.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include <drench/common/error.hpp>
#include <drench/io/ply_reader.hpp>

namespace drench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A cell of the mass grid by its integer coordinates, packed for the hash map.
struct CellKey {
  std::int64_t i, j, k;
  bool operator==(const CellKey& o) const { return i == o.i && j == o.j && k == o.k; }
};
struct CellHash {
  std::size_t operator()(const CellKey& c) const {
    std::uint64_t h = static_cast<std::uint64_t>(c.i) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(c.j) + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(c.k) + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};
using MassGrid = std::unordered_map<CellKey, double, CellHash>;

MassGrid mass_grid(const Vec3Array& positions, Scalar particle_mass, Scalar cell) {
  MassGrid grid;
  for (const Vec3& p : positions) {
    const CellKey key{static_cast<std::int64_t>(std::floor(p.x() / cell)),
                      static_cast<std::int64_t>(std::floor(p.y() / cell)),
                      static_cast<std::int64_t>(std::floor(p.z() / cell))};
    grid[key] += particle_mass;
  }
  return grid;
}

double l1_difference(const MassGrid& a, const MassGrid& b) {
  double sum = 0;
  for (const auto& [key, mass] : a) {
    const auto other = b.find(key);
    sum += std::abs(mass - (other == b.end() ? 0.0 : other->second));
  }
  for (const auto& [key, mass] : b)
    if (!a.count(key)) sum += mass;
  return sum;
}

/// The cloth seen from above (along -y): its triangles binned by their x-z bounds, so that the surface
/// under a particle is found among a few triangles.
class ClothFromAbove {
 public:
  ClothFromAbove(const Vec3Array& nodes, const std::vector<Triangle>& triangles)
      : m_nodes(nodes), m_triangles(triangles) {
    if (triangles.empty()) return;
    m_min_x = m_min_z = std::numeric_limits<double>::infinity();
    double max_x = -m_min_x, max_z = -m_min_z, extent = 0;
    for (const Triangle& t : triangles) {
      double lo_x = INFINITY, hi_x = -INFINITY, lo_z = INFINITY, hi_z = -INFINITY;
      for (const Index n : t) {
        lo_x = std::min(lo_x, nodes[n].x());
        hi_x = std::max(hi_x, nodes[n].x());
        lo_z = std::min(lo_z, nodes[n].z());
        hi_z = std::max(hi_z, nodes[n].z());
      }
      extent += std::max(hi_x - lo_x, hi_z - lo_z);
      m_min_x = std::min(m_min_x, lo_x);
      m_min_z = std::min(m_min_z, lo_z);
      max_x = std::max(max_x, hi_x);
      max_z = std::max(max_z, hi_z);
    }
    // Cells of about a triangle's size: a few triangles per cell.
    m_cell = std::max(extent / static_cast<double>(triangles.size()), 1e-9);
    m_nx = std::max<std::int64_t>(1, static_cast<std::int64_t>((max_x - m_min_x) / m_cell) + 1);
    m_nz = std::max<std::int64_t>(1, static_cast<std::int64_t>((max_z - m_min_z) / m_cell) + 1);
    // A cloth blown far apart (a blow-up) would make a huge grid: cap it, coarser cells cost only time.
    while (m_nx * m_nz > 4'000'000) {
      m_cell *= 2;
      m_nx = m_nx / 2 + 1;
      m_nz = m_nz / 2 + 1;
    }
    m_bins.assign(static_cast<std::size_t>(m_nx * m_nz), {});
    for (Index f = 0; f < triangles.size(); ++f) {
      double lo_x = INFINITY, hi_x = -INFINITY, lo_z = INFINITY, hi_z = -INFINITY;
      for (const Index n : triangles[f]) {
        lo_x = std::min(lo_x, nodes[n].x());
        hi_x = std::max(hi_x, nodes[n].x());
        lo_z = std::min(lo_z, nodes[n].z());
        hi_z = std::max(hi_z, nodes[n].z());
      }
      for (std::int64_t i = bin_x(lo_x); i <= bin_x(hi_x); ++i)
        for (std::int64_t k = bin_z(lo_z); k <= bin_z(hi_z); ++k)
          m_bins[static_cast<std::size_t>(i * m_nz + k)].push_back(f);
    }
  }

  /// The height of the highest cloth surface at or below `p` along y, NaN when no triangle lies under it.
  double surface_below(const Vec3& p) const {
    if (m_bins.empty()) return kNaN;
    const double fx = (p.x() - m_min_x) / m_cell, fz = (p.z() - m_min_z) / m_cell;
    if (fx < 0 || fz < 0 || fx >= static_cast<double>(m_nx) || fz >= static_cast<double>(m_nz)) return kNaN;
    double best = kNaN;
    for (const Index f : m_bins[static_cast<std::size_t>(bin_x(p.x()) * m_nz + bin_z(p.z()))]) {
      const Vec3& a = m_nodes[m_triangles[f][0]];
      const Vec3& b = m_nodes[m_triangles[f][1]];
      const Vec3& c = m_nodes[m_triangles[f][2]];
      // Barycentric coordinates in the x-z plane.
      const double d = (b.z() - c.z()) * (a.x() - c.x()) + (c.x() - b.x()) * (a.z() - c.z());
      if (std::abs(d) < 1e-30) continue;  // a triangle seen edge-on from above covers no area
      const double u = ((b.z() - c.z()) * (p.x() - c.x()) + (c.x() - b.x()) * (p.z() - c.z())) / d;
      const double v = ((c.z() - a.z()) * (p.x() - c.x()) + (a.x() - c.x()) * (p.z() - c.z())) / d;
      const double w = 1 - u - v;
      if (u < 0 || v < 0 || w < 0) continue;
      const double y = u * a.y() + v * b.y() + w * c.y();
      if (y <= p.y() && !(y <= best)) best = y;
    }
    return best;
  }

 private:
  std::int64_t bin_x(double x) const {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>((x - m_min_x) / m_cell), 0, m_nx - 1);
  }
  std::int64_t bin_z(double z) const {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>((z - m_min_z) / m_cell), 0, m_nz - 1);
  }

  const Vec3Array& m_nodes;
  const std::vector<Triangle>& m_triangles;
  double m_min_x = 0, m_min_z = 0, m_cell = 1;
  std::int64_t m_nx = 0, m_nz = 0;
  std::vector<std::vector<Index>> m_bins;
};

/// One frame of one run, read.
struct Frame {
  PlyData fluid;
  PlyData cloth;  ///< empty without a cloth
};

Frame read_frame(const RunFrames& run, std::size_t n) {
  Frame frame;
  frame.fluid = read_ply(run.fluid_files[n]);
  if (!run.cloth_files.empty()) {
    frame.cloth = read_ply(run.cloth_files[n]);
    if (frame.cloth.triangles.empty())
      throw IoError(run.cloth_files[n] + ": a cloth frame without triangles");
  }
  return frame;
}

/// The series of one frame that do not need the other run.
struct FrameSeries {
  double centre_y = kNaN, held = kNaN, past_edges = kNaN, fluid = 0, killed = 0, front = kNaN;
  std::vector<double> gauges;
};

FrameSeries frame_series(const Frame& frame, std::size_t frame_index, const RunFrames& run,
                         const ComparisonSettings& settings, std::size_t centre_node, double gauge_width,
                         double gauge_depth) {
  FrameSeries s;
  const Vec3Array& particles = frame.fluid.positions;
  s.fluid = static_cast<double>(particles.size()) * run.particle_mass;
  s.killed = run.killed_kg.empty() ? 0.0 : run.killed_kg[frame_index];
  if (!frame.cloth.positions.empty()) {
    const Vec3Array& nodes = frame.cloth.positions;
    s.centre_y = nodes[centre_node].y();
    double lowest = INFINITY;
    for (const Vec3& n : nodes)
      lowest = std::min(lowest, n.y());
    const ClothFromAbove above(nodes, frame.cloth.triangles);
    std::size_t held = 0, past = 0;
    for (const Vec3& p : particles) {
      if (p.y() < lowest) {
        ++past;
        continue;
      }
      const double y = above.surface_below(p);
      if (std::isfinite(y) && p.y() - y <= settings.held_band) ++held;
    }
    s.held = static_cast<double>(held) * run.particle_mass;
    // Water a kill region removed left the scene, below the cloth in every scene drench has.
    s.past_edges = static_cast<double>(past) * run.particle_mass + s.killed;
  } else {
    for (const Vec3& p : particles)
      s.front = std::isfinite(s.front) ? std::max(s.front, p.x()) : p.x();
  }
  // Each particle stands for its rest volume, spacing^3 (m_j / rho0): a splash's droplet adds one of them.
  const double particle_volume = std::pow(run.particle_spacing, 3);
  for (const Scalar x : settings.gauges_x) {
    std::size_t count = 0;
    for (const Vec3& p : particles)
      if (std::abs(p.x() - x) <= 0.5 * gauge_width) ++count;
    s.gauges.push_back(static_cast<double>(count) * particle_volume / (gauge_width * gauge_depth));
  }
  return s;
}

}  // namespace

const std::vector<std::string>& observable_names() {
  static const std::vector<std::string> names = {"cloth_rms_m", "cloth_max_m",   "cloth_sag_m",
                                                 "held_kg",     "past_edges_kg", "mass_l1_kg",
                                                 "front_m",     "gauge_height_m"};
  return names;
}

std::vector<std::string> reported_observables(bool cloth, bool gauges) {
  std::vector<std::string> names;
  for (const std::string& name : observable_names()) {
    const bool of_cloth = name.rfind("cloth_", 0) == 0 || name == "held_kg" || name == "past_edges_kg";
    if (name == "gauge_height_m" ? gauges : name == "front_m" ? !cloth : !of_cloth || cloth)
      names.push_back(name);
  }
  return names;
}

void check_comparison_settings(const ComparisonSettings& settings, const RunFrames& reference) {
  const auto fail = [](const std::string& setting, const std::string& option, const std::string& range,
                       double value) {
    return SceneError("comparison " + setting + (option.empty() ? "" : " (drench sweep " + option + ")") +
                      " must be " + range + ", got " + format_number(value));
  };
  const std::string up_to = format_number(kMaxCoordinate) + "] m";
  const double spacing = reference.particle_spacing;
  if (!(settings.cell_size == 0 || (settings.cell_size >= spacing && settings.cell_size <= kMaxCoordinate))) {
    throw fail("cell_size", "--cell-size",
               "0 (four particle spacings) or in [" + format_number(spacing) +
                   " (the reference's particle "
                   "spacing: a smaller cell holds at most one particle), " +
                   up_to,
               settings.cell_size);
  }
  if (!(settings.held_band > 0 && settings.held_band <= kMaxCoordinate))
    throw fail("held_band", "", "in (0, " + up_to, settings.held_band);
  if (!(settings.gauge_width >= 0 && settings.gauge_width <= kMaxCoordinate))
    throw fail("gauge_width", "--gauge-width", "in (0, " + up_to, settings.gauge_width);
  if (!(settings.gauge_depth >= 0 && settings.gauge_depth <= kMaxCoordinate))
    throw fail("gauge_depth", "--gauge-depth", "in (0, " + up_to, settings.gauge_depth);
  for (const Scalar x : settings.gauges_x)
    if (!(std::abs(x) <= kMaxCoordinate))
      throw fail("gauge x", "--gauge", "in [-" + format_number(kMaxCoordinate) + ", " + up_to, x);
  if (!(settings.time_tolerance >= 0 && settings.time_tolerance <= 1))
    throw fail("time_tolerance", "", "in [0, 1] s", settings.time_tolerance);
}

RunComparison compare_runs(const RunFrames& run, const RunFrames& reference,
                           const ComparisonSettings& settings) {
  check_comparison_settings(settings, reference);
  const std::size_t run_frames = run.fluid_files.size(), reference_frames = reference.fluid_files.size();
  if (reference_frames == 0)
    throw IoError(reference.dir + ": the reference has no frames (frames/fluid_0000.ply)");
  if (run_frames > reference_frames || (run_frames < reference_frames && !settings.allow_shorter)) {
    throw IoError(run.dir + ": " + std::to_string(run_frames) + " frames, the reference " + reference.dir +
                  " has " + std::to_string(reference_frames) +
                  ": the two runs must have the same time.duration and time.frame_rate");
  }
  if (run.cloth_files.empty() != reference.cloth_files.empty()) {
    throw IoError((run.cloth_files.empty() ? run.dir : reference.dir) + ": no cloth frames, the other run (" +
                  (run.cloth_files.empty() ? reference.dir : run.dir) + ") has a cloth");
  }
  for (const RunFrames* r : {&run, &reference}) {
    if (!r->killed_kg.empty() && r->killed_kg.size() != r->fluid_files.size()) {
      throw IoError(r->dir + ": the killed water is recorded for " + std::to_string(r->killed_kg.size()) +
                    " frames, the run has " + std::to_string(r->fluid_files.size()));
    }
  }
  const std::size_t frames = run_frames;
  for (std::size_t n = 0; n < frames; ++n) {
    const double a = n < run.times.size() ? run.times[n] : kNaN;
    const double b = n < reference.times.size() ? reference.times[n] : kNaN;
    if (!(std::abs(a - b) <= settings.time_tolerance)) {
      throw IoError(run.fluid_files[n] + ": frame " + std::to_string(n) + " is at t = " + format_number(a) +
                    " s, the reference's at " + format_number(b) +
                    " s: choose time.frame_rate so that every frame's time is a whole number of both runs' "
                    "time.dt (e.g. 50 frames/s for dt 1, 2, 4 ms)");
    }
  }
  const bool cloth = !run.cloth_files.empty();
  const double gauge_width = settings.gauge_width > 0 ? settings.gauge_width : reference.particle_spacing;
  const double cell = settings.cell_size > 0 ? settings.cell_size : 4 * reference.particle_spacing;

  // The reference's frame 0 fixes the centre node and the gauges' depth, for both runs.
  const Frame reference_first = read_frame(reference, 0);
  std::size_t centre_node = 0;
  if (cloth) {
    const Vec3Array& nodes = reference_first.cloth.positions;
    Vec3 mean = Vec3::Zero();
    for (const Vec3& n : nodes)
      mean += n;
    mean /= static_cast<double>(nodes.size());
    double best = INFINITY;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if ((nodes[i] - mean).squaredNorm() < best) {
        best = (nodes[i] - mean).squaredNorm();
        centre_node = i;
      }
    }
  }
  double gauge_depth = settings.gauge_depth;
  if (!(gauge_depth > 0)) {
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : reference_first.fluid.positions) {
      lo = std::min(lo, p.z());
      hi = std::max(hi, p.z());
    }
    gauge_depth = (std::isfinite(lo) ? hi - lo : 0.0) + reference.particle_spacing;
  }

  const std::vector<std::string>& names = observable_names();
  std::vector<std::vector<double>> diff(names.size());
  // Every frame of the reference, so that the normalisers are the whole reference's even when a run that
  // stopped has fewer frames.
  std::vector<FrameSeries> run_s, ref_s;
  for (std::size_t n = 0; n < reference_frames; ++n) {
    const Frame b = n == 0 ? reference_first : read_frame(reference, n);
    ref_s.push_back(frame_series(b, n, reference, settings, centre_node, gauge_width, gauge_depth));
    if (n >= frames) continue;
    const Frame a = read_frame(run, n);
    if (cloth) {
      const Vec3Array& pa = a.cloth.positions;
      const Vec3Array& pb = b.cloth.positions;
      if (pa.size() != pb.size() || centre_node >= pa.size()) {
        throw IoError(run.cloth_files[n] + ": " + std::to_string(pa.size()) +
                      " cloth nodes, the reference's " + reference.cloth_files[n] + " has " +
                      std::to_string(pb.size()) + ": the two runs must have the same cloth mesh");
      }
      double sum = 0, largest = 0;
      for (std::size_t i = 0; i < pa.size(); ++i) {
        const double d2 = (pa[i] - pb[i]).squaredNorm();
        sum += d2;
        largest = std::max(largest, d2);
      }
      diff[0].push_back(std::sqrt(sum / static_cast<double>(pa.size())));
      diff[1].push_back(std::sqrt(largest));
    }
    run_s.push_back(frame_series(a, n, run, settings, centre_node, gauge_width, gauge_depth));
    // The killed water as one more cell, outside the scene.
    diff[5].push_back(l1_difference(mass_grid(a.fluid.positions, run.particle_mass, cell),
                                    mass_grid(b.fluid.positions, reference.particle_mass, cell)) +
                      std::abs(run_s.back().killed - ref_s.back().killed));
  }

  for (std::size_t n = 0; n < frames; ++n) {
    const FrameSeries& r = ref_s[n];
    const FrameSeries& s = run_s[n];
    if (cloth) {
      const double sag_run = run_s[0].centre_y - s.centre_y, sag_ref = ref_s[0].centre_y - r.centre_y;
      diff[2].push_back(std::abs(sag_run - sag_ref));
      diff[3].push_back(std::abs(s.held - r.held));
      diff[4].push_back(std::abs(s.past_edges - r.past_edges));
    } else {
      // A frame with no particle has no front: equal when neither run has one, else not comparable.
      const bool both = std::isfinite(s.front) && std::isfinite(r.front);
      const bool neither = !std::isfinite(s.front) && !std::isfinite(r.front);
      diff[6].push_back(both ? std::abs(s.front - r.front) : neither ? 0.0 : kNaN);
    }
    if (!settings.gauges_x.empty()) {
      double worst = 0;
      for (std::size_t g = 0; g < settings.gauges_x.size(); ++g)
        worst = std::max(worst, std::abs(s.gauges[g] - r.gauges[g]));
      diff[7].push_back(worst);
    }
  }
  // The normalisers, from the whole reference.
  double largest_sag = 0, largest_mass = 0, largest_gauge = 0;
  for (const FrameSeries& r : ref_s) {
    if (cloth) largest_sag = std::max(largest_sag, std::abs(ref_s[0].centre_y - r.centre_y));
    largest_mass = std::max(largest_mass, r.fluid + r.killed);
    for (const double h : r.gauges)
      largest_gauge = std::max(largest_gauge, h);
  }
  const double travel = cloth ? kNaN : ref_s.back().front - ref_s[0].front;
  const double normalisers[] = {largest_sag,  largest_sag,  largest_sag, largest_mass,
                                largest_mass, largest_mass, travel,      largest_gauge};

  RunComparison result;
  result.frames = frames;
  result.worst_relative = kNaN;
  for (std::size_t o = 0; o < names.size(); ++o) {
    if (diff[o].empty()) continue;
    ObservableError e;
    e.name = names[o];
    e.per_frame = diff[o];
    e.largest = 0;
    for (const double d : diff[o])
      e.largest = std::isfinite(d) && std::isfinite(e.largest) ? std::max(e.largest, d) : kNaN;
    e.normaliser = normalisers[o] > 0 ? normalisers[o] : kNaN;
    e.relative = e.largest / e.normaliser;
    if (std::isfinite(e.relative) && !(e.relative <= result.worst_relative)) {
      result.worst_relative = e.relative;
      result.worst = e.name;
    }
    result.observables.push_back(std::move(e));
  }
  result.series_names = {"centre_sag_m", "held_kg", "past_edges_kg", "fluid_kg", "killed_kg", "front_m"};
  for (auto [series, source] :
       {std::pair{&result.run_series, &run_s}, std::pair{&result.reference_series, &ref_s}}) {
    series->assign(result.series_names.size(), {});
    for (const FrameSeries& s : *source) {
      (*series)[0].push_back(cloth ? (*source)[0].centre_y - s.centre_y : kNaN);
      (*series)[1].push_back(s.held);
      (*series)[2].push_back(s.past_edges);
      (*series)[3].push_back(s.fluid);
      (*series)[4].push_back(s.killed);
      (*series)[5].push_back(s.front);
    }
  }
  return result;
}

}  // namespace drench
