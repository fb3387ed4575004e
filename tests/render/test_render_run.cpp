// `drench render` (render/render_run.hpp), headless: the cloth's and the water's pixels are where the camera
// puts them (a known point projected, the pixel's colour class checked), on frames written by hand and on a
// short run of the jet scene; the surface replaces the particles; the cloth is shaded on both sides; bad
// input is named and writes nothing; --video says plainly when ffmpeg is missing, and with the real ffmpeg
// writes an MP4 that shows what the PNGs show.

#include <drench/render/render_run.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/common/error.hpp>
#include <drench/common/program.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_reader.hpp>
#include <drench/io/ply_writer.hpp>
#include <drench/render/png_image.hpp>

#include <drench/scene/frame_files.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_runner.hpp>
#include <drench/scene/simulation.hpp>
#include "../temp_dir.hpp"
#include "colour_classes.hpp"

namespace drench::render {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::TempDir;

// The hand-made run: a flat cloth of 0.6 m at y = 0, a ball of water resting on it off-centre, and the
// camera in front and above.
const Vec3 kWaterCentre(0.15, 0.08, 0.0);
const Vec3 kClothPoint(-0.15, 0.0, 0.15);  // clear of the water as the camera sees it
const Vec3 kEmptyPoint(-0.15, 0.25, 0.0);  // nothing there
const Vec3 kStrayParticles(-0.15, 0.1, 0.1);
const char* kCamera = R"({"position": [0, 0.6, 1.2], "target": [0, 0, 0], "fov_deg": 40})";

/// Writes scene.json and two frames: frame 0 the cloth and particles; frame 1 the cloth, the surface (an
/// octahedron around the ball) and particles elsewhere, which must not be drawn since a surface exists.
void write_hand_made_run(const fs::path& dir, const json& scene) {
  fs::create_directories(dir / "frames");
  write_file_atomic((dir / "scene.json").string(), scene.dump(2));
  const int n = 13;
  Vec3Array nodes;
  std::vector<Triangle> triangles;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i)
      nodes.emplace_back(-0.3 + 0.05 * i, 0.0, -0.3 + 0.05 * j);
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const Index v = static_cast<Index>(j * n + i);
      triangles.push_back({v, v + n, v + 1});
      triangles.push_back({v + 1, v + n, v + n + 1});
    }
  }
  ParticleSet ball, stray;
  std::uint32_t id = 0;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) {
      for (int k = -5; k <= 5; ++k) {
        const Vec3 offset = 0.01 * Vec3(i, j, k);
        if (offset.norm() > 0.05) continue;
        ball.add(kWaterCentre + offset, Vec3(0, -1, 0), 0.001, id);
        stray.add(kStrayParticles + 0.4 * offset, Vec3(0, -1, 0), 0.001, id++);
      }
    }
  }
  const Scalar r = 0.05;
  Vec3Array octahedron;
  for (const Vec3& axis :
       {Vec3(r, 0, 0), Vec3(-r, 0, 0), Vec3(0, r, 0), Vec3(0, -r, 0), Vec3(0, 0, r), Vec3(0, 0, -r)})
    octahedron.push_back(kWaterCentre + axis);
  const std::vector<Triangle> faces = {{0, 2, 4}, {4, 2, 1}, {1, 2, 5}, {5, 2, 0},
                                       {4, 3, 0}, {1, 3, 4}, {5, 3, 1}, {0, 3, 5}};
  write_mesh_ply((dir / "frames/cloth_0000.ply").string(), "cloth", nodes, triangles);
  write_particles_ply((dir / "frames/fluid_0000.ply").string(), ball);
  write_mesh_ply((dir / "frames/cloth_0001.ply").string(), "cloth", nodes, triangles);
  write_particles_ply((dir / "frames/fluid_0001.ply").string(), stray);
  write_mesh_ply((dir / "frames/surface_0001.ply").string(), "surface", octahedron, faces);
}

json hand_made_scene(bool with_camera) {
  json scene = json::parse(R"({"fluid": {"particle_spacing": 0.01}, "time": {"frame_rate": 30}})");
  if (with_camera) scene["camera"] = json::parse(kCamera);
  return scene;
}

std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.insert(entry.path().filename().string());
  return names;
}

