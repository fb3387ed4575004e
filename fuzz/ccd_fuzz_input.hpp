#pragma once
/// Byte encoding of a point-triangle CCD query for the fuzzer (fuzz_ccd.cpp) and its helper tool
/// (ccd_fuzz_input_tool.cpp). It is built so that libFuzzer's byte mutations land on degenerate queries
/// often: coordinates on a coarse dyadic grid (small integers by default), structure flags that put the point
/// on a vertex or an edge, make the triangle zero-area or static or the whole motion coplanar, and an escape
/// for raw doubles (NaN, infinities, huge and tiny magnitudes). Every byte string decodes to some query.
///
/// Layout; bytes past the end read as 0:
///   byte 0  grid: bits 0-1 pick F in {0, 1, 4, 10}, the grid step is 2^-F; bit 2 set: grid integers are
///           reduced to [-4, 4] (many coinciding coordinates). Other bits are ignored.
///   byte 1  structure flags, applied after the coordinates are read, in this order:
///           bit 0 static triangle (x_t1 = x_t0 for a, b, c)
///           bit 1 the triangle translates rigidly (b and c move as a does)
///           bit 2 static point (p_t1 = p_t0)
///           bit 3 zero-area triangle at t0, bit 4 at t1 (one argument byte each: DegenerateForm)
///           bit 5 point on the triangle's plane at t0, bit 6 at t1 (one argument byte each: a weight of
///                 kPlaneWeights, on a vertex, an edge, inside, or just outside)
///           bit 7 coplanar motion: every z set to a_t0's z (the coplanarity cubic vanishes identically)
///   then 24 coordinates in the order p_t0 a_t0 b_t0 c_t0 p_t1 a_t1 b_t1 c_t1 (x y z each), one byte n each:
///           n != 0x80: the grid value int8(n) * 2^-F
///           n == 0x80: an escape; the next byte k < 16 picks special_values()[k], any other k is followed
///                      by the 8 bytes of a little-endian double, a finite one with its binary exponent
///                      folded into [-kRawExponentLimit, kRawExponentLimit] (see there)
///   then the argument bytes of the structure flags that are set, in flag order.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <drench/ccd/point_triangle_ccd.hpp>

namespace drench::fuzz {

/// Grid fractional bits selected by byte 0, bits 0-1.
inline constexpr std::array<int, 4> kGridFractionBits = {0, 1, 4, 10};
/// Escape byte of a coordinate.
inline constexpr std::uint8_t kEscape = 0x80;
/// Raw finite doubles keep their binary exponent (frexp's, mantissa in [0.5, 1)) in [-this, this], so their
/// magnitudes lie in [2^-65, 2^64). The GMP reference slows down with the bits of the coordinates, by
/// hundreds of times from the unit grid to DBL_MAX, which would starve the fuzzer. The range where the fast
/// solver's double arithmetic overflows (|x| above about 2^340) is therefore left to the unit tests.
inline constexpr int kRawExponentLimit = 64;

/// Values an escape with k < 16 selects: non-finite ones, signed zero, magnitudes at the ends of the raw
/// range and next to 1, and doubles that are not short dyadics.
inline const std::array<double, 16>& special_values() {
  static const std::array<double, 16> values = {
      std::numeric_limits<double>::quiet_NaN(),
      std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(),
      -0.0,
      0x1p-60,
      -0x1p-60,
      0x1p60,
      -0x1p60,
      1.0 + 0x1p-52,
      1.0 - 0x1p-53,
      0x1p-65,               // the smallest raw magnitude
      0x1.fffffffffffffp63,  // the largest raw magnitude
      0.1,
      1.0 / 3.0,
      -0x1.fffffffffffffp63,
      -std::numeric_limits<double>::quiet_NaN(),
  };
  return values;
}

/// Barycentric weights (a, b, c) that the "point on the plane" flags use, picked by argument byte % 16: the
/// three vertices, the three edge midpoints, quarter points on edges, interior points, points on an edge's
/// line outside the triangle, and points 2^-30 outside a vertex or an edge (near misses). All dyadic, so on a
/// grid the combination is exact.
inline constexpr std::array<std::array<double, 3>, 16> kPlaneWeights = {{
    {1.0, 0.0, 0.0},
    {0.0, 1.0, 0.0},
    {0.0, 0.0, 1.0},
    {0.5, 0.5, 0.0},
    {0.0, 0.5, 0.5},
    {0.5, 0.0, 0.5},
    {0.75, 0.25, 0.0},
    {0.0, 0.75, 0.25},
    {0.25, 0.0, 0.75},
    {0.5, 0.25, 0.25},
    {0.25, 0.25, 0.5},
    {-0.25, 1.25, 0.0},
    {0.5, -0.25, 0.75},
    {1.0 + 0x1p-30, -0x1p-30, 0.0},
    {0.5 + 0x1p-30, 0.5, -0x1p-30},
    {0.25, 0.5, 0.25},
}};

/// How the zero-area flags degenerate the triangle, by argument byte % 4.
enum class DegenerateForm : std::uint8_t {
  C_ON_A = 0,         ///< c = a (two coinciding vertices)
  C_ON_B = 1,         ///< c = b
  ALL_ON_A = 2,       ///< b = c = a (a point)
  C_AT_MIDPOINT = 3,  ///< c = (a + b) / 2 (collinear, distinct vertices)
};

/// Reads bytes in order; past the end every byte is 0.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : m_data(data), m_size(size) {}
  std::uint8_t next() { return m_position < m_size ? m_data[m_position++] : 0; }

