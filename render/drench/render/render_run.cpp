#include <drench/render/render_run.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <system_error>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/common/program.hpp>
#include <drench/common/progress_line.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_reader.hpp>
#include <drench/render/offscreen_context.hpp>
#include <drench/render/png_image.hpp>
#include <drench/render/renderer.hpp>
#include <drench/scene/frame_files.hpp>
#include <drench/scene/json_reader.hpp>
#include <drench/scene/output_folder.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_resources.hpp>

namespace drench::render {

namespace {

namespace fs = std::filesystem;

/// One saved frame's files; a path is empty when the run did not save that part.
struct FrameFiles {
  std::int64_t number = 0;
  std::string digits;  ///< NNNN as the run wrote it, reused in frame_NNNN.png
  fs::path fluid, cloth, surface, bodies;
};

/// The frames in `frames_dir` in frame order: every NNNN of a fluid_, cloth_, surface_ or bodies_ file.
std::vector<FrameFiles> list_frames(const fs::path& frames_dir) {
  std::error_code ec;
  if (!fs::is_directory(frames_dir, ec)) {
    throw IoError(frames_dir.string() +
                  ": missing; drench render reads the frames/ folder of a `drench run --out` folder");
  }
  std::map<std::int64_t, FrameFiles> frames;
  for (const fs::directory_entry& entry : fs::directory_iterator(frames_dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::string digits;
    for (const char* prefix : {"fluid_", "cloth_", "surface_", "bodies_"}) {
      if (!frame_number(name, prefix, digits)) continue;
      FrameFiles& frame = frames[std::stoll(digits)];
      frame.number = std::stoll(digits);
      frame.digits = digits;
      switch (prefix[0]) {
        case 'f':
          frame.fluid = entry.path();
          break;
        case 'c':
          frame.cloth = entry.path();
          break;
        case 's':
          frame.surface = entry.path();
          break;
        default:
          frame.bodies = entry.path();
      }
    }
  }
  if (ec) throw IoError(frames_dir.string() + ": cannot list: " + ec.message());
  if (frames.empty())
    throw IoError(frames_dir.string() + ": no frames (fluid_NNNN.ply, cloth_NNNN.ply or surface_NNNN.ply)");
  std::vector<FrameFiles> list;
  for (auto& [number, frame] : frames)
    list.push_back(std::move(frame));
  return list;
}

/// The name a run gives frame `number`'s file of a kind, e.g. "cloth_0003.ply".
std::string frame_file_name(const char* prefix, std::int64_t number) {
  char name[48];
  std::snprintf(name, sizeof name, "%s%04lld.ply", prefix, static_cast<long long>(number));
  return name;
}

/// Refuses a frame set a run cannot have left whole: frames not numbered 0, 1, 2, ... without a gap, or a
/// frame without a part the run saved for every frame (the fluid always; the cloth when the scene has one or
/// any frame does; the surface with the `surface` effect; the moving bodies when any frame has them). Drawn
/// anyway, such a frame would show the water without its cloth, or a video would end at the gap.
/// @throws IoError naming the first missing file.
void check_frames_complete(const std::vector<FrameFiles>& frames, const fs::path& frames_dir,
                           const SceneConfig& config) {
  bool cloth = config.cloth.has_value(), bodies = false;
  for (const FrameFiles& frame : frames) {
    cloth = cloth || !frame.cloth.empty();
    bodies = bodies || !frame.bodies.empty();
  }
  const bool surface = config.has_effect("surface");
  std::int64_t expected = 0;
  for (const FrameFiles& frame : frames) {
    const auto missing = [&](const char* prefix, std::int64_t number, const std::string& why) {
      return IoError((frames_dir / frame_file_name(prefix, number)).string() + ": missing, " + why +
                     "; drench render draws only a whole run (run it again, or `drench reconstruct` for "
                     "surfaces)");
    };
    if (frame.number != expected) {
      throw missing(
          "fluid_", expected,
          "while frame " + frame.digits + " exists (the frames must be numbered from 0 without a gap)");
    }
    if (frame.fluid.empty()) throw missing("fluid_", frame.number, "while other files of the frame exist");
    if (cloth && frame.cloth.empty()) throw missing("cloth_", frame.number, "while the run has a cloth");
    if (bodies && frame.bodies.empty())
      throw missing("bodies_", frame.number, "while other frames have moving bodies");
    if (surface && frame.surface.empty())
      throw missing("surface_", frame.number, "while the run has the `surface` effect");
    ++expected;
  }
}

/// A PLY file that must be a triangle mesh (a cloth frame, a surface, the obstacles).
TriangleMesh read_mesh(const fs::path& path) {
  PlyData data = read_ply(path.string());
  if (!data.has_faces) throw IoError(path.string() + ": has no face element; expected a triangle mesh");
  return {std::move(data.positions), std::move(data.triangles)};
}

/// One frame's geometry as read from its files.
struct LoadedFrame {
  TriangleMesh cloth, surface, bodies;
  PlyData fluid;
};

LoadedFrame load_frame(const FrameFiles& files) {
  LoadedFrame frame;
  if (!files.cloth.empty()) frame.cloth = read_mesh(files.cloth);
  if (!files.surface.empty()) frame.surface = read_mesh(files.surface);
  if (!files.bodies.empty()) frame.bodies = read_mesh(files.bodies);
  if (!files.fluid.empty()) frame.fluid = read_ply(files.fluid.string());
  return frame;
}

/// The `q` quantile of the particles' speeds (unit: m/s); 0 without velocities.
double speed_quantile(const PlyData& fluid, double q) {
  if (fluid.velocities.empty()) return 0.0;
  std::vector<double> speeds(fluid.velocities.size());
  for (std::size_t i = 0; i < speeds.size(); ++i)
    speeds[i] = fluid.velocities[i].norm();
  const std::size_t k = static_cast<std::size_t>(q * (speeds.size() - 1));
  std::nth_element(speeds.begin(), speeds.begin() + k, speeds.end());
  return speeds[k];
}

}  // namespace

void parse_image_size(const std::string& text, int& width, int& height) {
  const auto fail = [&]() {
    return Error(
        "--size must be WIDTHxHEIGHT with each side an integer in [1, 16384], e.g. 1280x720, got \"" + text +
        "\"");
  };
  const std::size_t x = text.find('x');
  if (x == std::string::npos) throw fail();
  const std::string w = text.substr(0, x), h = text.substr(x + 1);
  for (const std::string* side : {&w, &h}) {
    if (side->empty() || side->size() > 5 || side->find_first_not_of("0123456789") != std::string::npos)
      throw fail();
  }
  width = std::stoi(w);
  height = std::stoi(h);
  if (width < 1 || height < 1 || width > 16384 || height > 16384) throw fail();
}

WaterShading parse_water_shading(const std::string& text) {
  if (text == "opaque") return WaterShading::OPAQUE;
  if (text == "transparent") return WaterShading::TRANSPARENT;
  throw Error("--water must be opaque or transparent, got \"" + text + "\"");
}

RenderResult render_run(const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  if (options.width < 1 || options.height < 1) {
    throw Error("the image size must be at least 1x1 pixels, got " + std::to_string(options.width) + "x" +
                std::to_string(options.height));
  }
  const WaterStyle& water = options.water;
  if (!(water.refractive_index > 1.0 && std::isfinite(water.refractive_index)))
    throw Error("the water's refractive index must be > 1, got " + format_number(water.refractive_index));
  for (int c = 0; c < 3; ++c) {
    if (!(water.absorption[c] >= 0.0 && std::isfinite(water.absorption[c])))
      throw Error("the water's absorption must be >= 0 1/m in each channel, got " +
                  format_number(water.absorption[c]) + " in channel " + std::to_string(c) +
                  " (0 red, 1 green, 2 blue)");
  }
  // The framebuffers and the read-back, per pixel: 4 samples of colour and depth (32 bytes), the resolved
  // colour, the pixels read back and the PNG rows (about 16); transparent water doubles the multisampled
  // targets and adds three full-size textures. Checked against the memory first, naming the size, rather
  // than failing in the driver after gigabytes were taken.
  const double bytes_per_pixel = water.shading == WaterShading::TRANSPARENT ? 96.0 : 48.0;
  const double image_bytes = static_cast<double>(options.width) * options.height * bytes_per_pixel;
  const double available = machine_limits("", 0).memory_bytes;
  if (image_bytes > available) {
    throw Error("an image of " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " pixels needs about " + format_number(std::round(image_bytes)) +
                " bytes for its framebuffers, more than the " + format_number(std::round(available)) +
                " bytes available (MemAvailable): choose a smaller size (drench render --size)");
  }
  const fs::path dir(options.run_dir);
  RenderResult result;
  // The folder first, as drench run does: a render that could not write there is refused before any frame is
  // read.
  const fs::path out_dir = options.out_dir.empty() ? dir / "render" : fs::path(options.out_dir);
  result.out_dir = out_dir.string();
  if (options.out_dir.empty())
    check_folder_holds_only(out_dir.string(), "render", render_output_patterns());
  else
    check_output_folder(out_dir.string(), "--out", "render", render_output_patterns(), options.overwrite);

  // The scene: its camera, the particle size and the frame rate.
  const fs::path scene_path = dir / "scene.json";
  std::error_code ec;
  if (!fs::exists(scene_path, ec)) {
    throw IoError(
        scene_path.string() +
        ": missing; drench render needs the scene.json that drench run writes into its --out folder");
  }
  const SceneConfig config = parse_scene(read_scene_document(scene_path.string()), scene_path.string());
  std::optional<CameraSettings> camera_settings = config.camera;
  if (!options.camera_json.empty()) {
    nlohmann::json camera;
    try {
      // Strict as a scene file is: a key given twice was silently the last one.
      camera = loader::parse_json_strict(options.camera_json, loader::kMaxJsonDepth);
    } catch (const SceneError& e) {
      throw SceneError("--camera: " + std::string(e.what()));
    } catch (const nlohmann::json::exception& e) {
      throw SceneError(
          "--camera is not valid JSON (" + std::string(e.what()) +
          "); expected e.g. {\"position\": [0, 0.4, 1.2], \"target\": [0, 0, 0], \"fov_deg\": 45}");
    }
    camera_settings = parse_camera(camera, "--camera");
  }

  // Every input read and checked before the first write, as drench reconstruct does; the same pass finds the
  // bounds the default camera frames and the speed drawn in the fastest colour.
  const std::vector<FrameFiles> frames = list_frames(dir / "frames");
  TriangleMesh obstacles;
  const fs::path obstacles_path = dir / "obstacles.ply";
  const bool has_obstacles = fs::exists(obstacles_path, ec);
  // The stage is what holds the water: the cloth over all frames, the obstacles and the emitters. Only a
  // scene without cloth and obstacles is framed on the fluid itself, on its middle 98 % (spray that flies
  // off and falls away would shrink the picture).
  Eigen::AlignedBox3d stage, fluid_box;
  double speed_scale = 0.0;
  {
    ScopedTimer timer(result.read_seconds);
    if (has_obstacles) {
      obstacles = read_mesh(obstacles_path);
      stage.extend(points_box(obstacles.positions));
    }
    for (const FrameFiles& files : frames) {
      const LoadedFrame frame = load_frame(files);
      stage.extend(points_box(frame.cloth.positions));
      stage.extend(points_box(frame.bodies.positions));
      fluid_box.extend(quantile_box(frame.fluid.positions, 0.01, 0.99));
      if (frame.fluid.positions.empty()) fluid_box.extend(quantile_box(frame.surface.positions, 0.01, 0.99));
      speed_scale = std::max(speed_scale, speed_quantile(frame.fluid, 0.99));
    }
  }
  // After the read pass, so that a malformed file is named as such rather than as the frame set's gap.
  check_frames_complete(frames, dir / "frames", config);
  const Eigen::AlignedBox3d bounds = framed_bounds(config, stage, fluid_box);
  const Scalar aspect = static_cast<Scalar>(options.width) / options.height;
  result.camera = resolve_camera(camera_settings, bounds, aspect);
  // The bounds set the depth range, so they must hold all that is drawn, spray and the camera's target too.
  Eigen::AlignedBox3d depth_bounds = bounds;
  depth_bounds.extend(fluid_box);
  depth_bounds.extend(result.camera.target);

  ParticleStyle style;
  style.radius = 0.5 * config.fluid.particle_spacing;
  style.speed_scale = std::max(speed_scale, 0.1);

  OffscreenContext context(options.width, options.height);
  Renderer renderer;
  result.gl = context.description();

  if (options.out_dir.empty()) {
    fs::create_directories(out_dir, ec);
    if (ec) throw IoError(out_dir.string() + ": cannot create: " + ec.message());
  } else {
    prepare_output_folder(out_dir.string(), "--out", "render", render_output_patterns(), options.overwrite);
  }

  // Transparent water needs the surface; frames without one keep their particles, said once at the end.
  std::int64_t particle_frames = 0;
  std::string first_particle_frame;
  ProgressLine progress(options.progress, frames.size());
  for (const FrameFiles& files : frames) {
    LoadedFrame frame;
    {
      ScopedTimer timer(result.read_seconds);
      frame = load_frame(files);
    }
    FrameGeometry geometry;
    geometry.bounds = depth_bounds;
    if (!files.cloth.empty()) geometry.cloth = &frame.cloth;
    // The moving bodies of the frame are drawn as obstacles are, with the static ones.
    TriangleMesh solids;
    if (!files.bodies.empty()) {
      solids = obstacles;
      const auto offset = static_cast<Index>(solids.positions.size());
      solids.positions.insert(solids.positions.end(), frame.bodies.positions.begin(),
                              frame.bodies.positions.end());
      for (const Triangle& t : frame.bodies.triangles)
        solids.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
      geometry.obstacles = &solids;
    } else if (has_obstacles) {
      geometry.obstacles = &obstacles;
    }
    if (!files.surface.empty()) {
      geometry.surface = &frame.surface;
    } else if (particle_frames++ == 0) {
      first_particle_frame = files.digits;
    }
    geometry.particles = &frame.fluid.positions;
    if (!frame.fluid.velocities.empty()) geometry.velocities = &frame.fluid.velocities;
    Image image;
    {
      ScopedTimer timer(result.draw_seconds);
      context.bind();
      renderer.draw(geometry, result.camera, style, options.width, options.height, options.water);
      image = context.read_image();
    }
    {
      ScopedTimer timer(result.write_seconds);
      write_file_atomic((out_dir / ("frame_" + files.digits + ".png")).string(), encode_png(image));
    }
    ++result.frames;
    progress.update(static_cast<std::size_t>(result.frames), wall());
  }

  if (options.water.shading == WaterShading::TRANSPARENT && particle_frames > 0) {
    result.water_note =
        std::to_string(particle_frames) + " of " + std::to_string(frames.size()) +
        " frames (the first frame_" + first_particle_frame +
        ") have no surface_NNNN.ply, so their water is drawn as particles, not as transparent water; the "
        "scene's `surface` effect writes the surfaces, or `drench reconstruct " +
        options.run_dir + "` afterwards";
  }

  if (options.video) {
    const std::string ffmpeg = find_program("ffmpeg");
    if (ffmpeg.empty()) {
      result.video_note = "no MP4 written: ffmpeg is not installed (Debian: sudo apt-get install ffmpeg)";
    } else {
      ScopedTimer timer(result.video_seconds);
      const fs::path video = out_dir / "video.mp4";
      const std::string temporary = video.string() + ".tmp-" + std::to_string(::getpid());
      const double rate = config.time.frame_rate > 0 ? config.time.frame_rate : 30.0;
      // Even sides for yuv420p, which every player takes; frames numbered on from the first one saved.
      const int status =
          run_program({ffmpeg, "-hide_banner", "-loglevel", "error", "-y", "-framerate", format_number(rate),
                       "-start_number", std::to_string(frames.front().number), "-i",
                       (out_dir / "frame_%04d.png").string(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v",
                       "libx264", "-pix_fmt", "yuv420p",
                       // Exactly this run's frames: never an older render's frame_NNNN.png
                       // that follows them in the folder.
                       "-frames:v", std::to_string(frames.size()), "-f", "mp4", temporary});
      if (status != 0) {
        std::remove(temporary.c_str());
        throw IoError(
            ffmpeg +
            (status < 0 ? " could not be started" : " failed with exit status " + std::to_string(status)) +
            " while writing " + video.string() + "; the PNG frames are in " + out_dir.string());
      }
      fs::rename(temporary, video, ec);
      if (ec) throw IoError("cannot rename " + temporary + " to " + video.string() + ": " + ec.message());
      result.video_path = video.string();
    }
  }
  result.wall_seconds = wall();
  return result;
}

}  // namespace drench::render