RenderOptions small_render(const fs::path& run) {
  RenderOptions options;
  options.run_dir = run.string();
  options.width = 320;
  options.height = 180;
  options.progress = false;
  return options;
}

TEST(RenderRun, DrawsClothAndParticlesWhereTheCameraPutsThem) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  const RenderResult result = render_run(small_render(dir.path()));
  EXPECT_EQ(result.frames, 2);
  EXPECT_EQ(result.camera.position, Vec3(0, 0.6, 1.2));  // the scene's camera
  EXPECT_EQ(files_in(dir.path() / "render"), (std::set<std::string>{"frame_0000.png", "frame_0001.png"}));

  const Image image = read_png((dir.path() / "render/frame_0000.png").string());
  EXPECT_EQ(image.width, 320);
  EXPECT_EQ(image.height, 180);
  EXPECT_TRUE(shows(image, result.camera, kWaterCentre, ColourClass::WATER));
  EXPECT_TRUE(shows(image, result.camera, kClothPoint, ColourClass::CLOTH));
  EXPECT_TRUE(shows(image, result.camera, Vec3(0.25, 0.0, -0.25), ColourClass::CLOTH));
  EXPECT_TRUE(shows(image, result.camera, kEmptyPoint, ColourClass::BACKDROP));
  EXPECT_EQ(classify(image.at(0, 0)), ColourClass::BACKDROP);
}

TEST(RenderRun, DrawsTheSurfaceInsteadOfTheParticlesWhereOneExists) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  const RenderResult result = render_run(small_render(dir.path()));
  const Image image = read_png((dir.path() / "render/frame_0001.png").string());
  EXPECT_TRUE(shows(image, result.camera, kWaterCentre, ColourClass::WATER));
  // Frame 1's particles sit above kClothPoint's side of the cloth; the surface replaces them, so there the
  // cloth shows.
  EXPECT_TRUE(shows(image, result.camera, kStrayParticles, ColourClass::CLOTH));
}

TEST(RenderRun, ShadesTheClothOnBothSides) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  RenderOptions options = small_render(dir.path());
  options.camera_json = R"({"position": [0.2, -0.8, 0.9], "target": [0, 0, 0]})";
  const RenderResult result = render_run(options);
  const Image image = read_png((dir.path() / "render/frame_0000.png").string());
  EXPECT_TRUE(shows(image, result.camera, kClothPoint, ColourClass::CLOTH));
  EXPECT_TRUE(shows(image, result.camera, kWaterCentre, ColourClass::CLOTH));  // the water is behind it
}

TEST(RenderRun, FramesTheRunWhenTheSceneHasNoCamera) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(false));
  RenderOptions options = small_render(dir.path());
  options.out_dir = (dir.path() / "elsewhere").string();
  const RenderResult result = render_run(options);
  const Image image = read_png((dir.path() / "elsewhere/frame_0000.png").string());
  EXPECT_TRUE(shows(image, result.camera, kWaterCentre, ColourClass::WATER));
  EXPECT_TRUE(shows(image, result.camera, kClothPoint, ColourClass::CLOTH));
  for (const Vec3& corner :
       {Vec3(-0.3, 0, -0.3), Vec3(0.3, 0, -0.3), Vec3(-0.3, 0, 0.3), Vec3(0.3, 0, 0.3)}) {
    const auto pixel = project_to_pixel(result.camera, 320, 180, corner);
    ASSERT_TRUE(pixel);
    EXPECT_TRUE(pixel->x() > 0 && pixel->x() < 320 && pixel->y() > 0 && pixel->y() < 180)
        << corner.transpose();
  }
}

/// Passes when render_run throws an `Exception` containing `expected` and has written nothing.
template <class Exception>
testing::AssertionResult fails_writing_nothing(const RenderOptions& options, const std::string& expected) {
  const fs::path out = fs::path(options.run_dir) / "render";
  try {
    render_run(options);
  } catch (const Exception& e) {
    const std::string message = e.what();
    if (message.find(expected) == std::string::npos)
      return testing::AssertionFailure()
             << "message \"" << message << "\" does not contain \"" << expected << "\"";
    if (fs::exists(out)) return testing::AssertionFailure() << out << " was created";
    return testing::AssertionSuccess();
  } catch (const std::exception& e) {
    return testing::AssertionFailure() << "threw another exception type: " << e.what();
  }
  return testing::AssertionFailure() << "did not throw";
}

