// The PLY reader against the writer (round trips of particles and meshes), a file from another writer
// (double coordinates, an extra element, CRLF header), and one clear error per kind of bad file.

#include <drench/io/ply_reader.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>

#include <drench/common/error.hpp>
#include <drench/io/ply_writer.hpp>
#include <drench/scene/frame_files.hpp>
#include "../temp_dir.hpp"

namespace drench {
namespace {

/// Passes when parse_ply(bytes, "f.ply") throws an IoError whose message contains `expected`.
testing::AssertionResult parse_error(const std::string& bytes, const std::string& expected) {
  try {
    parse_ply(bytes, "f.ply");
  } catch (const IoError& e) {
    const std::string message = e.what();
    if (message.rfind("f.ply: ", 0) == 0 && message.find(expected) != std::string::npos)
      return testing::AssertionSuccess();
    return testing::AssertionFailure() << "message \"" << message << "\" does not start with \"f.ply: \" "
                                       << "and contain \"" << expected << "\"";
  } catch (const std::exception& e) {
    return testing::AssertionFailure() << "threw another exception type: " << e.what();
  }
  return testing::AssertionFailure() << "did not throw";
}

template <class T>
void append(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

/// A triangle mesh of two faces over four vertices, as drench's writer gives it.
std::string two_triangles() {
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(1, 0.5, 1)};
  return mesh_to_ply("test", positions, {{0, 2, 1}, {1, 2, 3}});
}

TEST(PlyReader, ParticlesRoundTripThroughTheWriterAsFloat32) {
  ParticleSet particles;
  particles.add(Vec3(1.0, -2.0, 0.1), Vec3(0.25, 0.0, -3.0), 0.001, 7);
  particles.add(Vec3(0.0, 0.125, 4.0 / 3.0), Vec3(1.0, 2.0, 3.0), 0.001, 8);
  particles.densities = {998.5, 1001.0};
  particles.pressures = {12.5, 0.0};
  const PlyData data = parse_ply(particles_to_ply(particles), "fluid.ply");
  EXPECT_FALSE(data.has_faces);
  EXPECT_TRUE(data.triangles.empty());
  ASSERT_EQ(data.positions.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(data.positions[i][a], static_cast<double>(static_cast<float>(particles.positions[i][a])));
  }
  EXPECT_NE(data.positions[1].z(), 4.0 / 3.0);  // rounded: the file holds float32
  // The velocities come along (drench render colours particles by speed).
  ASSERT_EQ(data.velocities.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(data.velocities[i][a], static_cast<double>(static_cast<float>(particles.velocities[i][a])));
  }
}

TEST(PlyReader, AMeshHasNoVelocities) {
  EXPECT_TRUE(parse_ply(two_triangles(), "cloth.ply").velocities.empty());
}

TEST(PlyReader, MeshRoundTripsThroughTheWriterToAFile) {
  const test::TempDir dir;
  const std::string path = (dir.path() / "mesh.ply").string();
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(1, 0.5, 1)};
  const std::vector<Triangle> triangles = {{0, 2, 1}, {1, 2, 3}};
  write_mesh_ply(path, "test", positions, triangles);
  const PlyData data = read_ply(path);
  EXPECT_TRUE(data.has_faces);
  EXPECT_EQ(data.positions, positions);  // every coordinate is exact in float32
  EXPECT_EQ(data.triangles, triangles);
}

TEST(PlyReader, ReadsDoublesSkipsOtherElementsAndAcceptsCrlfHeaders) {
  std::string ply =
      "ply\r\nformat binary_little_endian 1.0\r\nobj_info made by hand\r\nelement camera 1\r\n"
      "property uchar a\r\nproperty list uint short b\r\nelement vertex 3\r\nproperty uchar flag\r\n"
      "property double z\r\nproperty double y\r\nproperty double x\r\nelement face 1\r\n"
      "property list uint uint vertex_index\r\nproperty float quality\r\nend_header\r\n";
  append<std::uint8_t>(ply, 1);  // camera: a, then a list b of two shorts
  append<std::uint32_t>(ply, 2);
  append<std::int16_t>(ply, -1);
  append<std::int16_t>(ply, 5);
  for (int i = 0; i < 3; ++i) {
    append<std::uint8_t>(ply, 9);
    append<double>(ply, 0.1 * i);   // z
    append<double>(ply, 1.0 / 3);   // y
    append<double>(ply, -2.0 * i);  // x
  }
  append<std::uint32_t>(ply, 3);
  for (std::uint32_t v : {2u, 1u, 0u})
    append(ply, v);
  append<float>(ply, 0.5f);
  const PlyData data = parse_ply(ply, "f.ply");
  ASSERT_EQ(data.positions.size(), 3u);
  EXPECT_EQ(data.positions[2], Vec3(-4.0, 1.0 / 3, 0.2));  // doubles stay doubles
  ASSERT_EQ(data.triangles.size(), 1u);
  EXPECT_EQ(data.triangles[0], (Triangle{2, 1, 0}));
}

TEST(PlyReader, AnEmptyPointCloudIsFine) {
  const PlyData data = parse_ply(points_to_ply("fluid particles", {}, {}), "f.ply");
  EXPECT_TRUE(data.positions.empty());
  EXPECT_FALSE(data.has_faces);
}

TEST(PlyReader, RejectsWhatIsNotPly) {
  EXPECT_TRUE(parse_error("", "not a PLY file"));
  EXPECT_TRUE(parse_error("{\"scene\": 1}", "not a PLY file"));
  EXPECT_TRUE(parse_error("plyx\n", "not a PLY file"));
}

TEST(PlyReader, RejectsAsciiAndBigEndianByName) {
  EXPECT_TRUE(parse_error("ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
                          "header line 2 (\"format ascii 1.0\"): ascii PLY is not supported"));
  EXPECT_TRUE(parse_error("ply\nformat binary_big_endian 1.0\nend_header\n",
                          "binary_big_endian PLY is not supported"));
  EXPECT_TRUE(parse_error("ply\nelement vertex 0\nend_header\n", "without a format line"));
}

TEST(PlyReader, RejectsMalformedHeaderLinesWithTheirNumber) {
  const std::string start = "ply\nformat binary_little_endian 1.0\n";
  EXPECT_TRUE(parse_error(start + "element vertex -3\nend_header\n", "header line 3"));
  EXPECT_TRUE(parse_error(start + "property float x\nend_header\n", "a property before any element"));
  EXPECT_TRUE(parse_error(start + "element vertex 1\nproperty float128 x\nend_header\n", "unknown type"));
  EXPECT_TRUE(parse_error(start + "elephant 1\nend_header\n", "unknown keyword elephant"));
  EXPECT_TRUE(parse_error(start + "element vertex 1\nproperty float x\n", "no end_header"));
}

TEST(PlyReader, RequiresFloatOrDoubleXyz) {
  const std::string start = "ply\nformat binary_little_endian 1.0\n";
  EXPECT_TRUE(parse_error(start + "element face 0\nproperty list uchar int vertex_indices\nend_header\n",
                          "no vertex element"));
  EXPECT_TRUE(parse_error(start + "element vertex 0\nproperty float x\nproperty float y\nend_header\n",
                          "element vertex has no property z"));
  EXPECT_TRUE(parse_error(
      start + "element vertex 0\nproperty int x\nproperty float y\nproperty float z\nend_header\n",
      "vertex property x must be a float or double"));
  EXPECT_TRUE(parse_error(start + "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                                  "element face 0\nproperty list uchar int vertex_list\nend_header\n",
                          "element face has no list property vertex_indices"));
}

TEST(PlyReader, RejectsTruncatedData) {
  const std::string whole = two_triangles();
  // Cut inside the faces, then inside the vertices.
  EXPECT_TRUE(parse_error(whole.substr(0, whole.size() - 5), "truncated: face 1 of 2 is cut off"));
  const std::size_t body = whole.find("end_header\n") + 11;
  EXPECT_TRUE(
      parse_error(whole.substr(0, body + 30), "truncated: element vertex needs at least 4 x 24 bytes"));
}

TEST(PlyReader, RefusesAnImpossibleCountWithoutAllocatingIt) {
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999999999\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  EXPECT_TRUE(parse_error(ply, "truncated: element vertex needs at least 999999999999999999 x 12 bytes"));
}

TEST(PlyReader, RejectsBytesTheHeaderDoesNotDescribe) {
  EXPECT_TRUE(parse_error(two_triangles() + "xyz", "3 bytes after the last element"));
}

TEST(PlyReader, RejectsAFaceNamingAVertexOutOfRange) {
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)};
  std::string ply = mesh_to_ply("test", positions, {{0, 2, 1}, {0, 1, 2}});
  std::int32_t bad = 3;
  std::memcpy(&ply[ply.size() - 4], &bad, 4);  // the last index of face 1
  EXPECT_TRUE(parse_error(ply, "face 1 names vertex 3, but there are 3 vertices"));
  bad = -1;
  std::memcpy(&ply[ply.size() - 4], &bad, 4);
  EXPECT_TRUE(parse_error(ply, "face 1 names vertex -1, which is out of range"));
}

