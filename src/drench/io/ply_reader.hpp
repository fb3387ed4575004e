#pragma once
/// Reads back the binary little-endian PLY files drench writes (io/ply_writer.hpp): vertex positions and,
/// when the file has them, velocities and triangles. Other properties (normals, ids) and other elements are
/// skipped, so a PLY from another program reads too as long as it is binary little-endian with float or
/// double x y z.

#include <cstdint>
#include <string>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// What read_ply finds in a file.
struct PlyData {
  Vec3Array positions;  ///< N vertices, x y z as stored (drench writes m), all finite
  /// N velocities vx vy vz as stored (drench writes m/s), all finite, when the vertex element has all three
  /// as float or double (a particle frame); else empty.
  Vec3Array velocities;
  std::vector<Triangle> triangles;  ///< F triangles, indices < N; empty without a `face` element
  bool has_faces = false;           ///< whether the file has a `face` element (a mesh, not a point cloud)
};

/// Parses the bytes of a PLY file.
/// Accepted: `format binary_little_endian 1.0`; a `vertex` element whose x, y and z are `float` or `double`,
/// optionally with vx, vy and vz (read when all three are `float` or `double`, else skipped);
/// optionally a `face` element with a list property `vertex_indices` (or `vertex_index`) of any integer
/// count and index types, every face a triangle; `comment` and `obj_info` lines; any other element or
/// property, which is skipped. Header lines may end in "\n" or "\r\n".
/// @param bytes  the whole file
/// @param name  names the file in messages (its path)
/// @throws IoError "<name>: <problem>" when the bytes are not PLY, the format is ascii or big-endian, a
///         header line is malformed (with its line number), the vertex element or x, y or z is missing, the
///         data is shorter or longer than the header promises, a coordinate or velocity is not finite, a face
///         is not a triangle, or a face names a vertex out of range (with the face's index).
PlyData parse_ply(const std::string& bytes, const std::string& name);

/// Largest PLY file read (unit: bytes): 4 GiB, some 100 million particles as drench writes them (about 40
/// bytes each), far beyond a frame a run can write (`--max-output` is 10 GiB for all of them).
inline constexpr std::uint64_t kMaxPlyFileBytes = std::uint64_t{4} << 30;

/// Reads the file at `path` and parses it as parse_ply does. Only a regular file of at most kMaxPlyFileBytes
/// is opened: a frame replaced by a FIFO blocked `drench render` forever, and /dev/zero or a sparse file of
/// many gigabytes ran it out of memory.
/// @throws IoError naming `path`: the file is not a regular file, is larger than kMaxPlyFileBytes or cannot
///         be read, or any error of parse_ply.
PlyData read_ply(const std::string& path);

}  // namespace drench