/// A cube of half side `half` about `centre` (unit: m), 12 triangles wound outwards.
void write_box_ply(const fs::path& path, const Vec3& centre, double half) {
  Vec3Array corners;
  for (int k = 0; k < 8; ++k)
    corners.push_back(centre + half * Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1));
  const std::vector<Triangle> faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  write_mesh_ply(path.string(), "bodies", corners, faces);
}

/// The largest difference of a channel between the pixels `point` projects to in two images.
int pixel_difference(const Image& a, const Image& b, const Camera& camera, const Vec3& point) {
  const auto pixel = project_to_pixel(camera, a.width, a.height, point);
  if (!pixel) return -1;
  const auto pa = a.at(static_cast<int>(pixel->x()), static_cast<int>(pixel->y()));
  const auto pb = b.at(static_cast<int>(pixel->x()), static_cast<int>(pixel->y()));
  int most = 0;
  for (int c = 0; c < 3; ++c)
    most = std::max(most, std::abs(int(pa[c]) - int(pb[c])));
  return most;
}

TEST(RenderRun, DrawsEachFramesMovingBodiesWhereThatFrameHasThem) {
  // demos/bullet_playground's balls and crate: a box in empty space, moved between the two frames.
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  const Vec3 there_first = kEmptyPoint, there_then(0.15, 0.25, 0.0);
  write_box_ply(dir.path() / "frames/bodies_0000.ply", there_first, 0.03);
  write_box_ply(dir.path() / "frames/bodies_0001.ply", there_then, 0.03);
  const RenderResult result = render_run(small_render(dir.path()));
  const Image first = read_png((dir.path() / "render/frame_0000.png").string());
  const Image then = read_png((dir.path() / "render/frame_0001.png").string());
  // Where the box is not, the backdrop; where it is, a pixel unlike that backdrop.
  EXPECT_TRUE(shows(then, result.camera, there_first, ColourClass::BACKDROP));
  EXPECT_TRUE(shows(first, result.camera, there_then, ColourClass::BACKDROP));
  EXPECT_GT(pixel_difference(first, then, result.camera, there_first), 20);
  EXPECT_GT(pixel_difference(then, first, result.camera, there_then), 20);

  // A frame without the bodies the others have is refused, naming its file.
  fs::remove_all(dir.path() / "render");
  fs::remove(dir.path() / "frames/bodies_0001.ply");
  EXPECT_TRUE(fails_writing_nothing<IoError>(small_render(dir.path()), "bodies_0001.ply: missing"));
}

TEST(RenderRun, BadInputIsNamedAndWritesNothing) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  RenderOptions options = small_render(dir.path());

  options.camera_json = R"({"positon": [0, 1, 2], "target": [0, 0, 0]})";
  EXPECT_TRUE(fails_writing_nothing<SceneError>(
      options, "camera.positon is not a known key (--camera); known: position, target, fov_deg"));
  options.camera_json = "{position: 1";
  EXPECT_TRUE(fails_writing_nothing<SceneError>(options, "--camera is not valid JSON"));
  options.camera_json = R"({"fov_deg": 30, "fov_deg": 60})";
  EXPECT_TRUE(fails_writing_nothing<SceneError>(options, "--camera: duplicate key \"fov_deg\""));
  options.camera_json.clear();

  options.width = 0;
  EXPECT_TRUE(fails_writing_nothing<Error>(options, "the image size must be at least 1x1 pixels, got 0x180"));
  // 2^31 pixels need about 1e11 bytes of framebuffers: refused before the frames are read, naming --size.
  options.width = 1 << 20;
  options.height = 1 << 11;
  EXPECT_TRUE(fails_writing_nothing<Error>(
      options, "an image of 1048576x2048 pixels needs about 103079215104 bytes for its framebuffers"));
  EXPECT_TRUE(fails_writing_nothing<Error>(options, "choose a smaller size (drench render --size)"));
  options.width = 320;
  options.height = 180;

  json scene = hand_made_scene(false);
  scene["camera"] = {{"fov", 30}};
  write_file_atomic((dir.path() / "scene.json").string(), scene.dump());
  EXPECT_TRUE(fails_writing_nothing<SceneError>(
      options, "camera.fov is not a known key (" + (dir.path() / "scene.json").string() + ")"));
  write_file_atomic((dir.path() / "scene.json").string(), hand_made_scene(true).dump());

  write_file_atomic((dir.path() / "frames/fluid_0002.ply").string(), "ply\nformat ascii 1.0\nend_header\n");
  EXPECT_TRUE(fails_writing_nothing<IoError>(options, "fluid_0002.ply: header line 2"));

  fs::remove_all(dir.path() / "frames");
  fs::create_directories(dir.path() / "frames");
  EXPECT_TRUE(fails_writing_nothing<IoError>(options, "frames: no frames (fluid_NNNN.ply"));
  fs::remove_all(dir.path() / "frames");
  EXPECT_TRUE(fails_writing_nothing<IoError>(options, "frames: missing; drench render reads the frames/"));
  fs::remove(dir.path() / "scene.json");
  EXPECT_TRUE(fails_writing_nothing<IoError>(options, "scene.json: missing"));
}

