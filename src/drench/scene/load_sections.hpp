#pragma once
/// The readers of the scene's sections that parse_scene (scene_loader.cpp) calls, one per top-level key or
/// list element; each is defined in the load_*.cpp file named after its section. Internal to the scene
/// loader. Every reader starts from the settings' defaults, overwrites what the JSON gives and validates it.
/// @throws SceneError naming the JSON path, the value and the scene's source (json_reader.hpp).

#include <drench/scene/json_reader.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench::loader {

/// `fluid` (load_fluid.cpp): the fluid's material, pressure solver and viscosity; absent: every default.
FluidSettings read_fluid(const Node& node);

/// One element of `emitters` (load_fluid_regions.cpp), a nozzle or a box chosen by its `type`.
EmitterSettings read_emitter(const Node& node);
/// One element of `boundaries` (load_fluid_regions.cpp), a box container or a plane.
BoundarySettings read_boundary(const Node& node);
/// One element of `kill_regions` (load_fluid_regions.cpp), a plane or a box.
KillRegionSettings read_kill_region(const Node& node);

/// `cloth` (load_cloth.cpp), read only when the scene has one.
ClothSettings read_cloth(const Node& node);

/// One element of `obstacles` (load_obstacles.cpp), the built-in v_plane or an OBJ file.
ObstacleSettings read_obstacle(const Node& node);

/// `coupling` (load_coupling.cpp): the coupling of fluid and cloth; absent: every default.
CouplingSettings read_coupling(const Node& node);
/// `surface` (load_surface.cpp): the surface reconstruction; absent: every default.
SurfaceSettings read_surface(const Node& node);
/// `wetting` (load_wetting.cpp): absorption, diffusion and dripping; absent: every default.
WettingSettings read_wetting(const Node& node);
/// `surface_tension` (load_surface_tension.cpp): its coefficient sigma; absent: water's.
SurfaceTensionSettings read_surface_tension(const Node& node);

/// `camera` (load_camera.cpp): where renders look from; `position` and `target` both or neither.
CameraSettings read_camera(const Node& node);

}  // namespace drench::loader
