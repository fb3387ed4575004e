#include <drench/render/viewer.hpp>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/render/live_simulation.hpp>
#include <drench/render/png_image.hpp>
#include <drench/render/render_error.hpp>
#include <drench/render/renderer.hpp>
#include <drench/scene/simulation.hpp>

namespace drench::render {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

/// The keys, as --keys spells them; the window maps its key codes onto these characters.
struct KeyHelp {
  char key;
  const char* name;
  const char* does;
};
constexpr KeyHelp kKeys[] = {
    {' ', "space", "pause or resume the simulation"},
    {'.', ".", "one step, while paused"},
    {'r', "r", "restart the scene"},
    {'p', "p", "particles on or off"},
    {'s', "s", "the fluid's surface on or off (scenes with `surface`)"},
    {'c', "c", "cloth on or off"},
    {'w', "w", "cloth shaded or as wireframe"},
    {'o', "o", "obstacles on or off"},
    {'q', "q", "quit (also Esc)"},
};

bool known_key(char key) {
  return std::any_of(std::begin(kKeys), std::end(kKeys), [&](const KeyHelp& k) { return k.key == key; });
}

/// The key a GLFW key code stands for, or 0 for keys the viewer ignores. Key codes name the US layout's
/// keys: the viewer's letters sit where a US keyboard has them.
char key_of(int code) {
  switch (code) {
    case GLFW_KEY_SPACE:
      return ' ';
    case GLFW_KEY_PERIOD:
      return '.';
    case GLFW_KEY_ESCAPE:
      return 'q';
    default:
      break;
  }
  if (code >= GLFW_KEY_A && code <= GLFW_KEY_Z) {
    const char key = static_cast<char>('a' + (code - GLFW_KEY_A));
    if (known_key(key)) return key;
  }
  return 0;
}

/// What the window shows and how the mouse last moved; GLFW's callbacks reach it through the window's user
/// pointer.
struct ViewState {
  Camera camera;
  bool show_particles = true, show_surface = false, show_cloth = true, wireframe = false,
       show_obstacles = true;
  bool has_surface = false;
  bool paused = false;  // as the keys left it; the simulation follows from the first frame on
  bool quit = false;
  LiveSimulation* simulation = nullptr;
  std::vector<char> pressed;  // keys pressed since the last frame, in order
  double cursor_x = 0, cursor_y = 0;
  bool cursor_known = false;
};

ViewState& state_of(GLFWwindow* window) {
  return *static_cast<ViewState*>(glfwGetWindowUserPointer(window));
}

void apply_key(ViewState& state, char key) {
  switch (key) {
    case ' ':
      state.paused = !state.paused;
      state.simulation->set_paused(state.paused);
      break;
    case '.':
      state.simulation->step_once();
      break;
    case 'r':
      state.simulation->restart();
      break;
    case 'p':
      state.show_particles = !state.show_particles;
      break;
    case 's':
      if (state.has_surface) state.show_surface = !state.show_surface;
      break;
    case 'c':
      state.show_cloth = !state.show_cloth;
      break;
    case 'w':
      state.wireframe = !state.wireframe;
      break;
    case 'o':
      state.show_obstacles = !state.show_obstacles;
      break;
    case 'q':
      state.quit = true;
      break;
    default:
      break;
  }
}

void on_key(GLFWwindow* window, int code, int /*scancode*/, int action, int /*mods*/) {
  const char key = key_of(code);
  // Holding `.` steps on at the keyboard's repeat rate; the toggles take one press each.
  if (key != 0 && (action == GLFW_PRESS || (action == GLFW_REPEAT && key == '.')))
    state_of(window).pressed.push_back(key);
}

void on_cursor(GLFWwindow* window, double x, double y) {
  ViewState& state = state_of(window);
  const double dx = x - state.cursor_x, dy = y - state.cursor_y;
  const bool known = state.cursor_known;
  state.cursor_x = x;
  state.cursor_y = y;
  state.cursor_known = true;
  if (!known) return;
  // 0.3 degrees a pixel: a drag across a 1280-pixel window turns the scene a full turn and some.
  constexpr Scalar kRadiansPerPixel = 0.3 * 3.14159265358979323846 / 180.0;
  if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
    orbit(state.camera, -kRadiansPerPixel * dx, kRadiansPerPixel * dy);
  } else if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
             glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS) {
    int width = 0, height = 0;
    glfwGetWindowSize(window, &width, &height);
    pan(state.camera, dx, dy, height);
  }
}

