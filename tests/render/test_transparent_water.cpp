// `drench render --water transparent` (render/renderer.hpp WaterStyle), headless: a striped cloth behind
// slabs of water written by hand. Through the water the cloth's stripes still show (the pixels follow the
// cloth alone) but tinted: each channel kept as Beer-Lambert's exp(-k d) says for the slab's thickness d,
// red absorbed more than blue, a thicker slab tinting more. The thickness is the ray's length inside the
// water: two slabs one behind the other tint as one slab of their summed thickness, and water behind the
// cloth does not count. A frame without a surface falls back to particles, said once.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_writer.hpp>
#include <drench/render/png_image.hpp>
#include <drench/render/render_run.hpp>
#include <drench/scene/frame_files.hpp>
#include <drench/scene/scene_loader.hpp>
#include "../temp_dir.hpp"
#include "colour_classes.hpp"

namespace drench::render {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// The cloth: ten vertical stripes 2 cm wide with 2 cm gaps, in the plane z = 0 facing the camera on +z, so
// that the pixels along a row alternate between cloth and backdrop. The camera looks straight at it.
constexpr double kStripe = 0.02;
constexpr double kClothHalfHeight = 0.12;
const char* kScene = R"({"fluid": {"particle_spacing": 0.01}, "time": {"frame_rate": 30},
  "camera": {"position": [0, 0, 1], "target": [0, 0, 0], "fov_deg": 30}})";
// In front of the cloth by this much, so that the slab's back face and the cloth do not fight for depth.
constexpr double kGap = 0.004;
constexpr int kWidth = 320, kHeight = 240;
// Stronger than the default (renderer.hpp), so that 1 and 3 cm span a wide range of transmission: red 71 %
// and 36 %, green 94 % and 84 %, blue 99 % and 97 % (pure water's absorption times 100).
const Vec3 kAbsorption(34.0, 5.7, 0.92);

/// Appends the box [lo, hi] (unit: m) to `positions` and `triangles`, 12 triangles wound counter-clockwise
/// seen from outside, as drench's surfaces are.
void add_box(const Vec3& lo, const Vec3& hi, Vec3Array& positions, std::vector<Triangle>& triangles) {
  const auto base = static_cast<Index>(positions.size());
  for (int k = 0; k < 8; ++k)
    positions.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  const std::vector<Triangle> faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const Triangle& t : faces)
    triangles.push_back({base + t[0], base + t[1], base + t[2]});
}

/// A slab of water over the cloth's middle from depth z0 to z1 (unit: m).
void add_slab(double z0, double z1, Vec3Array& positions, std::vector<Triangle>& triangles) {
  add_box(Vec3(-0.15, -0.06, z0), Vec3(0.15, 0.06, z1), positions, triangles);
}

/// The frames: 0 the cloth alone (no surface: its water, none, falls back to particles); 1 a 1 cm slab;
/// 2 a 3 cm slab; 3 a 1 cm and a 2 cm slab with 1 cm of air between; 4 a slab through the cloth from 2 cm
/// behind it to 1 cm in front.
void write_striped_run(const fs::path& dir) {
  fs::create_directories(dir / "frames");
  write_file_atomic((dir / "scene.json").string(), kScene);
  Vec3Array cloth;
  std::vector<Triangle> cloth_triangles;
  for (int i = 0; i < 10; ++i) {
    const double x0 = -0.2 + 2 * kStripe * i, x1 = x0 + kStripe;
    const auto v = static_cast<Index>(cloth.size());
    cloth.insert(cloth.end(), {Vec3(x0, -kClothHalfHeight, 0), Vec3(x1, -kClothHalfHeight, 0),
                               Vec3(x0, kClothHalfHeight, 0), Vec3(x1, kClothHalfHeight, 0)});
    cloth_triangles.push_back({v, v + 1, v + 2});
    cloth_triangles.push_back({v + 1, v + 3, v + 2});
  }
  std::vector<std::pair<Vec3Array, std::vector<Triangle>>> slabs(5);
  add_slab(kGap, kGap + 0.01, slabs[1].first, slabs[1].second);
  add_slab(kGap, kGap + 0.03, slabs[2].first, slabs[2].second);
  add_slab(kGap, kGap + 0.01, slabs[3].first, slabs[3].second);
  add_slab(kGap + 0.02, kGap + 0.04, slabs[3].first, slabs[3].second);
  add_slab(-0.02, 0.01, slabs[4].first, slabs[4].second);
  for (int frame = 0; frame < 5; ++frame) {
    const std::string n = "000" + std::to_string(frame);
    write_mesh_ply((dir / ("frames/cloth_" + n + ".ply")).string(), "cloth", cloth, cloth_triangles);
    write_particles_ply((dir / ("frames/fluid_" + n + ".ply")).string(), ParticleSet());
    if (frame > 0) {
      write_mesh_ply((dir / ("frames/surface_" + n + ".ply")).string(), "surface", slabs[frame].first,
                     slabs[frame].second);
    }
  }
}

