/// The scene's lists of regions, each element a shape chosen by its `type`: `emitters` (where fluid enters),
/// `boundaries` (what holds it) and `kill_regions` (where it leaves).

#include <cstddef>

#include <drench/scene/load_sections.hpp>
#include <drench/scene/scene_names.hpp>

namespace drench::loader {

EmitterSettings read_emitter(const Node& node) {
  using Kind = EmitterSettings::Kind;
  EmitterSettings emitter;
  emitter.kind = read_type(node, emitter_type_names());
  if (emitter.kind == Kind::NOZZLE) {
    NozzleEmitterSettings& nozzle = emitter.nozzle;
    const ObjectReader r(node,
                         {"type", "center", "direction", "radius", "speed", "start_time", "max_particles"});
    r.read("center", nozzle.center, kCoordinate);
    r.read_unit("direction", nozzle.direction);
    r.read("radius", nozzle.radius, kLength);
    r.read("speed", nozzle.speed, kPositive);
    r.read("start_time", nozzle.start_time, kNonNegative);
    r.read("max_particles", nozzle.max_particles, kNonNegative);
  } else {
    BoxEmitterSettings& box = emitter.box;
    const ObjectReader r(node, {"type", "min", "max", "velocity"});
    r.read("min", box.min, kCoordinate);
    r.read("max", box.max, kCoordinate);
    r.read("velocity", box.velocity);
    r.require_box(box.min, box.max);
  }
  return emitter;
}

BoundarySettings read_boundary(const Node& node) {
  using Kind = BoundarySettings::Kind;
  BoundarySettings boundary;
  boundary.kind = read_type(node, boundary_type_names());
  if (boundary.kind == Kind::BOX) {
    const ObjectReader r(node, {"type", "min", "max", "open_top", "layers"});
    r.read("min", boundary.min, kCoordinate);
    r.read("max", boundary.max, kCoordinate);
    r.read("open_top", boundary.open_top);
    r.read("layers", boundary.layers, kAtLeastOne);
    r.require_box(boundary.min, boundary.max);
  } else {
    const ObjectReader r(node, {"type", "point", "normal", "size", "layers"});
    r.read("point", boundary.point, kCoordinate);
    r.read_unit("normal", boundary.normal);
    if (const Node size = r["size"]; size.present()) {
      if (!size.value().is_array() || size.value().size() != 2) size.fail("must be an array of 2 numbers");
      for (std::size_t i = 0; i < 2; ++i)
        boundary.size[i] = size.element(i).number(kLength);
    }
    r.read("layers", boundary.layers, kAtLeastOne);
  }
  return boundary;
}

KillRegionSettings read_kill_region(const Node& node) {
  using Kind = KillRegionSettings::Kind;
  KillRegionSettings region;
  region.kind = read_type(node, kill_region_type_names());
  if (region.kind == Kind::PLANE) {
    const ObjectReader r(node, {"type", "point", "normal"});
    r.read("point", region.point, kCoordinate);
    r.read_unit("normal", region.normal);
  } else {
    const ObjectReader r(node, {"type", "min", "max"});
    r.read("min", region.min, kCoordinate);
    r.read("max", region.max, kCoordinate);
    r.require_box(region.min, region.max);
  }
  return region;
}

}  // namespace drench::loader