void on_scroll(GLFWwindow* window, double /*x*/, double y) {
  // A notch of the wheel is 10 % of the distance to the target.
  zoom(state_of(window).camera, std::pow(0.9, y));
}

/// GLFW's last error, for messages: "(65544) X11: The DISPLAY environment variable is missing".
std::string glfw_error() {
  const char* description = nullptr;
  const int code = glfwGetError(&description);
  if (code == GLFW_NO_ERROR) return "no error reported";
  return "(" + std::to_string(code) + ") " + (description ? description : "");
}

struct GlfwSession {
  GlfwSession() {
    if (glfwInit() != GLFW_TRUE) {
      throw RenderError("GLFW cannot start: " + glfw_error() +
                        "; no display: use drench render for headless images, or run under xvfb-run");
    }
  }
  ~GlfwSession() { glfwTerminate(); }
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

struct WindowDeleter {
  void operator()(GLFWwindow* window) const { glfwDestroyWindow(window); }
};

/// The bound framebuffer's back buffer as an image, rows from the top.
Image read_back_buffer(int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(3 * static_cast<std::size_t>(width) * height);
  std::vector<std::uint8_t> rgb(image.rgb.size());
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char text[64];
    std::snprintf(text, sizeof text, "OpenGL error 0x%04x while reading the window back", error);
    throw RenderError(text);
  }
  // OpenGL's rows start at the bottom, PNG's at the top.
  const std::size_t row = 3 * static_cast<std::size_t>(width);
  for (int y = 0; y < height; ++y)
    std::copy_n(rgb.data() + row * (height - 1 - y), row, image.rgb.data() + row * y);
  return image;
}

/// The `q` quantile of the speeds of `velocities` (unit: m/s); 0 when there are none.
double speed_quantile(const Vec3Array& velocities, double q, std::vector<double>& speeds) {
  if (velocities.empty()) return 0.0;
  speeds.resize(velocities.size());
  for (std::size_t i = 0; i < speeds.size(); ++i)
    speeds[i] = velocities[i].norm();
  const std::size_t k = static_cast<std::size_t>(q * (speeds.size() - 1));
  std::nth_element(speeds.begin(), speeds.begin() + k, speeds.end());
  return speeds[k];
}

/// The static obstacles as one mesh, drawn and handed to the surface in one piece.
TriangleMesh merge(const std::vector<TriangleMesh>& meshes) {
  TriangleMesh merged;
  for (const TriangleMesh& mesh : meshes) {
    const Index offset = static_cast<Index>(merged.positions.size());
    merged.positions.insert(merged.positions.end(), mesh.positions.begin(), mesh.positions.end());
    for (const Triangle& t : mesh.triangles)
      merged.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  return merged;
}

std::string status_line(const Snapshot& s, double fps, bool paused, bool surface_pending) {
  char line[256];
  const char* state = !s.stopped.empty() ? "stopped"
                      : s.finished       ? "finished"
                      : paused           ? "paused"
                                         : "running";
  std::snprintf(
      line, sizeof line,
      "drench view | t %.3f s | %zu particles | %.1f steps/s | %.1f fps | %llu contacts | %llu leaks "
      "| %s%s",
      s.time, s.positions.size(), paused || s.finished ? 0.0 : s.steps_per_second, fps,
      static_cast<unsigned long long>(s.contacts), static_cast<unsigned long long>(s.leaks), state,
      surface_pending ? " | surface..." : "");
  return line;
}

}  // namespace

std::string view_keys() {
  std::string text;
  for (const KeyHelp& k : kKeys)
    text += std::string("  ") + k.name + std::string(6 - std::string(k.name).size(), ' ') + k.does + "\n";
  return text;
}