RenderOptions striped_render(const fs::path& dir, WaterShading shading, const std::string& out) {
  RenderOptions options;
  options.run_dir = dir.string();
  options.out_dir = (dir / out).string();
  options.width = kWidth;
  options.height = kHeight;
  options.progress = false;
  options.water.shading = shading;
  options.water.absorption = kAbsorption;
  return options;
}

using Rgb = std::array<std::uint8_t, 3>;

/// The pixels along the row through the cloth's middle line (y = 0), one per column over x in
/// [-0.12, 0.12] m, well inside the slabs.
std::vector<Rgb> middle_row(const Image& image, const Camera& camera) {
  const auto left = project_to_pixel(camera, kWidth, kHeight, Vec3(-0.12, 0, 0));
  const auto right = project_to_pixel(camera, kWidth, kHeight, Vec3(0.12, 0, 0));
  const int y = static_cast<int>(left->y());
  std::vector<Rgb> row;
  for (int x = static_cast<int>(left->x()); x <= static_cast<int>(right->x()); ++x)
    row.push_back(image.at(x, y));
  return row;
}

/// Pearson's correlation of one channel along two rows.
double correlation(const std::vector<Rgb>& a, const std::vector<Rgb>& b, int channel) {
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i][channel];
    mb += b[i][channel];
  }
  ma /= a.size();
  mb /= b.size();
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ab += (a[i][channel] - ma) * (b[i][channel] - mb);
    aa += (a[i][channel] - ma) * (a[i][channel] - ma);
    bb += (b[i][channel] - mb) * (b[i][channel] - mb);
  }
  return ab / std::sqrt(aa * bb);
}

/// The columns of `cloth_alone` inside a stripe: the pixel and its two neighbours on each side show cloth,
/// so that the slight shift of refraction stays on the stripe.
std::vector<std::size_t> stripe_interior(const std::vector<Rgb>& cloth_alone) {
  std::vector<std::size_t> columns;
  for (std::size_t i = 2; i + 2 < cloth_alone.size(); ++i) {
    bool inside = true;
    for (std::size_t j = i - 2; j <= i + 2; ++j)
      inside = inside && classify(cloth_alone[j]) == ColourClass::CLOTH;
    if (inside) columns.push_back(i);
  }
  return columns;
}

/// The mean fraction of `channel` that the water lets through on the stripes' interior, Beer-Lambert's
/// exp(-k d): the pixel through the water less the sky it reflects, over the part (1 - F) of the cloth alone
/// that enters the water. Straight on, F is the reflectance head on, ((n - 1) / (n + 1))^2 = 2 % (1 - cos
/// is below 0.01 over the row, which Schlick's fifth power makes nil), and the reflected ray is level: the
/// horizon's colour.
double transmitted(const std::vector<Rgb>& through, const std::vector<Rgb>& alone, int channel) {
  const double n = WaterStyle().refractive_index;
  const double f = ((n - 1) / (n + 1)) * ((n - 1) / (n + 1));
  const double reflected = 255.0 * f * Palette::kSkyHorizon[channel];
  const std::vector<std::size_t> columns = stripe_interior(alone);
  double sum = 0;
  for (std::size_t i : columns)
    sum += (through[i][channel] - reflected) / ((1 - f) * alone[i][channel]);
  return columns.empty() ? 0.0 : sum / columns.size();
}

/// The run written and rendered twice, transparent and opaque; each test is its own process under ctest.
class TransparentWater : public testing::Test {
 protected:
  void SetUp() override {
    write_striped_run(m_dir.path());
    m_result = render_run(striped_render(m_dir.path(), WaterShading::TRANSPARENT, "transparent"));
    m_opaque = render_run(striped_render(m_dir.path(), WaterShading::OPAQUE, "opaque"));
  }
  /// The middle row of frame `frame` of the transparent render, or of the opaque one.
  std::vector<Rgb> row(int frame, bool opaque = false) const {
    return middle_row(image(frame, opaque), m_result.camera);
  }
  Image image(int frame, bool opaque = false) const {
    const fs::path file =
        m_dir.path() / (opaque ? "opaque" : "transparent") / ("frame_000" + std::to_string(frame) + ".png");
    return read_png(file.string());
  }

  TempDir m_dir;
  RenderResult m_result, m_opaque;
};

constexpr int kRed = 0, kGreen = 1, kBlue = 2;