/// Sets $PATH for the test's lifetime.
class ScopedPath {
 public:
  explicit ScopedPath(const std::string& path) : m_old(std::getenv("PATH") ? std::getenv("PATH") : "") {
    ::setenv("PATH", path.c_str(), 1);
  }
  ~ScopedPath() { ::setenv("PATH", m_old.c_str(), 1); }
  ScopedPath(const ScopedPath&) = delete;
  ScopedPath& operator=(const ScopedPath&) = delete;

 private:
  std::string m_old;
};

TEST(RenderRun, VideoSaysPlainlyThatFfmpegIsMissingAndKeepsThePngs) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  fs::create_directories(dir.path() / "empty_bin");
  RenderOptions options = small_render(dir.path());
  options.video = true;
  const ScopedPath path((dir.path() / "empty_bin").string());
  const RenderResult result = render_run(options);
  EXPECT_EQ(result.video_note,
            "no MP4 written: ffmpeg is not installed (Debian: sudo apt-get install ffmpeg)");
  EXPECT_TRUE(result.video_path.empty());
  EXPECT_EQ(files_in(dir.path() / "render"), (std::set<std::string>{"frame_0000.png", "frame_0001.png"}));
}

TEST(RenderRun, VideoGoesThroughFfmpegAtTheScenesFrameRate) {
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  // A stand-in ffmpeg that records its arguments and writes its output file.
  const fs::path bin = dir.path() / "bin";
  fs::create_directories(bin);
  {
    std::ofstream script(bin / "ffmpeg");
    script << "#!/bin/sh\nfor a; do last=$a; done\necho \"$@\" > \"$last.args\"\nprintf mp4 > \"$last\"\n";
  }
  fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
  RenderOptions options = small_render(dir.path());
  options.video = true;
  const ScopedPath path(bin.string() + ":/usr/bin:/bin");
  const RenderResult result = render_run(options);
  EXPECT_TRUE(result.video_note.empty());
  EXPECT_EQ(result.video_path, (dir.path() / "render/video.mp4").string());
  EXPECT_TRUE(fs::exists(dir.path() / "render/video.mp4"));
  // The arguments went to the temporary name, which was renamed.
  std::string args;
  for (const auto& entry : fs::directory_iterator(dir.path() / "render")) {
    if (entry.path().extension() == ".args") std::getline(std::ifstream(entry.path()), args);
  }
  EXPECT_NE(args.find("-framerate 30 -start_number 0 -i " + (dir.path() / "render/frame_%04d.png").string()),
            std::string::npos)
      << args;
  EXPECT_NE(args.find("-c:v libx264 -pix_fmt yuv420p"), std::string::npos) << args;
}

/// What a program printed on standard output, or "" when it could not be started.
std::string output_of(const std::string& command) {
  std::string text;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe))
      text += buffer;
    ::pclose(pipe);
  }
  return text;
}