void check_view_options(const ViewOptions& options) {
  if (options.width < 1 || options.height < 1) {
    throw Error("the window size must be at least 1x1 pixels, got " + std::to_string(options.width) + "x" +
                std::to_string(options.height));
  }
  if (options.frames < 0) throw Error("--frames must be >= 0, got " + std::to_string(options.frames));
  if (!options.screenshot.empty()) {
    if (options.frames == 0)
      throw Error("--screenshot " + options.screenshot + " needs --frames N: the frame to write is the Nth");
    const fs::path parent = fs::absolute(options.screenshot).parent_path();
    std::error_code ec;
    if (!fs::is_directory(parent, ec))
      throw Error("--screenshot " + options.screenshot + ": the folder " + parent.string() +
                  " does not exist");
    // Checked here, not when the Nth frame is written: a folder failed only after the frames had run.
    const fs::file_status status = fs::status(options.screenshot, ec);
    if (fs::exists(status) && !fs::is_regular_file(status))
      throw Error("--screenshot " + options.screenshot + ": exists and is not a file; name a PNG file");
  }
  for (std::size_t i = 0; i < options.keys.size(); ++i) {
    if (!known_key(options.keys[i])) {
      throw Error("--keys: unknown key '" + std::string(1, options.keys[i]) + "' at position " +
                  std::to_string(i) + " of \"" + options.keys + "\"; the keys are:\n" + view_keys());
    }
  }
}