TEST_F(TransparentWater, ShowsTheClothsStripesThroughTheWaterNotTheWatersColour) {
  ASSERT_EQ(m_result.frames, 5);
  const std::vector<Rgb> alone = row(0), thin = row(1), thick = row(2), opaque = row(1, true);
  ASSERT_GE(stripe_interior(alone).size(), 20u) << "the row should cross several stripes";
  // The stripes: the green channel runs from the cloth's (about 80) to the backdrop's (about 225), and
  // through the water it still follows the cloth alone, column for column (r = 1 for an exact copy).
  EXPECT_GT(correlation(alone, thin, kGreen), 0.97);
  EXPECT_GT(correlation(alone, thick, kGreen), 0.95);
  for (std::size_t i : stripe_interior(alone)) {
    // Behind 1 cm the cloth still reads as cloth (red over blue), where the opaque surface is water-blue.
    EXPECT_EQ(classify(thin[i]), ColourClass::CLOTH) << "column " << i;
    EXPECT_EQ(classify(opaque[i]), ColourClass::WATER) << "column " << i;
    // Tinted, not the cloth alone: 1 cm keeps 71 % of its red, some 55 of 190 levels lost.
    EXPECT_GT(int(alone[i][kRed]) - int(thin[i][kRed]), 30) << "column " << i;
  }
}

TEST_F(TransparentWater, KeepsEachChannelAsBeerLambertSaysForTheSlabsThickness) {
  const Vec3& k = kAbsorption;
  const std::vector<Rgb> alone = row(0), thin = row(1), thick = row(2);
  // Straight on, the path through a slab of depth d is d (refraction bends it by under 5 degrees over the
  // row: at most 0.4 % longer). 8-bit rounding moves a pixel by 0.5 of the cloth's 190 levels of red, 90 of
  // green, 40 of blue: tolerances 0.02 for red and green, 0.03 for blue.
  const double red_thin = transmitted(thin, alone, kRed), red_thick = transmitted(thick, alone, kRed);
  EXPECT_NEAR(red_thin, std::exp(-k.x() * 0.01), 0.02);
  EXPECT_NEAR(red_thick, std::exp(-k.x() * 0.03), 0.02);
  // The exponential: three times the thickness, three times the log of what passes (5 %).
  EXPECT_NEAR(std::log(red_thick) / std::log(red_thin), 3.0, 0.15);
  // Water absorbs red most: behind 3 cm 36 % of red passes, 84 % of green, 97 % of blue.
  const double green_thick = transmitted(thick, alone, kGreen), blue_thick = transmitted(thick, alone, kBlue);
  EXPECT_NEAR(green_thick, std::exp(-k.y() * 0.03), 0.02);
  EXPECT_NEAR(blue_thick, std::exp(-k.z() * 0.03), 0.03);
  EXPECT_LT(red_thick + 0.3, green_thick);
  EXPECT_LT(green_thick, blue_thick);
}

TEST_F(TransparentWater, CountsOnlyTheWaterAlongTheRayInFrontOfTheCloth) {
  const std::vector<Rgb> alone = row(0), thick = row(2), two_slabs = row(3), thin = row(1),
                         through_cloth = row(4);
  // 1 cm and 2 cm with air between tint as 3 cm; the air is not water.
  EXPECT_NEAR(transmitted(two_slabs, alone, kRed), transmitted(thick, alone, kRed), 0.01);
  // A slab from 2 cm behind the cloth to 1 cm in front of it tints the cloth as 1 cm does.
  EXPECT_NEAR(transmitted(through_cloth, alone, kRed), transmitted(thin, alone, kRed), 0.01);
}

TEST_F(TransparentWater, SaysOnceWhichFramesHaveNoSurfaceAndDrawsThemAsBefore) {
  EXPECT_EQ(m_result.water_note.find("1 of 5 frames (the first frame_0000) have no surface_NNNN.ply, so "
                                     "their water is drawn as particles"),
            0u)
      << m_result.water_note;
  EXPECT_EQ(m_opaque.water_note, "");
  // Without water the frame is the opaque render's, pixel for pixel.
  EXPECT_EQ(image(0).rgb, image(0, true).rgb);
}

TEST(TransparentWaterSettings, BadOpticsAreNamedAndWriteNothing) {
  TempDir dir;
  write_striped_run(dir.path());
  RenderOptions options = striped_render(dir.path(), WaterShading::TRANSPARENT, "render");
  const auto message = [&]() -> std::string {
    try {
      render_run(options);
    } catch (const Error& e) {
      return e.what();
    }
    return "did not throw";
  };
  options.water.refractive_index = 1.0;
  EXPECT_EQ(message(), "the water's refractive index must be > 1, got 1");
  options.water.refractive_index = 1.33;
  options.water.absorption.y() = -0.5;
  EXPECT_EQ(message(),
            "the water's absorption must be >= 0 1/m in each channel, got -0.5 in channel 1 (0 red, "
            "1 green, 2 blue)");
  EXPECT_FALSE(fs::exists(dir.path() / "render"));
}

TEST(ParseWaterShading, NamesBothChoicesForAnUnknownOne) {
  EXPECT_EQ(parse_water_shading("opaque"), WaterShading::OPAQUE);
  EXPECT_EQ(parse_water_shading("transparent"), WaterShading::TRANSPARENT);
  try {
    parse_water_shading("clear");
    ADD_FAILURE() << "did not throw";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "--water must be opaque or transparent, got \"clear\"");
  }
}

}  // namespace
}  // namespace drench::render
