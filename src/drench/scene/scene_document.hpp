#pragma once
/// A SceneConfig as the scene file that gives it back: the loader's inverse, so that a scene a program built
/// in code is held to the same checks as a file (check_scene_built_in_code) and can be saved for `drench run`
/// or `drench view`.

#include <nlohmann/json.hpp>
#include <string>

#include <drench/scene/scene_config.hpp>

namespace drench {

/// The scene document (docs/scenes.md) whose parse_scene gives `config` back. Every key of the always-used
/// sections is written (gravity, fluid, emitters, boundaries, kill regions, time, cloth, obstacles,
/// coupling, effects, camera); the settings sections of `surface`, `wetting` and `surface_tension`, and
/// the works of adhesion, only when their effect is listed, as a file could write them. Settings no scene
/// key names (SurfaceSettings::kernel_radius_in_spacings, particle_radius_in_spacings) are left out.
/// Values are written as they are, NaN and out-of-range ones too, for parse_scene to refuse.
nlohmann::json scene_document(const SceneConfig& config);

/// Holds a scene built in code to every check a scene file meets (parse_scene of its scene_document), but
/// for the effects' needs that `supplied` meets: a game's SceneConfig is refused as the same scene file
/// would be, in the same words, its source named `config.source` ("<code>" by default).
/// @throws SceneError `<json.path> <problem>, got <value> (<config.source>)`, as parse_scene
void check_scene_built_in_code(const SceneConfig& config, const SuppliedMeshes& supplied = {});

}  // namespace drench