ViewResult run_viewer(const ViewOptions& options) {
  check_view_options(options);
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0'))
    throw Error("no display: use drench render for headless images, or run under xvfb-run");

  // The scene first: a bad one is reported before a window opens. Paused until the window is up, so that
  // the first frame shows the initial state.
  const SceneConfig& config = options.config;
  LiveSimulation simulation(
      [&config, &options] { return std::make_unique<Simulation>(config, options.cloth_factory); }, true);
  Snapshot snapshot;
  simulation.take_latest(snapshot);

  std::vector<TriangleMesh> obstacle_meshes = build_obstacles(config);
  const TriangleMesh obstacles = merge(obstacle_meshes);
  std::unique_ptr<LiveSurface> surface;
  if (options.has_surface)
    surface = std::make_unique<LiveSurface>(config.fluid.particle_spacing, config.surface, obstacles);

  GlfwSession session;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);  // as OffscreenContext draws; a soft hint, fewer where there are fewer
  std::unique_ptr<GLFWwindow, WindowDeleter> window(
      glfwCreateWindow(options.width, options.height, "drench view", nullptr, nullptr));
  if (!window) {
    throw RenderError("GLFW cannot open a window with OpenGL 3.3 core: " + glfw_error() +
                      " (Debian: libgl1-mesa-dri for Mesa's drivers)");
  }
  glfwMakeContextCurrent(window.get());
  // Vsync where the display has it: no more frames than it shows, and the cores left to the simulation.
  glfwSwapInterval(1);

  ViewResult result;
  result.gl = std::string(reinterpret_cast<const char*>(glGetString(GL_RENDERER))) + ", " +
              reinterpret_cast<const char*>(glGetString(GL_VERSION));
  Renderer renderer;

  ViewState state;
  state.simulation = &simulation;
  state.has_surface = options.has_surface;
  glfwSetWindowUserPointer(window.get(), &state);
  glfwSetKeyCallback(window.get(), on_key);
  glfwSetCursorPosCallback(window.get(), on_cursor);
  glfwSetScrollCallback(window.get(), on_scroll);

  // The camera frames what `drench render` frames, from the scene's start: the cloth and the obstacles with
  // the emitters, or a fluid-only scene's water.
  Eigen::AlignedBox3d stage = points_box(snapshot.cloth.positions);
  stage.extend(points_box(obstacles.positions));
  const Eigen::AlignedBox3d bounds =
      framed_bounds(config, stage, quantile_box(snapshot.positions, 0.01, 0.99));
  state.camera = resolve_camera(config.camera, bounds, static_cast<Scalar>(options.width) / options.height);

  ParticleStyle style;
  style.radius = 0.5 * config.fluid.particle_spacing;
  double fastest = 0.1;  // the speed drawn in the fastest colour only grows, so colours do not flicker
  std::vector<double> speeds;

  TriangleMesh surface_mesh;
  std::uint64_t surface_serial = 0, surface_generation = 0, requested_serial = 0;
  bool have_surface = false;

  const Clock::time_point start = Clock::now();
  Clock::time_point title_time = start;
  std::int64_t title_frames = 0;
  double fps = 0.0;
  // 60 frames a second at most: where there is no vsync (Xvfb, some drivers), drawing faster than a screen
  // shows would only take the cores from the simulation.
  constexpr double kMinFrameSeconds = 1.0 / 60.0;
  Clock::time_point frame_start = start;
  std::int64_t keyed_frame = -1;
  bool started = false;

  while (!state.quit && !glfwWindowShouldClose(window.get())) {
    glfwPollEvents();
    // Each scripted key once, before the frame of its index is drawn (a minimised window draws none).
    if (result.frames > keyed_frame && result.frames < static_cast<std::int64_t>(options.keys.size())) {
      keyed_frame = result.frames;
      state.pressed.push_back(options.keys[static_cast<std::size_t>(result.frames)]);
    }
    for (const char key : state.pressed)
      apply_key(state, key);
    state.pressed.clear();
    // The simulation waited, paused, for the window; it starts once the first frame's keys are in, so that
    // a script that begins with a space has it paused before its first step.
    if (!started) {
      simulation.set_paused(state.paused);
      started = true;
    }
    if (state.quit) break;
    const std::string error = simulation.error();
    if (!error.empty()) throw SceneError("restarting the scene failed: " + error);

    if (simulation.take_latest(snapshot))
      fastest = std::max(fastest, speed_quantile(snapshot.velocities, 0.99, speeds));
    if (surface) {
      std::string surface_error;
      if (surface->take(surface_mesh, surface_serial, surface_generation, surface_error)) {
        have_surface = true;
        if (!surface_error.empty()) std::fprintf(stderr, "drench view: surface: %s\n", surface_error.c_str());
      }
      // At most one request a frame, and none while the last one is under way (request refuses then).
      if (state.show_surface && snapshot.serial != requested_serial && surface->request(snapshot))
        requested_serial = snapshot.serial;
    }
    const bool surface_shown =
        state.show_surface && have_surface && surface_generation == snapshot.generation;

    int width = 0, height = 0;
    glfwGetFramebufferSize(window.get(), &width, &height);
    if (width > 0 && height > 0) {  // 0 while minimised
      FrameGeometry geometry;
      geometry.bounds = bounds;
      geometry.bounds.extend(quantile_box(snapshot.positions, 0.01, 0.99));
      geometry.bounds.extend(state.camera.target);
      if (state.show_cloth && !snapshot.cloth.triangles.empty()) geometry.cloth = &snapshot.cloth;
      geometry.cloth_wireframe = state.wireframe;
      if (state.show_obstacles && !obstacles.triangles.empty()) geometry.obstacles = &obstacles;
      if (surface_shown) geometry.surface = &surface_mesh;
      if (state.show_particles) {
        geometry.particles = &snapshot.positions;
        geometry.velocities = &snapshot.velocities;
      }
      style.speed_scale = fastest;
      const Clock::time_point draw_start = Clock::now();
      glViewport(0, 0, width, height);
      renderer.draw(geometry, state.camera, style, width, height);
      ++result.frames;
      if (options.frames > 0 && result.frames >= options.frames && !options.screenshot.empty()) {
        write_file_atomic(options.screenshot, encode_png(read_back_buffer(width, height)));
        result.screenshot = options.screenshot;
      }
      glfwSwapBuffers(window.get());
      result.draw_seconds += seconds_between(draw_start, Clock::now());
    } else {
      glfwSwapBuffers(window.get());
    }
    if (options.frames > 0 && result.frames >= options.frames) break;

    const Clock::time_point now = Clock::now();
    const double since_title = seconds_between(title_time, now);
    if (since_title >= 0.25) {
      fps = (result.frames - title_frames) / since_title;
      title_frames = result.frames;
      title_time = now;
      const bool pending = state.show_surface && !surface_shown;
      glfwSetWindowTitle(window.get(), status_line(snapshot, fps, state.paused, pending).c_str());
    }
    const double spare = kMinFrameSeconds - seconds_between(frame_start, now);
    if (spare > 0) glfwWaitEventsTimeout(spare);
    frame_start = Clock::now();
  }

  result.seconds = seconds_between(start, Clock::now());
  result.steps = simulation.total_steps();
  result.stepping_seconds = simulation.stepping_seconds();
  if (surface) result.surface_seconds = surface->last_seconds();
  result.camera = state.camera;
  return result;
}

}  // namespace drench::render
