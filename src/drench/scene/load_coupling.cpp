/// `coupling` of a scene: how fluid and cloth act on each other (CouplingSettings,
/// coupling/coupling_settings.hpp).

#include <drench/scene/load_sections.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench::loader {

CouplingSettings read_coupling(const Node& node) {
  CouplingSettings coupling;
  const ObjectReader r(
      node, {"cloth_thickness", "repulsion_stiffness", "repulsion_sweeps", "continuous", "substep_obstacle",
             "scheme", "max_ccd_iterations", "slip", "friction_coefficient", "broad_phase"});
  r.read("cloth_thickness", coupling.cloth_thickness, kPositive);
  r.read("repulsion_stiffness", coupling.repulsion_stiffness, kNonNegative);
  r.read("repulsion_sweeps", coupling.repulsion_sweeps, kPassesPerStep);
  r.read("continuous", coupling.continuous);
  r.read("substep_obstacle", coupling.substep_obstacle);
  r.read_choice("scheme", coupling.scheme, coupling_scheme_names());
  r.read("max_ccd_iterations", coupling.max_ccd_iterations, kPassesPerStep);
  r.read_choice("slip", coupling.slip, slip_names());
  r.read("friction_coefficient", coupling.friction_coefficient, kNonNegative);
  r.read_choice("broad_phase", coupling.broad_phase, broad_phase_names());
  return coupling;
}

}  // namespace drench::loader
