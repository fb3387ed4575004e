#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <drench/common/error.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_writer.hpp>
#include <drench/scene/frame_files.hpp>
#include "../temp_dir.hpp"

namespace drench {
namespace {

TEST(PlyWriter, WritesHeaderAndLittleEndianRecordsThatReadBack) {
  ParticleSet particles;
  particles.add(Vec3(1.0, -2.0, 0.5), Vec3(0.25, 0.0, -3.0), 0.001, 7);
  particles.add(Vec3(0.0, 0.125, 4.0), Vec3(1.0, 2.0, 3.0), 0.001, 4000000000u);
  particles.densities = {998.5, 1001.0};
  particles.pressures = {12.5, 0.0};
  const std::string ply = particles_to_ply(particles);

  const std::string end = "end_header\n";
  const std::size_t body = ply.find(end);
  ASSERT_NE(body, std::string::npos);
  const std::string header = ply.substr(0, body);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("element vertex 2"), std::string::npos);
  EXPECT_NE(header.find("property uint id"), std::string::npos);
  const std::size_t record = 8 * 4 + 4;
  ASSERT_EQ(ply.size(), body + end.size() + 2 * record);

  const char* p = ply.data() + body + end.size() + record;  // second particle
  float values[8];
  std::memcpy(values, p, sizeof values);
  std::uint32_t id;
  std::memcpy(&id, p + 32, 4);
  EXPECT_EQ(values[1], 0.125f);
  EXPECT_EQ(values[2], 4.0f);
  EXPECT_EQ(values[5], 3.0f);
  EXPECT_EQ(values[6], 1001.0f);
  EXPECT_EQ(id, 4000000000u);
}

TEST(PlyWriter, MeshWritesNormalsThenNamedPropertiesPerVertex) {
  // A unit right triangle in the xz plane, counter-clockwise seen from +y: every vertex normal is +y.
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0)};
  const std::vector<Triangle> triangles = {{0, 1, 2}};
  const ScalarArray wetness = {0.0, 0.5, 1.0};
  const std::string ply =
      mesh_to_ply("cloth mesh", positions, triangles, {PlyProperty::scalar("wetness", wetness)});

  const std::string end = "end_header\n";
  const std::size_t body = ply.find(end);
  ASSERT_NE(body, std::string::npos);
  const std::string header = ply.substr(0, body);
  EXPECT_NE(header.find("property float nz\nproperty float wetness\nelement face 1\n"), std::string::npos)
      << header;
  const std::size_t record = 7 * 4;
  ASSERT_EQ(ply.size(), body + end.size() + 3 * record + (1 + 3 * 4));
  float values[7];
  std::memcpy(values, ply.data() + body + end.size() + record, sizeof values);  // second vertex
  EXPECT_EQ(values[2], 1.0f);                                                   // z
  EXPECT_EQ(values[4], 1.0f);                                                   // ny
  EXPECT_EQ(values[6], 0.5f);                                                   // wetness
}

TEST(PlyWriter, APropertyOfTheWrongLengthIsRejectedByName) {
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const ScalarArray short_values = {1.0};
  try {
    points_to_ply("test", positions, {PlyProperty::scalar("pressure", short_values)});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'pressure' has 1 values for 2 vertices"), std::string::npos)
        << e.what();
  }
}

TEST(AtomicFile, ReplacesWholeFileAndLeavesNoTemporary) {
  namespace fs = std::filesystem;
  const test::TempDir temp;
  const fs::path& dir = temp.path();
  const std::string path = (dir / "summary.json").string();
  write_file_atomic(path, "old");
  write_file_atomic(path, "new contents");
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "new contents");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, MissingFolderRaisesIoErrorNamingThePath) {
  try {
    write_file_atomic("/nonexistent-drench-dir/x.ply", "data");
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-drench-dir/x.ply"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace drench
