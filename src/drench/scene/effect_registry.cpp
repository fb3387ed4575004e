#include <drench/scene/effect_registry.hpp>

#include <algorithm>
#include <utility>

namespace drench {
namespace {

void build_viscosity(const EffectSite&, EffectParts& parts) {
  parts.viscosity = true;
}

void build_surface_tension(const EffectSite&, EffectParts& parts) {
  parts.surface_tension = true;
}

void build_coupling(const EffectSite& site, EffectParts& parts) {
  // A scene built in code may list the coupling without a cloth or obstacles: nothing to couple.
  if (!site.contact_mesh) return;
  const CouplingSettings& settings = site.config.coupling;
  // Friction is a stage of the coupler, on the coupler's own contacts (coupler.cpp): built into it here.
  parts.coupler = std::make_unique<Coupler>(settings, site.config.has_effect("friction"));
  const bool carried_water = settings.scheme == CouplingScheme::CARRIED_WATER;
  if (settings.continuous && settings.substep_obstacle)
    parts.obstacle =
        std::make_unique<ClothObstacle>(settings.cloth_thickness, settings.broad_phase, carried_water);
  if (carried_water) parts.carried = std::make_unique<CarriedWater>();
}

void build_adhesion(const EffectSite& site, EffectParts& parts) {
  if (!parts.coupler) return;  // no cloth and no obstacles: nothing to cling to
  // One work per triangle of the contact mesh, in its order: the cloth's, then each obstacle's; a program's
  // own obstacles and rigid bodies after them get none.
  AdhesionSettings adhesion;
  if (site.cloth_mesh)
    adhesion.work.assign(site.cloth_mesh->triangle_count(),
                         (site.config.cloth ? *site.config.cloth : ClothSettings{}).adhesion);
  if (site.obstacles) {
    for (std::size_t i = 0; i < site.obstacles->size() && i < site.config.obstacles.size(); ++i)
      adhesion.work.insert(adhesion.work.end(), (*site.obstacles)[i].triangles.size(),
                           site.config.obstacles[i].adhesion);
  }
  // The SPH support radius: the water within it of a face feels the face as it feels its neighbors.
  adhesion.range = 2.0 * site.config.fluid.particle_spacing;
  adhesion.rest_density = site.config.fluid.rest_density;
  parts.coupler->set_adhesion(std::move(adhesion));
}

void build_leak_audit(const EffectSite& site, EffectParts& parts) {
  parts.leak_audit = site.contact_mesh != nullptr;
  parts.leak_counter.constructed = parts.leak_audit ? 1 : 0;
}

void build_wetting(const EffectSite& site, EffectParts& parts) {
  // The water comes from the coupling's contacts: without a coupler there is none to absorb.
  if (!site.cloth_mesh || !parts.coupler) return;
  const ClothMesh& nodes = *site.cloth_mesh;
  parts.wetting = std::make_unique<ClothWetting>(site.config.wetting, nodes.triangles, nodes.positions_t0,
                                                 cloth_dry_masses(site.config, site.cloth, nodes));
  ++parts.wetting_counter.constructed;
}

}  // namespace

const std::vector<EffectEntry>& effect_registry() {
  // Each entry: name, description, needs {mesh, effect, why}, settings {section, what}, counter, build.
  static const std::vector<EffectEntry> registry = {
      {"viscosity",
       "the viscosity force of fluid.viscosity in every fluid sub-step (XSPH, Monaghan 1989; artificial "
       "viscosity, Monaghan 1992), built by the FluidSolver",
       {},
       {},
       &EffectCounters::viscosity,
       build_viscosity},
      {"surface_tension",
       "the surface tension force of surface_tension.sigma in every fluid sub-step, of surface_tension.model "
       "(Akinci et al. 2013's cohesion and curvature, or the continuum surface force of Brackbill et al. "
       "1992; "
       "the paper's future work, sec. 6), built by the FluidSolver",
       {},
       {"surface_tension", "the surface tension"},
       &EffectCounters::surface_tension,
       build_surface_tension},
      {"coupling",
       "two-way coupling with the cloth and the obstacles: repulsion (sec. 3.1-3.2, eq. 1-4) and continuous "
       "handling (sec. 3.3, eq. 5-6)",
       {EffectMesh::CLOTH_OR_OBSTACLES},
       {},
       &EffectCounters::coupling,
       build_coupling},
      {"friction",
       "tangential boundary conditions at contact, no-slip or Coulomb friction (sec. 3.4, eq. 7-8): a stage "
       "of the coupler, built by \"coupling\"",
       {EffectMesh::NONE, "coupling"},
       {},
       &EffectCounters::friction,
       nullptr},
      {"adhesion",
       "water clings to the cloth and the obstacles by cloth.adhesion and obstacles[i].adhesion, a work of "
       "adhesion per area (the paper's future work, sec. 6): a stage of the coupler, after friction",
       {EffectMesh::NONE, "coupling", ", whose broad phase finds the faces near the water"},
       {},
       &EffectCounters::adhesion,
       build_adhesion},
      {"leak_audit",
       "counts the particles that cross the cloth or an obstacle in a step, by exact predicates (a drench "
       "addition that checks sec. 3.3's claim)",
       {EffectMesh::CLOTH_OR_OBSTACLES},
       {},
       &EffectCounters::leak_audit,
       build_leak_audit},
      {"surface",
       "the fluid's surface at every frame, kept off the cloth (sec. 4), built by the run loop",
       {},
       {"surface", "the surface reconstruction"},
       &EffectCounters::surface,
       nullptr},
      {"wetting",
       "the cloth absorbs, spreads and drips water (sec. 5, Fig. 9)",
       {EffectMesh::CLOTH, "coupling", ", whose contacts give the cloth its water"},
       {"wetting", "the wetting"},
       &EffectCounters::wetting,
       build_wetting},
  };
  return registry;
}

const EffectEntry* find_effect(const std::string& name) {
  const std::vector<EffectEntry>& registry = effect_registry();
  const auto it = std::find_if(registry.begin(), registry.end(),
                               [&](const EffectEntry& entry) { return name == entry.name; });
  return it == registry.end() ? nullptr : &*it;
}

ScalarArray cloth_dry_masses(const SceneConfig& config, const ClothEngine* engine, const ClothMesh& cloth) {
  ScalarArray dry;
  if (!config.cloth && engine) dry = engine->dry_node_masses();
  if (!dry.empty()) return dry;
  const double area_density = (config.cloth ? *config.cloth : ClothSettings{}).area_density;
  dry.assign(cloth.node_count(), 0.0);
  for (const Triangle& t : cloth.triangles) {
    const Vec3& a = cloth.positions_t0[t[0]];
    const double area = 0.5 * (cloth.positions_t0[t[1]] - a).cross(cloth.positions_t0[t[2]] - a).norm();
    for (const Index i : t)
      dry[i] += area_density * area / 3.0;
  }
  return dry;
}

EffectParts build_effects(const EffectSite& site) {
  EffectParts parts;
  for (const EffectEntry& effect : effect_registry()) {
    if (effect.build && site.config.has_effect(effect.name)) effect.build(site, parts);
  }
  return parts;
}

}  // namespace drench
