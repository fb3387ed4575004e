#pragma once
/// `drench render`: the frames of a finished run (`drench run --out DIR`) as PNG images, drawn headless
/// (offscreen_context.hpp) by the renderer the viewer shares (renderer.hpp), and optionally an MP4.

#include <cstdint>
#include <string>

#include <drench/render/camera.hpp>
#include <drench/render/renderer.hpp>

namespace drench::render {

struct RenderOptions {
  std::string run_dir;  ///< a `drench run --out` folder: scene.json, frames/, obstacles.ply
  /// Where the PNGs go: "" is `run_dir`/render, which may hold only an earlier render's files; any other
  /// folder must be new or empty, or an earlier `drench render --out`'s with `overwrite` (output_folder.hpp).
  std::string out_dir;
  bool overwrite = false;   ///< `--overwrite`: replace an earlier render in `out_dir`
  std::string camera_json;  ///< `--camera`: a JSON object as the scene's `camera` key; "" keeps the scene's
  int width = 1280;         ///< image width (unit: pixel), >= 1
  int height = 720;         ///< image height (unit: pixel), >= 1
  bool video = false;       ///< also write `video.mp4` through ffmpeg, when it is installed
  bool progress = true;     ///< print a progress line when stderr is a terminal
  WaterStyle water;         ///< `--water`: the surface opaque (default) or as transparent water
};

struct RenderResult {
  std::int64_t frames = 0;
  std::string out_dir;         ///< where the PNGs went
  Camera camera;               ///< the camera every frame was drawn with
  std::string gl;              ///< the OpenGL that drew them (OffscreenContext::description)
  std::string video_path;      ///< the MP4 written, or "" when none was
  std::string video_note;      ///< with `video`, why no MP4 was written (ffmpeg missing), else ""
  std::string water_note;      ///< with transparent water, frames drawn as particles (no surface), else ""
  double read_seconds = 0.0;   ///< reading and checking the frames, both passes (unit: s)
  double draw_seconds = 0.0;   ///< drawing and reading the pixels back, all frames (unit: s)
  double write_seconds = 0.0;  ///< PNG encoding and writing, all frames (unit: s)
  double video_seconds = 0.0;  ///< ffmpeg (unit: s)
  double wall_seconds = 0.0;   ///< the whole command (unit: s)
};

/// Parses `--size`: `WIDTHxHEIGHT`, e.g. "1280x720", each an integer in [1, 16384].
/// @throws drench::Error quoting the text when it is malformed or a side is out of range (a size of 0).
void parse_image_size(const std::string& text, int& width, int& height);

/// Parses `--water`: "opaque" or "transparent".
/// @throws drench::Error quoting the text and naming both when it is neither.
WaterShading parse_water_shading(const std::string& text);

/// Draws every frame a run saved into `out_dir`/frame_NNNN.png (NNNN as in frames/): the cloth
/// (cloth_NNNN.ply), the fluid as its surface when surface_NNNN.ply exists, else as particles
/// (fluid_NNNN.ply) coloured by speed, obstacles.ply and the moving bodies of the frame (bodies_NNNN.ply,
/// drawn as the obstacles are; written by demos/bullet_playground). Every frame is drawn with one camera: the
/// `camera_json` or else the scene's `camera` key when they give a position, else one framing the run's
/// stage (camera.hpp): the cloth over all frames, the obstacles and the emitters, or in a scene without cloth
/// and obstacles the middle 98 % of the fluid over all frames. The surface is drawn as `water` says; a frame
/// without one is drawn with its particles, and with transparent water `water_note` names such frames. With
/// `video`, then writes `out_dir`/video.mp4 at the scene's frame rate through ffmpeg when it is on $PATH;
/// without ffmpeg, `video_note` says so and the PNGs stand.
///
/// The frames must be whole (numbered from 0 without a gap; each with its fluid, its cloth when the run has a
/// cloth, its surface with the `surface` effect, its bodies when any frame has them), else nothing is drawn.
/// Everything is read and checked, and the OpenGL context made, before anything is written: bad input writes
/// nothing. Each PNG (and the MP4) is written under a temporary name and renamed.
/// @throws drench::Error for a size < 1, a `water.refractive_index` <= 1 or an absorption < 0 (or not
///         finite); SceneError for a bad scene.json, a malformed `camera_json` or an
///         unknown camera key (naming camera.<key>); IoError naming the file when the output folder is
///         refused (a file drench render did not write), scene.json or the frames
///         are missing, a frame's file is missing (the first such), a frame is malformed, a file cannot be
///         written, or ffmpeg fails; RenderError when no headless OpenGL context can be made.
RenderResult render_run(const RenderOptions& options);

}  // namespace drench::render
