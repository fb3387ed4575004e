#include <drench/sph/pressure/pressure_solver.hpp>

#include <algorithm>

#include <drench/sph/pressure/pressure_dfsph.hpp>
#include <drench/sph/pressure/pressure_pcisph.hpp>
#include <drench/sph/pressure/pressure_wcsph.hpp>

namespace drench {

std::unique_ptr<PressureSolver> make_pressure_solver(const FluidSettings& settings, Scalar speed_of_sound) {
  switch (settings.pressure_solver) {
    case PressureSolverKind::WCSPH:
      return std::make_unique<PressureWcsph>(settings, speed_of_sound);
    case PressureSolverKind::PCISPH:
      return std::make_unique<PressurePcisph>(settings);
    case PressureSolverKind::DFSPH:
      return std::make_unique<PressureDfsph>(settings);
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

}  // namespace drench
