/// `fluid` of a scene: rest density and spacing, the pressure solver with its settings, viscosity, CFL and
/// sorting (FluidSettings, scene_config.hpp).

#include <tuple>

#include <drench/scene/load_sections.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench::loader {

FluidSettings read_fluid(const Node& node) {
  FluidSettings fluid;
  const ObjectReader r(
      node, {"rest_density", "particle_spacing", "pressure_solver", "wcsph", "pcisph", "dfsph", "pbf",
             "viscosity", "cfl", "max_speed", "sort_interval", "substep_halvings"});
  r.read("rest_density", fluid.rest_density, kPositive);
  r.read("particle_spacing", fluid.particle_spacing, kPositive);
  r.read_choice("pressure_solver", fluid.pressure_solver, pressure_solver_names());
  r.read("cfl", fluid.cfl, Range{0.0, true, 1.0, false});
  r.read("sort_interval", fluid.sort_interval, kAtLeastOne);
  // 20 halvings are a millionth of the step: past that a failing solve is not the step's fault.
  r.read("substep_halvings", fluid.substep_halvings, Range{0.0, false, kMaxSubstepHalvings, false});
  // null is "no limit", so that --set fluid.max_speed=null can undo the default.
  if (const Node c = r["max_speed"]; c.present())
    fluid.max_speed = c.value().is_null() ? std::nullopt : std::optional<Scalar>(c.number(kPositive));

  const ObjectReader wcsph(r["wcsph"], {"speed_of_sound", "exponent", "max_compression"});
  // null is accepted as "auto" so that --set fluid.wcsph.speed_of_sound=null can undo a file's value.
  if (const Node c = wcsph["speed_of_sound"]; c.present() && !c.value().is_null())
    fluid.wcsph.speed_of_sound = c.number(Range{0.0, true, kMaxSpeedOfSound, false});
  wcsph.read("exponent", fluid.wcsph.exponent, kAtLeastOne);

  const ObjectReader pcisph(r["pcisph"],
                            {"eta", "min_iterations", "max_iterations", "max_compression_per_iteration",
                             "max_relief_per_substep", "precision"});
  pcisph.read("eta", fluid.pcisph.eta, Range{0.0, true, 1.0, true});
  pcisph.read("min_iterations", fluid.pcisph.min_iterations, kPassesPerStep);
  pcisph.read("max_iterations", fluid.pcisph.max_iterations, kPassesPerStep);
  pcisph.read_choice("precision", fluid.pcisph.precision, precision_names());
  pcisph.require_order("min_iterations", fluid.pcisph.min_iterations, "max_iterations",
                       fluid.pcisph.max_iterations);
  const ObjectReader dfsph(
      r["dfsph"], {"eta", "eta_divergence", "min_iterations", "max_iterations", "max_divergence_iterations",
                   "max_relief_per_substep", "warm_start", "precision"});
  dfsph.read("eta", fluid.dfsph.eta, Range{0.0, true, 1.0, true});
  dfsph.read("eta_divergence", fluid.dfsph.eta_divergence, kPositive);
  dfsph.read("min_iterations", fluid.dfsph.min_iterations, kPassesPerStep);
  dfsph.read("max_iterations", fluid.dfsph.max_iterations, kPassesPerStep);
  dfsph.read("max_divergence_iterations", fluid.dfsph.max_divergence_iterations, kPassesPerStep);
  dfsph.read("warm_start", fluid.dfsph.warm_start);
  dfsph.read_choice("precision", fluid.dfsph.precision, precision_names());
  dfsph.require_order("min_iterations", fluid.dfsph.min_iterations, "max_iterations",
                      fluid.dfsph.max_iterations);

  const ObjectReader pbf(r["pbf"], {"substeps", "iterations", "relaxation", "scorr_k", "scorr_n", "scorr_dq",
                                    "max_compression_per_iteration", "scorr_substep", "precision"});
  pbf.read("substeps", fluid.pbf.substeps, kPassesPerStep);
  pbf.read("iterations", fluid.pbf.iterations, kPassesPerStep);
  pbf.read("relaxation", fluid.pbf.relaxation, kNonNegative);
  pbf.read("scorr_k", fluid.pbf.scorr_k, kNonNegative);
  pbf.read("scorr_n", fluid.pbf.scorr_n, Range{1.0, false, kMaxScorrExponent, false});
  pbf.read("scorr_dq", fluid.pbf.scorr_dq, Range{0.0, true, 1.0, true});
  pbf.read_choice("precision", fluid.pbf.precision, precision_names());

  // null is "no limit" (the published WCSPH, PCISPH and DFSPH), so that --set can undo the default.
  for (auto [reader, key, limit] :
       {std::tuple{&wcsph, "max_compression", &fluid.wcsph.max_compression},
        std::tuple{&pcisph, "max_compression_per_iteration", &fluid.pcisph.max_compression_per_iteration},
        std::tuple{&pcisph, "max_relief_per_substep", &fluid.pcisph.max_relief_per_substep},
        std::tuple{&dfsph, "max_relief_per_substep", &fluid.dfsph.max_relief_per_substep},
        std::tuple{&pbf, "max_compression_per_iteration", &fluid.pbf.max_compression_per_iteration},
        std::tuple{&pbf, "scorr_substep", &fluid.pbf.scorr_substep}}) {
    if (const Node c = (*reader)[key]; c.present()) {
      if (c.value().is_null()) {
        limit->reset();
      } else {
        *limit = c.number(kPositive);
      }
    }
  }

  const ObjectReader viscosity(r["viscosity"], {"method", "coefficient"});
  viscosity.read_choice("method", fluid.viscosity.method, viscosity_names());
  viscosity.read("coefficient", fluid.viscosity.coefficient, kNonNegative);
  return fluid;
}

}  // namespace drench::loader
