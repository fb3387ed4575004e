#pragma once
/// `drench view`: a scene running live in a GLFW window, drawn by the Renderer that draws `drench render`'s
/// images (renderer.hpp), from the snapshots of a LiveSimulation stepping beside the window
/// (live_simulation.hpp). The keys and the mouse are documented in docs/viewer.md.

#include <cstdint>
#include <string>

#include <drench/coupling/cloth_engine.hpp>
#include <drench/render/camera.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench::render {

struct ViewOptions {
  SceneConfig config;                ///< the scene, `--set` applied and validated
  bool has_surface = false;          ///< the scene has `surface` (or the effect): the `s` key is live
  ClothEngineFactory cloth_factory;  ///< builds the cloth (the Bullet adapter's); needed with a cloth
  int width = 1280;                  ///< window width (unit: screen pixel), >= 1
  int height = 720;                  ///< window height (unit: screen pixel), >= 1
  std::int64_t frames = 0;           ///< > 0: quit after this many drawn frames; 0: run until closed
  std::string screenshot;            ///< with `frames`: the last frame as a PNG here; "" writes none
  std::string keys;                  ///< scripted keys, one per drawn frame from the first (see view_keys)
};

struct ViewResult {
  std::int64_t frames = 0;        ///< frames drawn
  double seconds = 0.0;           ///< from the first frame to the end (unit: s)
  double draw_seconds = 0.0;      ///< in Renderer::draw and the buffer swap, all frames (unit: s)
  std::int64_t steps = 0;         ///< simulation steps over all restarts
  double stepping_seconds = 0.0;  ///< wall time in those steps (unit: s)
  double surface_seconds = 0.0;   ///< the last surface reconstruction, when one was made (unit: s)
  Camera camera;                  ///< where the camera was at the end
  std::string gl;                 ///< GL_RENDERER and GL_VERSION of the window's context
  std::string screenshot;         ///< the PNG written, or ""
};

/// The keys the viewer answers, each with what it does, one per line, for --help and error messages.
std::string view_keys();

/// Checks `options` without opening anything: a size < 1, negative `frames`, a `screenshot` without
/// `frames` or in a folder that does not exist, a key in `keys` that view_keys does not list.
/// @throws drench::Error naming the option and the value.
void check_view_options(const ViewOptions& options);

/// Opens the window and runs the scene until `q`, Esc, the window's close button or `frames` drawn frames,
/// then writes the screenshot (through a temporary name) and returns. The simulation steps on its own
/// thread and the window draws the newest snapshot it has, at most 60 frames a second.
/// @throws drench::Error as check_view_options, or with "no display" when neither $DISPLAY nor
///         $WAYLAND_DISPLAY is set (before anything is built); SceneError when the scene cannot be built;
///         RenderError when GLFW cannot open an OpenGL 3.3 core window; IoError when the screenshot cannot
///         be written.
ViewResult run_viewer(const ViewOptions& options);

}  // namespace drench::render