 private:
  const std::uint8_t* m_data;
  std::size_t m_size;
  std::size_t m_position = 0;
};

/// The eight vertices of a query in encoding order.
inline std::array<Vec3*, 8> query_vertices(ccd::VertexFaceQuery& q) {
  return {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1};
}

/// The 24 coordinates of a query in encoding order (the order of the ccd-vertex-face data files).
inline std::array<double, 24> query_coordinates(const ccd::VertexFaceQuery& query) {
  ccd::VertexFaceQuery copy = query;
  std::array<double, 24> out{};
  const auto vertices = query_vertices(copy);
  for (int v = 0; v < 8; ++v) {
    for (int k = 0; k < 3; ++k)
      out[3 * v + k] = (*vertices[v])[k];
  }
  return out;
}

/// Folds the binary exponent of a finite double into [-kRawExponentLimit, kRawExponentLimit].
inline double fold_exponent(double x) {
  if (!std::isfinite(x) || x == 0.0) return x;
  int exponent = 0;
  const double mantissa = std::frexp(x, &exponent);  // x = mantissa * 2^exponent, |mantissa| in [0.5, 1)
  const int span = 2 * kRawExponentLimit + 1;
  int folded = (exponent + kRawExponentLimit) % span;
  if (folded < 0) folded += span;
  return std::ldexp(mantissa, folded - kRawExponentLimit);
}

inline double decode_coordinate(ByteReader& in, int fraction_bits, bool small_range) {
  const std::uint8_t n = in.next();
  if (n != kEscape) {
    int value = static_cast<std::int8_t>(n);
    if (small_range) value %= 5;
    return std::ldexp(static_cast<double>(value), -fraction_bits);
  }
  const std::uint8_t k = in.next();
  if (k < 16) return special_values()[k];
  std::uint64_t bits = 0;
  for (int i = 0; i < 8; ++i)
    bits |= static_cast<std::uint64_t>(in.next()) << (8 * i);
  double x = 0.0;
  std::memcpy(&x, &bits, sizeof x);
  return fold_exponent(x);
}

inline void make_degenerate(Vec3& a, Vec3& b, Vec3& c, std::uint8_t argument) {
  switch (static_cast<DegenerateForm>(argument % 4)) {
    case DegenerateForm::C_ON_A:
      c = a;
      break;
    case DegenerateForm::C_ON_B:
      c = b;
      break;
    case DegenerateForm::ALL_ON_A:
      b = a;
      c = a;
      break;
    case DegenerateForm::C_AT_MIDPOINT:
      c = 0.5 * (a + b);
      break;
  }
}