TEST(PlyReader, RejectsAFaceThatIsNotATriangle) {
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)};
  std::string ply = mesh_to_ply("test", positions, {{0, 2, 1}});
  ply[ply.size() - 13] = 4;  // the face's uchar count
  ply += std::string(4, '\0');
  EXPECT_TRUE(parse_error(ply, "face 0 has 4 vertices; drench reads triangles only"));
}

TEST(PlyReader, RejectsANonFiniteCoordinate) {
  const Vec3Array positions = {Vec3(0, 0, 0), Vec3(1, std::numeric_limits<double>::quiet_NaN(), 0)};
  EXPECT_TRUE(parse_error(points_to_ply("test", positions, {}), "vertex 1 has a non-finite coordinate"));
}

TEST(PlyReader, AMissingFileIsNamed) {
  try {
    read_ply("/nonexistent/drench/fluid_0000.ply");
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/drench/fluid_0000.ply: cannot read"),
              std::string::npos)
        << e.what();
  }
}

// A sparse frame of many gigabytes with a huge vertex count was read whole and allocated for.
TEST(PlyReader, AFileLargerThan4GiBIsRefusedBeforeItIsRead) {
  const test::TempDir dir;
  const std::string path = (dir.path() / "fluid_0000.ply").string();
  write_points_ply(path, "test", {Vec3(0, 0, 0)}, {});
  std::filesystem::resize_file(path, kMaxPlyFileBytes + 1);  // sparse: nothing written
  try {
    read_ply(path);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot read: 4294967297 bytes, more than the 4 GiB"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace drench
