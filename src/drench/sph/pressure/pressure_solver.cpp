#include <drench/sph/pressure/pressure_solver.hpp>

#include <algorithm>
#include <limits>
#include <utility>

#include <drench/common/parallel.hpp>
#include <drench/sph/pressure/pressure_dfsph.hpp>
#include <drench/sph/pressure/pressure_pbf.hpp>
#include <drench/sph/pressure/pressure_pcisph.hpp>
#include <drench/sph/pressure/pressure_wcsph.hpp>

namespace drench {

namespace {
/// The axis-aligned bounding box of the finite points among `points` (unit: m); lo > hi on every axis when
/// there is none. Non-finite points are left out: one particle at infinity (the solver names it after the
/// sub-step) would otherwise put every other particle's float record at NaN. Min and max are exact, so any
/// thread count gives the same bits.
void finite_bounding_box(const Vec3Array& points, Vec3& lo, Vec3& hi) {
  constexpr Scalar kInf = std::numeric_limits<Scalar>::infinity();
  using Box = std::pair<Vec3, Vec3>;
  const Box empty(Vec3::Constant(kInf), Vec3::Constant(-kInf));
  const Box box = parallel_reduce(
      points.size(), kLightChunk, empty,
      [&](std::size_t begin, std::size_t end) {
        Box b = empty;
        for (std::size_t i = begin; i < end; ++i) {
          const Vec3& x = points[i];
          if (!x.allFinite()) continue;
          b.first = b.first.cwiseMin(x);
          b.second = b.second.cwiseMax(x);
        }
        return b;
      },
      [](const Box& a, const Box& b) { return Box(a.first.cwiseMin(b.first), a.second.cwiseMax(b.second)); });
  lo = box.first;
  hi = box.second;
}

/// Single precision rounds a coordinate by up to 2^-24 of its distance from the fluid's centre; beyond this
/// many spacings from it (1e-4 x 2^24, about 1,680) the rounding would exceed 1e-4 of a spacing, and the
/// solve takes double precision instead (a particle flung far from the fluid without a kill region).
constexpr Scalar kSingleReachInSpacings = 1e-4 * 0x1p24;
}  // namespace

std::unique_ptr<PressureSolver> make_pressure_solver(const FluidSettings& settings, Scalar speed_of_sound) {
  switch (settings.pressure_solver) {
    case PressureSolverKind::WCSPH:
      return std::make_unique<PressureWcsph>(settings, speed_of_sound);
    case PressureSolverKind::PCISPH:
      return std::make_unique<PressurePcisph>(settings);
    case PressureSolverKind::DFSPH:
      return std::make_unique<PressureDfsph>(settings);
    case PressureSolverKind::PBF:
      return std::make_unique<PressurePbf>(settings);
  }
  return nullptr;
}

void density_error_stats(const ScalarArray& densities, Scalar rest_density, PressureStats& stats) {
  Scalar sum = 0.0;
  Scalar max = 0.0;
  for (const Scalar rho : densities) {
    const Scalar err = std::max(rho - rest_density, 0.0);
    sum += err;
    max = std::max(max, err);
  }
  stats.average_density_error = densities.empty() ? 0.0 : sum / (densities.size() * rest_density);
  stats.max_density_error = max / rest_density;
}

bool single_precision_origin(const FluidContext& ctx, IterationPrecision precision, Vec3& origin,
                             bool needs_uniform_mass) {
  origin = Vec3::Zero();
  const bool wanted =
      precision == IterationPrecision::SINGLE && (ctx.uniform_mass > 0.0 || !needs_uniform_mass);
  if (!wanted || ctx.particles.empty()) return false;
  Vec3 lo, hi;
  finite_bounding_box(ctx.particles.positions, lo, hi);
  if (lo.x() > hi.x()) return true;  // no finite particle: the sub-step names the first one
  origin = 0.5 * (lo + hi);
  return 0.5 * (hi - lo).maxCoeff() <= kSingleReachInSpacings * ctx.particle_spacing;
}

}  // namespace drench
