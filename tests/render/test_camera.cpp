// The renderer's camera (render/camera.hpp): projection onto pixels, the automatic framing, the viewer's
// orbit, pan and zoom, and PNG files that round-trip through libpng.

#include <drench/render/camera.hpp>

#include <gtest/gtest.h>

#include <drench/common/error.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/render/png_image.hpp>
#include <drench/render/render_run.hpp>
#include "../temp_dir.hpp"

namespace drench::render {
namespace {

TEST(Camera, ProjectsTheTargetToTheImageCentreAndUpToTheTop) {
  Camera camera;
  camera.position = Vec3(0, 0.5, 2);
  camera.target = Vec3(0, 0.5, 0);
  const auto centre = project_to_pixel(camera, 640, 360, camera.target);
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre->x(), 320.0, 1e-9);
  EXPECT_NEAR(centre->y(), 180.0, 1e-9);
  // 45 degrees of vertical field: a point tan(22.5 deg) * 2 m above the target is at the top edge.
  const auto top = project_to_pixel(camera, 640, 360, Vec3(0, 0.5 + 2 * std::tan(M_PI / 8), 0));
  EXPECT_NEAR(top->y(), 0.0, 1e-9);
  // +x is to the right when looking down -z.
  EXPECT_GT(project_to_pixel(camera, 640, 360, Vec3(0.1, 0.5, 0))->x(), 320.0);
  EXPECT_FALSE(project_to_pixel(camera, 640, 360, Vec3(0, 0.5, 3)));  // behind the eye
}

TEST(Camera, OrbitTurnsAboutTheTargetAndStopsShortOfThePole) {
  Camera camera;
  camera.position = Vec3(1, 0.5, 3);
  camera.target = Vec3(1, 0.5, 1);
  orbit(camera, M_PI / 2, 0.0);  // a quarter turn about +y: from +z of the target to its +x
  EXPECT_TRUE(camera.position.isApprox(Vec3(3, 0.5, 1), 1e-12)) << camera.position.transpose();
  EXPECT_TRUE(camera.target.isApprox(Vec3(1, 0.5, 1)));
  orbit(camera, 0.0, M_PI / 6);
  EXPECT_NEAR((camera.position - camera.target).norm(), 2.0, 1e-12);
  EXPECT_NEAR(camera.position.y() - camera.target.y(), 2.0 * std::sin(M_PI / 6), 1e-12);
  orbit(camera, 0.0, M_PI);  // far past straight up: stops at 89 degrees, the image's up still defined
  EXPECT_NEAR(std::asin((camera.position.y() - camera.target.y()) / 2.0), 89.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR((camera.position - camera.target).norm(), 2.0, 1e-12);
}

TEST(Camera, PanKeepsAPointAtTheTargetsDepthUnderTheCursor) {
  Camera camera;
  camera.position = Vec3(0.3, 0.6, 1.2);
  camera.target = Vec3(0, 0, 0);
  const Vec3 point = camera.target;  // at the image's centre before the pan
  pan(camera, 40.0, -25.0, 360);     // the cursor moved 40 pixels right and 25 up
  const auto pixel = project_to_pixel(camera, 640, 360, point);
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 320.0 + 40.0, 1e-6);
  EXPECT_NEAR(pixel->y(), 180.0 - 25.0, 1e-6);
  EXPECT_NEAR((camera.position - camera.target).norm(), Vec3(0.3, 0.6, 1.2).norm(), 1e-12);
}

TEST(Camera, ZoomScalesTheDistanceToTheTargetDownToAMillimetre) {
  Camera camera;
  camera.position = Vec3(0, 0, 2);
  camera.target = Vec3(0, 0, 0.5);
  zoom(camera, 0.5);
  EXPECT_TRUE(camera.position.isApprox(Vec3(0, 0, 1.25), 1e-12)) << camera.position.transpose();
  zoom(camera, 1e-9);
  EXPECT_NEAR((camera.position - camera.target).norm(), 1e-3, 1e-12);
  EXPECT_GT(camera.position.z(), camera.target.z());  // still on the same side
}

TEST(Camera, FramedBoundsTakeTheStageWithTheEmittersElseTheFluid) {
  SceneConfig config;
  EmitterSettings nozzle;
  nozzle.kind = EmitterSettings::Kind::NOZZLE;
  nozzle.nozzle.center = Vec3(0, 0.3, 0);
  config.emitters.push_back(nozzle);
  const Eigen::AlignedBox3d stage(Vec3(-0.3, 0, -0.3), Vec3(0.3, 0, 0.3));
  const Eigen::AlignedBox3d fluid(Vec3(5, 5, 5), Vec3(6, 6, 6));
  const Eigen::AlignedBox3d framed = framed_bounds(config, stage, fluid);
  EXPECT_TRUE(framed.min().isApprox(Vec3(-0.3, 0, -0.3)));
  EXPECT_TRUE(framed.max().isApprox(Vec3(0.3, 0.3, 0.3)));
  EXPECT_TRUE(framed_bounds(config, Eigen::AlignedBox3d(), fluid).isApprox(fluid));
  EXPECT_NEAR(framed_bounds(config, Eigen::AlignedBox3d(), Eigen::AlignedBox3d()).sizes().x(), 1.0, 1e-12);
}

TEST(Camera, LooksStraightDownWithoutDegenerating) {
  Camera camera;
  camera.position = Vec3(0, 2, 0);
  camera.target = Vec3::Zero();
  const auto far_side = project_to_pixel(camera, 100, 100, Vec3(0, 0, -0.5));
  ASSERT_TRUE(far_side);
  EXPECT_TRUE(far_side->allFinite());
  EXPECT_LT(far_side->y(), 50.0);  // -z is the image's up
}

TEST(Camera, TheDefaultFramingShowsEveryCornerOfTheBounds) {
  const Eigen::AlignedBox3d box(Vec3(-0.3, -0.5, -0.3), Vec3(0.3, 0.3, 0.3));
  for (const auto& [width, height] : {std::pair{1280, 720}, std::pair{300, 600}}) {
    const Camera camera = frame_bounds(box, static_cast<double>(width) / height);
    double widest = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const auto pixel = project_to_pixel(camera, width, height,
                                          box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)));
      ASSERT_TRUE(pixel);
      EXPECT_GE(pixel->x(), 0.0);
      EXPECT_LE(pixel->x(), width);
      EXPECT_GE(pixel->y(), 0.0);
      EXPECT_LE(pixel->y(), height);
      widest = std::max({widest, std::abs(pixel->x() - 0.5 * width) / (0.5 * width),
                         std::abs(pixel->y() - 0.5 * height) / (0.5 * height)});
    }
    EXPECT_GT(widest, 0.85);  // framed, not lost in the middle
  }
}