inline Vec3 plane_point(const Vec3& a, const Vec3& b, const Vec3& c, std::uint8_t argument) {
  const auto& w = kPlaneWeights[argument % kPlaneWeights.size()];
  return w[0] * a + w[1] * b + w[2] * c;
}

/// Decodes any byte string into a query (see the layout above).
inline ccd::VertexFaceQuery decode_query(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const std::uint8_t grid = in.next();
  const std::uint8_t flags = in.next();
  const int fraction_bits = kGridFractionBits[grid & 3];
  const bool small_range = (grid & 4) != 0;

  ccd::VertexFaceQuery q;
  for (Vec3* vertex : query_vertices(q)) {
    for (int k = 0; k < 3; ++k)
      (*vertex)[k] = decode_coordinate(in, fraction_bits, small_range);
  }
  if (flags & 1) {
    q.a_t1 = q.a_t0;
    q.b_t1 = q.b_t0;
    q.c_t1 = q.c_t0;
  }
  if (flags & 2) {
    const Vec3 d = q.a_t1 - q.a_t0;
    q.b_t1 = q.b_t0 + d;
    q.c_t1 = q.c_t0 + d;
  }
  if (flags & 4) q.p_t1 = q.p_t0;
  if (flags & 8) make_degenerate(q.a_t0, q.b_t0, q.c_t0, in.next());
  if (flags & 16) make_degenerate(q.a_t1, q.b_t1, q.c_t1, in.next());
  if (flags & 32) q.p_t0 = plane_point(q.a_t0, q.b_t0, q.c_t0, in.next());
  if (flags & 64) q.p_t1 = plane_point(q.a_t1, q.b_t1, q.c_t1, in.next());
  if (flags & 128) {
    const double z = q.a_t0.z();
    for (Vec3* vertex : query_vertices(q))
      vertex->z() = z;
  }
  return q;
}

/// Encodes 24 coordinates (encoding order) with no structure flags, so that decode_query gives them back
/// bit for bit: on the coarsest grid that holds every coordinate that fits one, the others as raw doubles
/// (or special values). Coordinates whose exponent is outside the raw range are not representable and come
/// back folded.
inline std::vector<std::uint8_t> encode_coordinates(const std::array<double, 24>& x, std::uint8_t flags = 0,
                                                    const std::vector<std::uint8_t>& arguments = {}) {
  auto grid_integer = [](double value, int fraction_bits, int& n) {
    const double scaled = std::ldexp(value, fraction_bits);
    if (!(std::fabs(scaled) <= 127.0) || scaled != std::nearbyint(scaled)) return false;
    if (value == 0.0 && std::signbit(value)) return false;  // -0.0 is a special value
    n = static_cast<int>(scaled);
    return true;
  };
  // The grid that holds the most coordinates; ties go to the coarser grid.
  int best_grid = 0;
  int best_count = -1;
  for (int g = 0; g < 4; ++g) {
    int count = 0;
    for (double value : x) {
      int n = 0;
      count += grid_integer(value, kGridFractionBits[g], n) ? 1 : 0;
    }
    if (count > best_count) {
      best_count = count;
      best_grid = g;
    }
  }
  std::vector<std::uint8_t> out = {static_cast<std::uint8_t>(best_grid), flags};
  for (double value : x) {
    int n = 0;
    if (grid_integer(value, kGridFractionBits[best_grid], n)) {
      out.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(n)));
      continue;
    }
    out.push_back(kEscape);
    int special = -1;
    for (int k = 0; k < 16; ++k) {
      const double s = special_values()[k];
      if (std::memcmp(&s, &value, sizeof s) == 0) special = k;
    }
    if (special >= 0) {
      out.push_back(static_cast<std::uint8_t>(special));
      continue;
    }
    out.push_back(0xFF);
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    for (int i = 0; i < 8; ++i)
      out.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
  }
  out.insert(out.end(), arguments.begin(), arguments.end());
  return out;
}

}  // namespace drench::fuzz