// The real ffmpeg (scripts/setup installs it): the MP4 holds every frame at the scene's rate, in the format
// players take, and its first frame, decoded back, shows the water and the cloth where the PNG does.
TEST(RenderRun, VideoThroughTheRealFfmpegHoldsEveryFrameAndShowsTheScene) {
  if (find_program("ffmpeg").empty() || find_program("ffprobe").empty())
    GTEST_SKIP() << "ffmpeg is not installed (Debian: ffmpeg; scripts/setup)";
  TempDir dir;
  write_hand_made_run(dir.path(), hand_made_scene(true));
  RenderOptions options = small_render(dir.path());
  options.video = true;
  const RenderResult result = render_run(options);
  ASSERT_EQ(result.video_path, (dir.path() / "render/video.mp4").string()) << result.video_note;
  const std::string probe = output_of(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=codec_name,pix_fmt,width,height,r_frame_rate,nb_read_frames -of default=nw=1 " +
      result.video_path);
  for (const char* line : {"codec_name=h264", "pix_fmt=yuv420p", "width=320", "height=180",
                           "r_frame_rate=30/1", "nb_read_frames=2"}) {
    EXPECT_NE(probe.find(line), std::string::npos) << line << " not in:\n" << probe;
  }
  const fs::path first = dir.path() / "first.png";
  ASSERT_EQ(
      std::system(("ffmpeg -v error -i " + result.video_path + " -frames:v 1 " + first.string()).c_str()), 0);
  const Image image = read_png(first.string());
  EXPECT_TRUE(shows(image, result.camera, kWaterCentre, ColourClass::WATER));
  EXPECT_TRUE(shows(image, result.camera, kClothPoint, ColourClass::CLOTH));
  EXPECT_TRUE(shows(image, result.camera, kEmptyPoint, ColourClass::BACKDROP));
}

// A real run: the jet scene shortened to 80 steps (the jet has not reached the cloth yet) with a coarser
// cloth, rendered with its default camera. Nodes next to pinned corners are cloth; a point on the jet's axis
// below the nozzle is water.
TEST(RenderRun, AShortJetOnClothRunShowsClothAndWaterWhereTheyAre) {
  TempDir dir;
  const std::string scene_path = DRENCH_SOURCE_DIR "/demos/scenes/jet_on_cloth.json";
  const std::vector<std::string> overrides = {"cloth.nodes=[15,15]", "time.duration=0.08",
                                              "time.frame_rate=25"};
  const SceneConfig config = load_scene_file(scene_path, overrides);
  Simulation simulation(config, bullet::cloth_engine_factory());
  RunOptions run;
  run.out_dir = (dir.path() / "run").string();
  run.progress = false;
  run.scene_document = read_scene_document(scene_path, overrides);
  ASSERT_TRUE(run_scene(simulation, run).status.ok());

  RenderOptions options = small_render(dir.path() / "run");
  options.width = 480;
  options.height = 270;
  const RenderResult result = render_run(options);
  ASSERT_EQ(result.frames, 3);
  const Image image = read_png((dir.path() / "run/render/frame_0002.png").string());
  const PlyData cloth = read_ply((dir.path() / "run/frames/cloth_0002.ply").string());
  const PlyData fluid = read_ply((dir.path() / "run/frames/fluid_0002.ply").string());
  ASSERT_EQ(cloth.positions.size(), 15u * 15u);
  EXPECT_TRUE(shows(image, result.camera, cloth.positions[15 + 1], ColourClass::CLOTH));
  EXPECT_TRUE(shows(image, result.camera, cloth.positions[15 * 15 - 15 - 2], ColourClass::CLOTH));
  // The nozzle (0, 0.3, 0) points down at 3 m/s: after 80 ms the jet fills the axis 5 cm below it.
  const Vec3 on_jet(0.0, 0.25, 0.0);
  const bool particle_there = std::any_of(fluid.positions.begin(), fluid.positions.end(),
                                          [&](const Vec3& p) { return (p - on_jet).norm() < 0.005; });
  ASSERT_TRUE(particle_there);
  EXPECT_TRUE(shows(image, result.camera, on_jet, ColourClass::WATER));
  EXPECT_TRUE(shows(image, result.camera, Vec3(0.0, 0.25, 0.3), ColourClass::BACKDROP));
}

}  // namespace
}  // namespace drench::render
