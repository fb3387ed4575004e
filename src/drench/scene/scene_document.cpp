/// The loader's inverse: each section written with the keys its load_*.cpp reads, the enums by the names of
/// scene_names.hpp.

#include <drench/scene/scene_document.hpp>

#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench {
namespace {

using loader::name_of;
using nlohmann::json;

json vec3(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

/// An optional limit: null is "none", as the loader reads it.
template <class T>
json limit(const std::optional<T>& value) {
  return value ? json(*value) : json(nullptr);
}

json fluid_document(const FluidSettings& f) {
  json viscosity = {{"method", name_of(loader::viscosity_names(), f.viscosity.method)},
                    {"coefficient", f.viscosity.coefficient}};
  json wcsph = {{"speed_of_sound", limit(f.wcsph.speed_of_sound)},
                {"exponent", f.wcsph.exponent},
                {"max_compression", limit(f.wcsph.max_compression)}};
  json pcisph = {{"eta", f.pcisph.eta},
                 {"min_iterations", f.pcisph.min_iterations},
                 {"max_iterations", f.pcisph.max_iterations},
                 {"max_compression_per_iteration", limit(f.pcisph.max_compression_per_iteration)},
                 {"max_relief_per_substep", limit(f.pcisph.max_relief_per_substep)},
                 {"precision", name_of(loader::precision_names(), f.pcisph.precision)}};
  json dfsph = {{"eta", f.dfsph.eta},
                {"eta_divergence", f.dfsph.eta_divergence},
                {"min_iterations", f.dfsph.min_iterations},
                {"max_iterations", f.dfsph.max_iterations},
                {"max_divergence_iterations", f.dfsph.max_divergence_iterations},
                {"max_relief_per_substep", limit(f.dfsph.max_relief_per_substep)},
                {"warm_start", f.dfsph.warm_start},
                {"precision", name_of(loader::precision_names(), f.dfsph.precision)}};
  json pbf = {{"substeps", f.pbf.substeps},
              {"iterations", f.pbf.iterations},
              {"relaxation", f.pbf.relaxation},
              {"scorr_k", f.pbf.scorr_k},
              {"scorr_n", f.pbf.scorr_n},
              {"scorr_dq", f.pbf.scorr_dq},
              {"max_compression_per_iteration", limit(f.pbf.max_compression_per_iteration)},
              {"scorr_substep", limit(f.pbf.scorr_substep)},
              {"precision", name_of(loader::precision_names(), f.pbf.precision)}};
  return {{"rest_density", f.rest_density},
          {"particle_spacing", f.particle_spacing},
          {"pressure_solver", name_of(loader::pressure_solver_names(), f.pressure_solver)},
          {"wcsph", wcsph},
          {"pcisph", pcisph},
          {"dfsph", dfsph},
          {"pbf", pbf},
          {"viscosity", viscosity},
          {"cfl", f.cfl},
          {"max_speed", limit(f.max_speed)},
          {"sort_interval", f.sort_interval},
          {"substep_halvings", f.substep_halvings}};
}

json emitter_document(const EmitterSettings& e) {
  json out = {{"type", name_of(loader::emitter_type_names(), e.kind)}};
  if (e.kind == EmitterSettings::Kind::NOZZLE) {
    const NozzleEmitterSettings& n = e.nozzle;
    out.update({{"center", vec3(n.center)},
                {"direction", vec3(n.direction)},
                {"radius", n.radius},
                {"speed", n.speed},
                {"start_time", n.start_time},
                {"max_particles", n.max_particles}});
  } else {
    out.update({{"min", vec3(e.box.min)}, {"max", vec3(e.box.max)}, {"velocity", vec3(e.box.velocity)}});
  }
  return out;
}

json boundary_document(const BoundarySettings& b) {
  json out = {{"type", name_of(loader::boundary_type_names(), b.kind)}, {"layers", b.layers}};
  if (b.kind == BoundarySettings::Kind::BOX) {
    out.update({{"min", vec3(b.min)}, {"max", vec3(b.max)}, {"open_top", b.open_top}});
  } else {
    out.update({{"point", vec3(b.point)}, {"normal", vec3(b.normal)}, {"size", {b.size[0], b.size[1]}}});
  }
  return out;
}

json kill_region_document(const KillRegionSettings& k) {
  json out = {{"type", name_of(loader::kill_region_type_names(), k.kind)}};
  if (k.kind == KillRegionSettings::Kind::PLANE) {
    out.update({{"point", vec3(k.point)}, {"normal", vec3(k.normal)}});
  } else {
    out.update({{"min", vec3(k.min)}, {"max", vec3(k.max)}});
  }
  return out;
}

json cloth_document(const ClothSettings& c, bool adhesion) {
  json out = {{"mesh", c.mesh},
              {"center", vec3(c.center)},
              {"size", {c.size_x, c.size_z}},
              {"nodes", {c.nodes_x, c.nodes_z}},
              {"area_density", c.area_density},
              {"pinned", c.pinned},
              {"position_iterations", c.position_iterations},
              {"substeps", c.substeps},
              {"stretch_stiffness", c.stretch_stiffness},
              {"bending_stiffness", c.bending_stiffness},
              {"damping", c.damping},
              {"max_speed", limit(c.max_speed)},
              {"max_strain", limit(c.max_strain)}};
  if (adhesion) out["adhesion"] = c.adhesion;
  return out;
}

json obstacle_document(const ObstacleSettings& o, bool adhesion) {
  json out = {{"mesh", o.mesh}, {"center", vec3(o.center)}};
  if (o.mesh == "v_plane") {
    out.update({{"angle_deg", o.angle_deg},
                {"size", o.size},
                {"width", o.width},
                {"triangle_size", o.triangle_size}});
  } else {
    out["scale"] = o.scale;
  }
  if (adhesion) out["adhesion"] = o.adhesion;
  return out;
}

json coupling_document(const CouplingSettings& c) {
  return {{"cloth_thickness", c.cloth_thickness},
          {"repulsion_stiffness", c.repulsion_stiffness},
          {"repulsion_sweeps", c.repulsion_sweeps},
          {"continuous", c.continuous},
          {"substep_obstacle", c.substep_obstacle},
          {"scheme", name_of(loader::coupling_scheme_names(), c.scheme)},
          {"max_ccd_iterations", c.max_ccd_iterations},
          {"slip", name_of(loader::slip_names(), c.slip)},
          {"friction_coefficient", c.friction_coefficient},
          {"broad_phase", name_of(loader::broad_phase_names(), c.broad_phase)}};
}

json surface_document(const SurfaceSettings& s) {
  json out = {{"field", name_of(loader::surface_field_names(), s.field)},
              {"kernel", name_of(loader::surface_kernel_names(), s.kernel)},
              {"contact_aware", s.contact_aware},
              {"smoothing", s.smoothing},
              {"max_anisotropy", s.max_anisotropy},
              {"anisotropy_scale", s.anisotropy_scale},
              {"isolated_scale", s.isolated_scale},
              {"min_neighbours", s.min_neighbours}};
  // 0 and a negative offset are "automatic" (half the spacing, half a cell), which a file says by omission.
  if (s.cell_size != 0.0) out["cell_size"] = s.cell_size;
  if (!(s.contact_offset < 0.0)) out["contact_offset"] = s.contact_offset;
  return out;
}

}  // namespace

json scene_document(const SceneConfig& config) {
  json document = {{"gravity", vec3(config.gravity)},
                   {"fluid", fluid_document(config.fluid)},
                   {"emitters", json::array()},
                   {"boundaries", json::array()},
                   {"kill_regions", json::array()},
                   {"time",
                    {{"dt", config.time.dt},
                     {"duration", config.time.duration},
                     {"frame_rate", config.time.frame_rate},
                     {"adaptive", config.time.adaptive},
                     {"dt_min", config.time.dt_min}}},
                   {"obstacles", json::array()},
                   {"coupling", coupling_document(config.coupling)},
                   {"effects", config.effects}};
  for (const EmitterSettings& e : config.emitters)
    document["emitters"].push_back(emitter_document(e));
  for (const BoundarySettings& b : config.boundaries)
    document["boundaries"].push_back(boundary_document(b));
  for (const KillRegionSettings& k : config.kill_regions)
    document["kill_regions"].push_back(kill_region_document(k));
  const bool adhesion = config.has_effect("adhesion");
  if (config.cloth) document["cloth"] = cloth_document(*config.cloth, adhesion);
  for (const ObstacleSettings& o : config.obstacles)
    document["obstacles"].push_back(obstacle_document(o, adhesion));
  if (config.has_effect("surface")) document["surface"] = surface_document(config.surface);
  if (config.has_effect("wetting")) {
    const WettingSettings& w = config.wetting;
    document["wetting"] = {{"max_saturation", w.max_saturation},
                           {"absorption_rate", w.absorption_rate},
                           {"diffusion", w.diffusion},
                           {"gravity_flow", w.gravity_flow}};
  }
  if (config.has_effect("surface_tension")) {
    document["surface_tension"] = {
        {"sigma", config.surface_tension.sigma},
        {"model", name_of(loader::surface_tension_model_names(), config.surface_tension.model)}};
  }
  if (config.camera) {
    json camera = {{"fov_deg", config.camera->fov_deg}};
    if (config.camera->position) camera["position"] = vec3(*config.camera->position);
    if (config.camera->target) camera["target"] = vec3(*config.camera->target);
    document["camera"] = camera;
  }
  return document;
}

void check_scene_built_in_code(const SceneConfig& config, const SuppliedMeshes& supplied) {
  parse_scene(scene_document(config), config.source, supplied);
}

}  // namespace drench