TEST(Camera, SceneSettingsWithoutAPositionKeepTheFramingAndTheirFieldOfView) {
  const Eigen::AlignedBox3d box(Vec3(-1, -1, -1), Vec3(1, 1, 1));
  CameraSettings settings;
  settings.fov_deg = 30;
  EXPECT_EQ(resolve_camera(settings, box, 1.5).position, frame_bounds(box, 1.5, 30).position);
  settings.position = Vec3(1, 2, 3);
  settings.target = Vec3(0, 1, 0);
  const Camera camera = resolve_camera(settings, box, 1.5);
  EXPECT_EQ(camera.position, Vec3(1, 2, 3));
  EXPECT_EQ(camera.target, Vec3(0, 1, 0));
  EXPECT_EQ(camera.fov_deg, 30.0);
}

TEST(PngImage, RoundTripsThroughLibpng) {
  Image image;
  image.width = 3;
  image.height = 2;
  image.rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 20, 30, 40, 50, 60, 70, 80, 90};
  const test::TempDir dir;
  const std::string path = (dir.path() / "image.png").string();
  write_file_atomic(path, encode_png(image));
  const Image back = read_png(path);
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_EQ(back.at(0, 1), (std::array<std::uint8_t, 3>{10, 20, 30}));
}

TEST(ImageSize, ParsesWidthByHeightAndRejectsZeroAndJunk) {
  int width = 0, height = 0;
  parse_image_size("1280x720", width, height);
  EXPECT_EQ(width, 1280);
  EXPECT_EQ(height, 720);
  for (const char* bad : {"0x720", "1280x0", "1280", "x720", "12a0x720", "-1x5", "20000x10", "1280x720x3"}) {
    try {
      parse_image_size(bad, width, height);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--size must be WIDTHxHEIGHT")), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace drench::render
