#pragma once
/// The names a scene file writes for each enum of the settings, in the order error messages list them: one
/// table for the loader (load_*.cpp) and the writer (scene_document.cpp), so that the two cannot disagree.

#include <string>

#include <drench/scene/json_reader.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench::loader {

/// `fluid.pressure_solver`.
inline const Choices<PressureSolverKind>& pressure_solver_names() {
  static const Choices<PressureSolverKind> names = {{"pcisph", PressureSolverKind::PCISPH},
                                                    {"wcsph", PressureSolverKind::WCSPH},
                                                    {"dfsph", PressureSolverKind::DFSPH},
                                                    {"pbf", PressureSolverKind::PBF}};
  return names;
}
/// `fluid.pcisph.precision`, `fluid.dfsph.precision`, `fluid.pbf.precision`.
inline const Choices<IterationPrecision>& precision_names() {
  static const Choices<IterationPrecision> names = {{"single", IterationPrecision::SINGLE},
                                                    {"double", IterationPrecision::DOUBLE}};
  return names;
}
/// `fluid.viscosity.method`.
inline const Choices<ViscosityKind>& viscosity_names() {
  static const Choices<ViscosityKind> names = {{"xsph", ViscosityKind::XSPH},
                                               {"artificial", ViscosityKind::ARTIFICIAL}};
  return names;
}
/// `coupling.scheme`.
inline const Choices<CouplingScheme>& coupling_scheme_names() {
  static const Choices<CouplingScheme> names = {{"carried_water", CouplingScheme::CARRIED_WATER},
                                                {"impulses", CouplingScheme::IMPULSES}};
  return names;
}
/// `coupling.slip`.
inline const Choices<SlipCondition>& slip_names() {
  static const Choices<SlipCondition> names = {{"friction", SlipCondition::FRICTION},
                                               {"no_slip", SlipCondition::NO_SLIP}};
  return names;
}
/// `coupling.broad_phase`.
inline const Choices<BroadPhaseKind>& broad_phase_names() {
  static const Choices<BroadPhaseKind> names = {{"grid", BroadPhaseKind::GRID}, {"fcl", BroadPhaseKind::FCL}};
  return names;
}
/// `surface.kernel`.
inline const Choices<SurfaceKernel>& surface_kernel_names() {
  static const Choices<SurfaceKernel> names = {{"isotropic", SurfaceKernel::ISOTROPIC},
                                               {"anisotropic", SurfaceKernel::ANISOTROPIC}};
  return names;
}
/// `surface.field`.
inline const Choices<SurfaceField>& surface_field_names() {
  static const Choices<SurfaceField> names = {{"zhu_bridson", SurfaceField::ZHU_BRIDSON},
                                              {"density", SurfaceField::DENSITY}};
  return names;
}
/// `surface_tension.model`.
inline const Choices<SurfaceTensionModel>& surface_tension_model_names() {
  static const Choices<SurfaceTensionModel> names = {{"csf", SurfaceTensionModel::CSF},
                                                     {"akinci", SurfaceTensionModel::AKINCI}};
  return names;
}
/// `emitters[i].type`.
inline const Choices<EmitterSettings::Kind>& emitter_type_names() {
  static const Choices<EmitterSettings::Kind> names = {{"nozzle", EmitterSettings::Kind::NOZZLE},
                                                       {"box", EmitterSettings::Kind::BOX}};
  return names;
}
/// `boundaries[i].type`.
inline const Choices<BoundarySettings::Kind>& boundary_type_names() {
  static const Choices<BoundarySettings::Kind> names = {{"box", BoundarySettings::Kind::BOX},
                                                        {"plane", BoundarySettings::Kind::PLANE}};
  return names;
}
/// `kill_regions[i].type`.
inline const Choices<KillRegionSettings::Kind>& kill_region_type_names() {
  static const Choices<KillRegionSettings::Kind> names = {{"plane", KillRegionSettings::Kind::PLANE},
                                                          {"box", KillRegionSettings::Kind::BOX}};
  return names;
}

/// The name `value` has in `names`.
template <class Enum>
const std::string& name_of(const Choices<Enum>& names, Enum value) {
  for (const auto& [name, v] : names)
    if (v == value) return name;
  return names.front().first;  // unreachable for a value of the enum: every table lists them all
}

}  // namespace drench::loader
