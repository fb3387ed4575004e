#include <drench/ccd/point_triangle_ccd.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/common/triangle_geometry.hpp>

// Method: a certified floating-point filter in Bernstein form, with the exact rational reference as fallback.
//
// Why this and not a plain cubic solver: Provot's solver (and the paper's eq. 6 solved in floating point)
// finds the roots of the coplanarity cubic and then tests the point against the triangle with a tolerance;
// both steps round, and the published counts on the benchmark this project is tested on are 16 + 12 missed
// collisions. Tight-Inclusion (Wang et al. 2021) never misses but needs a tolerance and reports every near
// miss. Here the decision is exact: with separation 0 and touching counted, it agrees with rational
// arithmetic on every input.
//
// The contact condition at time t is: f(t) = 0 (eq. 6) and g_a, g_b, g_c >= 0 (the point inside the closed
// triangle), with n = (b - a) x (c - a), f = (p - a).n and g_a = ((b - p) x (c - p)).n, etc. (g_a / |n|^2 is
// the barycentric weight of a when the point is in the plane). The vertices move linearly, so the Bernstein
// coefficients on [0, 1] of every difference are the differences at t0 and t1; f is a cubic and the g's are
// quartics, built by Bernstein products (Farouki & Rajan 1988). Every coefficient carries a rigorous bound on
// its rounding error (running error analysis, Higham 2002 sec. 3.3), so "all coefficients > their error"
// proves the polynomial positive on the interval (convex hull property). The filter walks [0, 1] left to
// right, halving intervals by de Casteljau's algorithm:
//   - f certainly one-signed, or some g certainly negative: no contact in the interval, skip it;
//   - f certainly changes sign between the ends and every g certainly positive: a contact, the earliest one
//   since
//     everything to the left was skipped; halve until the interval is narrower than the toi tolerance;
//   - neither: halve, until the interval budget runs out; then the exact reference decides from that time on.
// The fallback takes the queries that are degenerate or within rounding of degenerate: contact exactly on an
// edge or a vertex, a tangential (double) root, motion inside the triangle's plane, zero-area triangles,
// roots exactly at t = 0 or 1. Those are where floating-point solvers miss (Brochu, Edwards, Bridson 2012
// make the same observation and go exact everywhere; Wang et al. 2021 list them as the hard cases of their
// benchmark).

namespace drench::ccd {
namespace {

constexpr double kUnitRoundoff = 0x1p-53;
// The error bounds are themselves computed in floating point; this factor and the absolute term cover the
// roundings of that computation and any underflow (at most 2^-1075 per operation), with a wide margin. The
// absolute term is far above the subnormal range on purpose: error terms are multiplied together, and a
// subnormal operand or result costs ~100 cycles per operation on x86 (a microcode assist), which made the
// filter four times slower (bench_ccd). The price: values below ~1e-150 (lengths below ~1e-30 m) are left to
// the exact reference.
constexpr double kGrow = 1.0 + 0x1p-45;
constexpr double kTiny = 0x1p-500;

/// A computed value and a bound on its distance to the exact value.
struct Ev {
  double v;
  double e;
};

inline Ev exact(double v) {
  return {v, 0.0};
}

inline double bound(double terms, double result) {
  return (terms + kUnitRoundoff * std::abs(result)) * kGrow + kTiny;
}

inline Ev operator+(Ev a, Ev b) {
  const double s = a.v + b.v;
  return {s, bound(a.e + b.e, s)};
}

inline Ev operator-(Ev a, Ev b) {
  const double s = a.v - b.v;
  return {s, bound(a.e + b.e, s)};
}

inline Ev operator*(Ev a, Ev b) {
  const double m = a.v * b.v;
  return {m, bound(std::abs(a.v) * b.e + std::abs(b.v) * a.e + a.e * b.e, m)};
}

/// Division by a small positive integer constant.
inline Ev divide(Ev a, double d) {
  const double q = a.v / d;
  return {q, bound(a.e / d, q)};
}

/// Midpoint of two values: the de Casteljau step at 1/2.
inline Ev midpoint(Ev a, Ev b) {
  const double m = 0.5 * (a.v + b.v);
  return {m, bound(0.5 * (a.e + b.e), m)};
}

using V3 = std::array<Ev, 3>;

inline V3 operator+(const V3& a, const V3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline V3 half(const V3& a) {
  return {divide(a[0], 2.0), divide(a[1], 2.0), divide(a[2], 2.0)};
}

inline V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

inline Ev dot(const V3& a, const V3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// Difference y - x of two vertices as a linear vector polynomial: its Bernstein coefficients at t0 and t1.
inline std::array<V3, 2> difference(const Vec3& x_t0, const Vec3& x_t1, const Vec3& y_t0, const Vec3& y_t1) {
  std::array<V3, 2> d;
  for (int k = 0; k < 3; ++k) {
    d[0][k] = exact(y_t0[k]) - exact(x_t0[k]);
    d[1][k] = exact(y_t1[k]) - exact(x_t1[k]);
  }
  return d;
}

/// Cross product of two linear vector polynomials: a quadratic, in Bernstein form.
inline std::array<V3, 3> cross(const std::array<V3, 2>& u, const std::array<V3, 2>& w) {
  return {cross(u[0], w[0]), half(cross(u[0], w[1]) + cross(u[1], w[0])), cross(u[1], w[1])};
}

/// Bernstein coefficients of a polynomial of degree N - 1 on the current interval.
template <std::size_t N>
using Bernstein = std::array<Ev, N>;

/// Quadratic times linear (dot product): a cubic.
inline Bernstein<4> dot(const std::array<V3, 3>& q, const std::array<V3, 2>& r) {
  const Ev two_q1r0 = dot(q[1], r[0]) + dot(q[1], r[0]);
  const Ev two_q1r1 = dot(q[1], r[1]) + dot(q[1], r[1]);
  return {dot(q[0], r[0]), divide(two_q1r0 + dot(q[0], r[1]), 3.0), divide(dot(q[2], r[0]) + two_q1r1, 3.0),
          dot(q[2], r[1])};
}

/// Quadratic times quadratic (dot product): a quartic.
inline Bernstein<5> dot(const std::array<V3, 3>& q, const std::array<V3, 3>& s) {
  const Ev q1s1 = dot(q[1], s[1]);
  const Ev four_q1s1 = q1s1 + q1s1 + q1s1 + q1s1;
  return {dot(q[0], s[0]), divide(dot(q[0], s[1]) + dot(q[1], s[0]), 2.0),
          divide(dot(q[0], s[2]) + four_q1s1 + dot(q[2], s[0]), 6.0),
          divide(dot(q[1], s[2]) + dot(q[2], s[1]), 2.0), dot(q[2], s[2])};
}

template <std::size_t N>
bool certainly_positive(const Bernstein<N>& b) {
  for (const Ev& c : b) {
    if (!(c.v - c.e > 0.0)) return false;
  }
  return true;
}

template <std::size_t N>
bool certainly_negative(const Bernstein<N>& b) {
  for (const Ev& c : b) {
    if (!(c.v + c.e < 0.0)) return false;
  }
  return true;
}

inline int certain_sign(const Ev& c) {
  if (c.v - c.e > 0.0) return 1;
  if (c.v + c.e < 0.0) return -1;
  return 0;
}

/// de Casteljau at 1/2: the coefficients on the left and right halves.
template <std::size_t N>
void subdivide(const Bernstein<N>& b, Bernstein<N>& left, Bernstein<N>& right) {
  Bernstein<N> work = b;
  for (std::size_t level = 0; level < N; ++level) {
    left[level] = work[0];
    right[N - 1 - level] = work[N - 1 - level];
    for (std::size_t k = 0; k + 1 + level < N; ++k)
      work[k] = midpoint(work[k], work[k + 1]);
  }
}

/// de Casteljau at the fraction r of the interval (r and 1 - r exact doubles).
template <std::size_t N>
void subdivide_at(const Bernstein<N>& b, double r, Bernstein<N>& left, Bernstein<N>& right) {
  Bernstein<N> work = b;
  for (std::size_t level = 0; level < N; ++level) {
    left[level] = work[0];
    right[N - 1 - level] = work[N - 1 - level];
    for (std::size_t k = 0; k + 1 + level < N; ++k)
      work[k] = exact(1.0 - r) * work[k] + exact(r) * work[k + 1];
  }
}

// A split point must be exactly the double the Bernstein coefficients were subdivided at; deep enough into
// [0, 1] a midpoint no longer fits in a double, and the filter hands over to the exact reference there.
bool exact_split(double lo, double mid, double hi, double r) {
  return lo < mid && mid < hi && mid - lo == r * (hi - lo) && hi - mid == (1.0 - r) * (hi - lo);
}

// When eq. 6 vanishes exactly at a midpoint (hand-built and symmetric scenes put roots at t = 1/2, 1/4, ...),
// no error bound can certify its sign there, so the root's side is unknown. Splitting a little off the middle
// instead puts the root strictly inside one half, where the sign change is certain.
constexpr double kOffCentre = 63.0 / 128.0;

/// Deepest level of halving; 2^-60 of the step is far below what a double time near 1 resolves anyway.
constexpr int kMaxDepth = 60;

/// The filter's polynomials on one interval [t_lo, t_hi] of the step.
struct Span {
  double t_lo, t_hi;
  Bernstein<4> f;                 // coplanarity, eq. 6
  std::array<Bernstein<5>, 3> g;  // inside tests of the vertices a, b, c

  void split(Span& left, Span& right) const {
    const double mid = 0.5 * (t_lo + t_hi);
    left.t_lo = t_lo;
    left.t_hi = mid;
    right.t_lo = mid;
    right.t_hi = t_hi;
    subdivide(f, left.f, right.f);
    for (int i = 0; i < 3; ++i)
      subdivide(g[i], left.g[i], right.g[i]);
  }
};

/// Coplanarity cubic (eq. 6) on [0, 1]; `n` receives the triangle normal's Bernstein coefficients.
Bernstein<4> coplanarity(const VertexFaceQuery& q, std::array<V3, 3>& n) {
  n = cross(difference(q.a_t0, q.a_t1, q.b_t0, q.b_t1), difference(q.a_t0, q.a_t1, q.c_t0, q.c_t1));
  return dot(n, difference(q.a_t0, q.a_t1, q.p_t0, q.p_t1));
}

/// det[u; v; w] in plain floating point and a bound on its rounding error: u, v, w are differences of input
/// doubles (one rounding each, relative u) and each of the six terms adds at most 5 more roundings, their sum
/// 3: |error| <= 16 u sum |terms| covers it with a margin (Shewchuk 1997's orient3d bound is 7.8 u for exact
/// inputs), and the absolute term any underflow.
struct PlainDet {
  double value;
  double error;
};

PlainDet plain_det3(const Vec3& u, const Vec3& v, const Vec3& w) {
  const double t[6] = {u.x() * v.y() * w.z(), u.y() * v.z() * w.x(), u.z() * v.x() * w.y(),
                       u.z() * v.y() * w.x(), u.x() * v.z() * w.y(), u.y() * v.x() * w.z()};
  const double value = ((t[0] + t[1]) + t[2]) - ((t[3] + t[4]) + t[5]);
  double magnitude = 0.0;
  for (const double x : t)
    magnitude += std::abs(x);
  return {value, 16.0 * kUnitRoundoff * magnitude + kTiny};
}

/// True when eq. 6, f(t) = det[b - a, c - a, p - a](t), certainly keeps one sign on [0, 1], decided in plain
/// floating point with a certified bound before the filter's running error analysis: its Bernstein
/// coefficients (from the blossom of the trilinear determinant; for a triangle that does not move, f is
/// linear and its two ends decide) are all certainly of that sign. Then the point never reaches the
/// triangle's plane: no contact. Most queries of a step end here (a particle near a face, not crossing its
/// plane), and the filter's error-tracked cubic cost several times more (issue 41's game frame, where every
/// fluid sub-step tests the particles against the cloth at rest, coupling/cloth_obstacle.hpp).
bool certainly_one_signed(const VertexFaceQuery& q) {
  const Vec3 b0 = q.b_t0 - q.a_t0, c0 = q.c_t0 - q.a_t0, p0 = q.p_t0 - q.a_t0;
  const Vec3 b1 = q.b_t1 - q.a_t1, c1 = q.c_t1 - q.a_t1, p1 = q.p_t1 - q.a_t1;
  const auto one_signed = [](const double* coef, const double* err, int count) {
    bool positive = true, negative = true;
    for (int k = 0; k < count; ++k) {
      // The sums of determinants round too: a further 3 u of their magnitude, covered by the growth.
      const double margin = err[k] * kGrow + 4.0 * kUnitRoundoff * std::abs(coef[k]);
      positive = positive && coef[k] > margin;
      negative = negative && coef[k] < -margin;
    }
    return positive || negative;
  };
  if (q.a_t0 == q.a_t1 && q.b_t0 == q.b_t1 && q.c_t0 == q.c_t1) {
    const PlainDet d0 = plain_det3(b0, c0, p0), d1 = plain_det3(b0, c0, p1);
    const double coef[2] = {d0.value, d1.value}, err[2] = {d0.error, d1.error};
    return one_signed(coef, err, 2);
  }
  // The eight determinants det[b, c, p] = p . (b x c) share their cross products: four of them and six dot
  // products give the coefficients (times 3). Along every term the inputs round once (the differences), a
  // cross product twice and the sum of two once, a dot product three times, the last sum or the factor 3
  // once: at most 10 roundings, so 10 u (1 + 10 u) of the terms' magnitude bounds the error, and 16 u covers
  // it and the rounding of the magnitudes. In plain doubles (Eigen's small temporaries cost a third more
  // here), this is half the instructions of eight determinants with their own bounds (issue 41).
  using D3 = std::array<double, 3>;
  const auto cross = [](const D3& u, const D3& v) {
    return D3{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  const auto abs_cross = [](const D3& u, const D3& v) {  // of absolute values: the terms' magnitudes
    return D3{u[1] * v[2] + u[2] * v[1], u[2] * v[0] + u[0] * v[2], u[0] * v[1] + u[1] * v[0]};
  };
  const auto dot = [](const D3& u, const D3& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  const auto sum = [](const D3& u, const D3& v) { return D3{u[0] + v[0], u[1] + v[1], u[2] + v[2]}; };
  const auto d3 = [](const Vec3& v) { return D3{v[0], v[1], v[2]}; };
  const auto abs3 = [](const D3& v) { return D3{std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}; };
  const D3 b0_ = d3(b0), c0_ = d3(c0), p0_ = d3(p0), b1_ = d3(b1), c1_ = d3(c1), p1_ = d3(p1);
  const D3 n00 = cross(b0_, c0_), n11 = cross(b1_, c1_), mixed = sum(cross(b0_, c1_), cross(b1_, c0_));
  const double coef[4] = {3 * dot(p0_, n00), dot(p0_, mixed) + dot(p1_, n00), dot(p1_, mixed) + dot(p0_, n11),
                          3 * dot(p1_, n11)};
  // Mixed signs: eq. 6 may vanish, nothing to certify.
  const bool all_positive = coef[0] > 0.0 && coef[1] > 0.0 && coef[2] > 0.0 && coef[3] > 0.0;
  const bool all_negative = coef[0] < 0.0 && coef[1] < 0.0 && coef[2] < 0.0 && coef[3] < 0.0;
  if (!all_positive && !all_negative) return false;
  // One bound for all four first, from the largest coordinates: the six terms of det[b, c, p] sum in
  // magnitude to at most 2 |p|_1 |b|_inf |c|_inf, and a coefficient (times 3) holds three determinants. It
  // decides nearly every query the bounds per coefficient below would (a particle near a face, far from its
  // plane compared with rounding), for a quarter of their cost.
  const auto max3 = [](const D3& v) { return std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}); };
  const auto sum3 = [](const D3& v) { return std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]); };
  const double largest =
      std::max(sum3(p0_), sum3(p1_)) * std::max(max3(b0_), max3(b1_)) * std::max(max3(c0_), max3(c1_));
  const double margin = 16.0 * kUnitRoundoff * 6.0 * largest * kGrow + kTiny;
  if (std::abs(coef[0]) > margin && std::abs(coef[1]) > margin && std::abs(coef[2]) > margin &&
      std::abs(coef[3]) > margin) {
    return true;
  }
  const D3 ab0 = abs3(b0_), ac0 = abs3(c0_), ap0 = abs3(p0_), ab1 = abs3(b1_), ac1 = abs3(c1_),
           ap1 = abs3(p1_);
  const D3 m00 = abs_cross(ab0, ac0), m11 = abs_cross(ab1, ac1),
           m_mixed = sum(abs_cross(ab0, ac1), abs_cross(ab1, ac0));
  const double magnitude[4] = {3 * dot(ap0, m00), dot(ap0, m_mixed) + dot(ap1, m00),
                               dot(ap1, m_mixed) + dot(ap0, m11), 3 * dot(ap1, m11)};
  for (int k = 0; k < 4; ++k) {
    if (!(std::abs(coef[k]) > 16.0 * kUnitRoundoff * magnitude[k] * kGrow + kTiny)) return false;
  }
  return true;
}

/// True when the point is certainly outside the triangle at every time of the step, beyond one of its edges:
/// for a fixed direction d (an edge's outward normal in the triangle's plane at t0 or at t1), d . (p - v) > 0
/// for every vertex v at both ends. Each d . (p(t) - v(t)) is linear in t, so its ends decide it on [0, 1]:
/// the point is then beyond the whole triangle along d at every time, and cannot touch it. Any d serves (it
/// need not be the exact normal), so only the dot products and the differences in them round, by at most
/// 4 u of their terms' magnitude, covered twice. A particle crossing the plane of a face beside it (a curved
/// cloth, a faceted ball) is decided here, before the error-tracked cubic and the quartic inside tests,
/// which were most of the filter's time in issue 41's game frame. The leak audit keeps its own copies of
/// this test and certainly_one_signed on purpose (coupling/leak_audit.cpp): it checks the coupler.
bool certainly_beside(const VertexFaceQuery& q) {
  const Vec3* ends[2][4] = {{&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0}, {&q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1}};
  for (const auto& frame : ends) {
    const Vec3 normal = (*frame[2] - *frame[1]).cross(*frame[3] - *frame[1]);
    for (int e = 0; e < 3; ++e) {
      const Vec3 d = (*frame[1 + (e + 1) % 3] - *frame[1 + e]).cross(normal);  // away from the third vertex
      bool beside = true;
      for (int end = 0; end < 2 && beside; ++end) {
        for (int v = 1; v <= 3 && beside; ++v) {
          const Vec3 diff = *ends[end][0] - *ends[end][v];
          const double margin = 8.0 * kUnitRoundoff * d.cwiseAbs().dot(diff.cwiseAbs()) + kTiny;
          beside = d.dot(diff) > margin;
        }
      }
      if (beside) return true;
    }
  }
  return false;
}

/// The inside tests on [0, 1], given the normal's coefficients.
std::array<Bernstein<5>, 3> inside_tests(const VertexFaceQuery& q, const std::array<V3, 3>& n) {
  const auto pa = difference(q.p_t0, q.p_t1, q.a_t0, q.a_t1);
  const auto pb = difference(q.p_t0, q.p_t1, q.b_t0, q.b_t1);
  const auto pc = difference(q.p_t0, q.p_t1, q.c_t0, q.c_t1);
  return {dot(cross(pb, pc), n), dot(cross(pc, pa), n), dot(cross(pa, pb), n)};
}

template <std::size_t N>
bool all_finite(const Bernstein<N>& b) {
  for (const Ev& c : b) {
    if (!std::isfinite(c.v) || !std::isfinite(c.e)) return false;
  }
  return true;
}

/// f divided by t (when f(0) = 0 exactly) or by 1 - t (when f(1) = 0), degree-elevated back to a cubic. The
/// quotient has the sign of f inside (0, 1) and usually no zero at that end, so the filter can certify it
/// there.
Bernstein<4> deflate(const Bernstein<4>& b, bool at_end) {
  const Ev three = exact(3.0);
  const Ev three_halves = exact(1.5);
  const std::array<Ev, 3> q = at_end ? std::array<Ev, 3>{b[0], three_halves * b[1], three * b[2]}
                                     : std::array<Ev, 3>{three * b[1], three_halves * b[2], b[3]};
  return {q[0], divide(q[0] + exact(2.0) * q[1], 3.0), divide(exact(2.0) * q[1] + q[2], 3.0), q[2]};
}

/// A point that starts on a vertex (a mesh vertex tested against its own triangle, or a particle resting on
/// a node) touches at t = 0: decided by exact comparison, before any rounding. True and `r` set when so.
bool starts_on_vertex(const VertexFaceQuery& q, CcdResult& r) {
  const std::array<const Vec3*, 3> vertices_t0 = {&q.a_t0, &q.b_t0, &q.c_t0};
  for (int i = 0; i < 3; ++i) {
    if (q.p_t0 == *vertices_t0[i]) {
      r = CcdResult{};
      r.hit = true;
      r.toi = 0.0;
      r.barycentric[i] = 1.0;
      return true;
    }
  }
  return false;
}

enum class Verdict { NO_CONTACT, CONTACT, UNDECIDED };

Verdict classify(const Span& s) {
  if (certainly_positive(s.f) || certainly_negative(s.f)) return Verdict::NO_CONTACT;
  for (const auto& gi : s.g) {
    if (certainly_negative(gi)) return Verdict::NO_CONTACT;
  }
  const int sign_lo = certain_sign(s.f.front());
  const int sign_hi = certain_sign(s.f.back());
  if (sign_lo * sign_hi < 0 && certainly_positive(s.g[0]) && certainly_positive(s.g[1]) &&
      certainly_positive(s.g[2])) {
    return Verdict::CONTACT;
  }
  return Verdict::UNDECIDED;
}

/// Walks the spans of `root` depth-first, left half first, so in time order: skips the spans classify
/// certifies free of contact, and returns on_contact(span) at the first it certifies a contact in, or
/// on_undecided(span) at the first it cannot split further (over `budget` splits, kMaxDepth, or a midpoint
/// that does not split exactly); nullopt when every span is free. The stack holds at most one pending right
/// half per level, so its size bounds the depth.
template <class OnContact, class OnUndecided>
auto walk_spans(const Span& root, int budget, OnContact on_contact, OnUndecided on_undecided)
    -> std::optional<decltype(on_contact(root))> {
  std::array<Span, kMaxDepth + 1> stack;
  std::array<int, kMaxDepth + 1> depth;
  int top = 0;
  stack[top] = root;
  depth[top++] = 0;
  for (int splits = 0; top > 0;) {
    --top;
    const Verdict verdict = classify(stack[top]);
    if (verdict == Verdict::NO_CONTACT) continue;
    if (verdict == Verdict::CONTACT) return on_contact(stack[top]);
    const Span s = stack[top];
    const int d = depth[top];
    if (++splits > budget || d >= kMaxDepth || !exact_split(s.t_lo, 0.5 * (s.t_lo + s.t_hi), s.t_hi, 0.5)) {
      return on_undecided(s);
    }
    s.split(stack[top + 1], stack[top]);  // right half below, left half on top
    depth[top++] = d + 1;
    depth[top++] = d + 1;
  }
  return std::nullopt;
}

Vec3 at(const Vec3& x_t0, const Vec3& x_t1, double t) {
  return (1.0 - t) * x_t0 + t * x_t1;
}

CcdResult contact_at(const VertexFaceQuery& q, double toi, CcdPath path) {
  CcdResult r;
  r.hit = true;
  r.toi = std::clamp(toi, 0.0, 1.0);
  r.path = path;
  r.barycentric = closest_point_barycentric(at(q.p_t0, q.p_t1, r.toi), at(q.a_t0, q.a_t1, r.toi),
                                            at(q.b_t0, q.b_t1, r.toi), at(q.c_t0, q.c_t1, r.toi));
  return r;
}

CcdResult exact_from(const VertexFaceQuery& q, double t_from, const CcdSettings& settings) {
  const ExactCcdResult exact = point_triangle_ccd_exact(q, t_from, settings.toi_tolerance);
  if (!exact.hit) {
    CcdResult r;
    r.path = CcdPath::EXACT;
    return r;
  }
  return contact_at(q, exact.toi_lower, CcdPath::EXACT);
}

/// The earliest contact in a span classified CONTACT: every g is positive on the whole span, so it is the
/// first root of f there. Halves f alone (g stays positive on every sub-interval) until the span is narrower
/// than the toi tolerance; hands over to the exact reference if rounding hides which half holds the first
/// root. Bisection for the single root of a cubic that is certainly monotone on the span: point values
/// suffice, in plain double with one error bound for all of them, so each step costs a dozen flops instead of
/// a subdivision with error tracking. Returns false when rounding hides the sign at a bisection point.
bool bisect_monotone(const Span& s, double toi_tolerance, double& toi) {
  for (std::size_t i = 0; i + 1 < s.f.size(); ++i) {
    if (certain_sign(s.f[i + 1] - s.f[i]) * certain_sign(s.f[1] - s.f[0]) <= 0) return false;
  }
  double max_error = 0.0;
  double max_value = 0.0;
  for (const Ev& c : s.f) {
    max_error = std::max(max_error, c.e);
    max_value = std::max(max_value, std::abs(c.v));
  }
  // de Casteljau at an exact r in [0, 1] is three levels of convex combinations (1 - r is exact for the
  // dyadic r used here): each level adds at most 2 roundings of the largest coefficient.
  const double bound = (max_error + 8.0 * kUnitRoundoff * max_value) * kGrow + kTiny;
  const int sign_lo = certain_sign(s.f.front());
  const double width = s.t_hi - s.t_lo;
  double r_lo = 0.0;
  double r_hi = 1.0;
  while ((r_hi - r_lo) * width > 0.5 * toi_tolerance) {  // half: leaves room for the rounding below
    const double r = 0.5 * (r_lo + r_hi);
    if (!(r_lo < r && r < r_hi)) return false;
    std::array<double, 4> b = {s.f[0].v, s.f[1].v, s.f[2].v, s.f[3].v};
    for (int level = 3; level > 0; --level) {
      for (int k = 0; k < level; ++k)
        b[k] = (1.0 - r) * b[k] + r * b[k + 1];
    }
    if (std::abs(b[0]) <= bound) return false;
    if ((b[0] > 0.0 ? 1 : -1) == sign_lo) {
      r_lo = r;
    } else {
      r_hi = r;
    }
  }
  // s.t_lo + r_lo * width may round up by an ulp or two; step down so toi stays a lower bound.
  const double t = s.t_lo + r_lo * width;
  toi = std::nextafter(std::nextafter(t, 0.0), 0.0);
  toi = std::max(toi, s.t_lo);
  return true;
}

CcdResult earliest_root(const VertexFaceQuery& q, const Span& s, const CcdSettings& settings) {
  double toi = 0.0;
  if (bisect_monotone(s, settings.toi_tolerance, toi)) return contact_at(q, toi, CcdPath::FILTER);
  double lo = s.t_lo;
  double hi = s.t_hi;
  Bernstein<4> f = s.f;
  while (hi - lo > settings.toi_tolerance) {
    bool narrowed = false;
    for (const double r : {0.5, kOffCentre}) {
      Bernstein<4> left, right;
      if (r == 0.5) {
        subdivide(f, left, right);
      } else {
        subdivide_at(f, r, left, right);
      }
      const double mid = lo + r * (hi - lo);
      if (!exact_split(lo, mid, hi, r)) break;
      if (certainly_positive(left) || certainly_negative(left)) {
        f = right;
        lo = mid;
      } else if (certain_sign(left.front()) * certain_sign(left.back()) < 0) {
        f = left;
        hi = mid;
      } else if (certain_sign(left.back()) == 0) {
        continue;  // eq. 6 is (nearly) zero at mid: try off centre
      } else {
        break;  // more than one root may lie in the left half
      }
      narrowed = true;
      break;
    }
    if (!narrowed) return exact_from(q, lo, settings);
  }
  return contact_at(q, lo, CcdPath::FILTER);
}

}  // namespace

namespace {

/// 0 when every coordinate is finite, NaN otherwise: x - x is 0 for every finite x and NaN for the rest, so
/// one comparison clears the usual query (a search per coordinate cost as much as the cheap rejections of a
/// query, issue 41).
inline double finite_zero(const Vec3& v) {
  return ((v[0] - v[0]) + (v[1] - v[1])) + (v[2] - v[2]);
}

[[gnu::cold, gnu::noinline]] void throw_non_finite(const VertexFaceQuery& query) {
  const Vec3* vertices[8] = {&query.p_t0, &query.a_t0, &query.b_t0, &query.c_t0,
                             &query.p_t1, &query.a_t1, &query.b_t1, &query.c_t1};
  static const char* const names[8] = {"p_t0", "a_t0", "b_t0", "c_t0", "p_t1", "a_t1", "b_t1", "c_t1"};
  for (int v = 0; v < 8; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double x = (*vertices[v])[k];
      if (!std::isfinite(x)) {
        throw InvalidQueryError("CCD query coordinate " + std::string(names[v]) + "." + "xyz"[k] +
                                " is not finite, got " + format_number(x));
      }
    }
  }
}

inline void check_finite(const VertexFaceQuery& q) {
  const double zero =
      ((finite_zero(q.p_t0) + finite_zero(q.a_t0)) + (finite_zero(q.b_t0) + finite_zero(q.c_t0))) +
      ((finite_zero(q.p_t1) + finite_zero(q.a_t1)) + (finite_zero(q.b_t1) + finite_zero(q.c_t1)));
  if (!(zero == 0.0)) throw_non_finite(q);
}

}  // namespace

void check_query_finite(const VertexFaceQuery& query) {
  check_finite(query);
}

CcdResult point_triangle_ccd(const VertexFaceQuery& query, const CcdSettings& settings) {
  check_finite(query);
  CcdResult on_vertex;
  if (starts_on_vertex(query, on_vertex)) return on_vertex;
  if (certainly_one_signed(query)) return CcdResult{};  // never coplanar
  if (certainly_beside(query)) return CcdResult{};      // never inside the triangle

  Span root;
  root.t_lo = 0.0;
  root.t_hi = 1.0;
  std::array<V3, 3> normal;
  root.f = coplanarity(query, normal);
  if (!all_finite(root.f)) return exact_from(query, 0.0, settings);  // overflow: only exact arithmetic helps
  if (certainly_positive(root.f) || certainly_negative(root.f)) return CcdResult{};  // never coplanar
  root.g = inside_tests(query, normal);
  for (const auto& g : root.g) {
    if (!all_finite(g)) return exact_from(query, 0.0, settings);
  }

  // A point exactly in the plane at t = 0 or t = 1 (resting contact, hand-built scenes) makes eq. 6 vanish at
  // that end, which no rounding error bound can certify; exact signs decide, and f is divided by the root.
  bool contact_at_end = false;    // the point is strictly inside the triangle at t = 1
  bool undecided_at_end = false;  // the point is in the plane at t = 1, on the triangle's boundary or near it
  for (const bool at_end : {false, true}) {
    const int end = at_end ? 3 : 0;
    const int g_end = at_end ? 4 : 0;
    if (certain_sign(root.f[end]) != 0 || coplanarity_sign_exact(query, at_end) != 0) continue;
    const bool inside = certain_sign(root.g[0][g_end]) > 0 && certain_sign(root.g[1][g_end]) > 0 &&
                        certain_sign(root.g[2][g_end]) > 0;
    const bool outside = certain_sign(root.g[0][g_end]) < 0 || certain_sign(root.g[1][g_end]) < 0 ||
                         certain_sign(root.g[2][g_end]) < 0;
    if (!at_end) {
      if (inside) return contact_at(query, 0.0, CcdPath::FILTER);
      if (!outside) return exact_from(query, 0.0, settings);  // on an edge or a vertex at t = 0
    } else {
      // Whatever happens at t = 1 matters only if nothing touches earlier: decided after the search.
      contact_at_end = inside;
      undecided_at_end = !inside && !outside;
    }
    root.f = deflate(root.f, at_end);
  }

  // In time order, so the first contact certified is the earliest: everything to its left was skipped.
  const std::optional<CcdResult> found = walk_spans(
      root, std::max(settings.max_filter_intervals, 1),
      [&](const Span& s) { return earliest_root(query, s, settings); },
      [&](const Span& s) { return exact_from(query, s.t_lo, settings); });
  if (found) return *found;
  if (contact_at_end) return contact_at(query, 1.0, CcdPath::FILTER);
  if (undecided_at_end) return exact_from(query, 1.0, settings);
  return CcdResult{};
}

namespace {

/// Sign of a plain determinant when its error bound leaves it certain, else 0; the margin as in
/// certainly_one_signed.
int certain_sign(const PlainDet& d) {
  const double margin = d.error * kGrow + 4.0 * kUnitRoundoff * std::abs(d.value);
  return d.value > margin ? 1 : d.value < -margin ? -1 : 0;
}

/// 2^bits for the time grid the general filter brackets a time of impact on: bisect_monotone halves until the
/// bracket is at most half the tolerance, so its ends are multiples of the largest power of two 2^-bits <=
/// toi_tolerance / 2, whatever interval it started from. 0 when the tolerance is outside the range this path
/// reproduces.
double bracket_scale(double toi_tolerance) {
  int bits = 0;
  double cell = 1.0;
  while (cell > 0.5 * toi_tolerance && bits <= 40) {
    cell *= 0.5;
    ++bits;
  }
  return bits >= 13 && bits <= 40 ? 1.0 / cell : 0.0;
}

}  // namespace

CcdResult point_static_triangle_ccd(const Vec3& p_t0, const Vec3& p_t1, const Vec3& a, const Vec3& b,
                                    const Vec3& c, const CcdSettings& settings) {
  const auto query = [&] { return VertexFaceQuery{p_t0, a, b, c, p_t1, a, b, c}; };
  const double zero =
      ((finite_zero(p_t0) + finite_zero(p_t1)) + (finite_zero(a) + finite_zero(b))) + finite_zero(c);
  if (!(zero == 0.0)) throw_non_finite(query());
  CcdResult on_vertex;
  if ((p_t0 == a || p_t0 == b || p_t0 == c) && starts_on_vertex(query(), on_vertex)) return on_vertex;
  // Eq. 6 at the ends: f(t) = (1 - t) f0 + t f1, the plane being fixed.
  // Both ends share the normal: f = (p - a) . n, n = (b - a) x (c - a), with plain_det3's bound (the same six
  // roundings along each term), the terms' magnitudes from the same products in absolute values.
  const Vec3 ab = b - a, ac = c - a, ap0 = p_t0 - a, ap1 = p_t1 - a;
  const Vec3 n = ab.cross(ac);
  const Vec3 ab_abs = ab.cwiseAbs(), ac_abs = ac.cwiseAbs();
  const Vec3 n_terms(ab_abs.y() * ac_abs.z() + ab_abs.z() * ac_abs.y(),
                     ab_abs.z() * ac_abs.x() + ab_abs.x() * ac_abs.z(),
                     ab_abs.x() * ac_abs.y() + ab_abs.y() * ac_abs.x());
  const PlainDet f0{ap0.dot(n), 16.0 * kUnitRoundoff * ap0.cwiseAbs().dot(n_terms) + kTiny};
  const PlainDet f1{ap1.dot(n), 16.0 * kUnitRoundoff * ap1.cwiseAbs().dot(n_terms) + kTiny};
  const int side_t0 = certain_sign(f0), side_t1 = certain_sign(f1);
  if (side_t0 != 0 && side_t0 == side_t1) return CcdResult{};  // never in the plane
  if (side_t0 * side_t1 < 0) {
    // The point passes the plane once, inside the step. The line p_t0 p_t1 meets the closed triangle exactly
    // when its orientations against the three edges, det[p_t1 - p_t0, u - p_t0, w - p_t0] for the edges uw,
    // share a sign (or vanish): two certain opposite signs, and it passes beside the triangle.
    const Vec3 d = p_t1 - p_t0, pa = a - p_t0, pb = b - p_t0, pc = c - p_t0;
    const int edge[3] = {certain_sign(plain_det3(d, pa, pb)), certain_sign(plain_det3(d, pb, pc)),
                         certain_sign(plain_det3(d, pc, pa))};
    const int positive = (edge[0] > 0) + (edge[1] > 0) + (edge[2] > 0);
    const int negative = (edge[0] < 0) + (edge[1] < 0) + (edge[2] < 0);
    if (positive > 0 && negative > 0) return CcdResult{};
    const double scale = bracket_scale(settings.toi_tolerance);
    // Outside this range of lengths the general filter's quartics overflow or sink below its bounds'
    // absolute term, and the exact reference brackets the time instead (still correct, another bracket).
    const double length = std::max({ab.cwiseAbs().maxCoeff(), ac.cwiseAbs().maxCoeff(),
                                    ap0.cwiseAbs().maxCoeff(), ap1.cwiseAbs().maxCoeff()});
    const bool in_range = length >= 0x1p-90 && length <= 0x1p190;
    if ((positive == 3 || negative == 3) && scale > 0.0 && in_range) {
      // Strictly inside the face at the root t = |f0| / (|f0| + |f1|). Each |f| is within its margin e of the
      // exact value, which moves t by at most (e0 + e1) / (|f0| + |f1| - e0 - e1); the division and the sum
      // add 2 u. The general filter brackets the root on the grid of bracket_scale and steps the lower end
      // down by two ulps, except where its bisection meets the root within its own rounding (a wider bound
      // than this one, hence the factor 256) or where the bracket's lower end starts the filter interval the
      // contact was certified on (then it is not stepped down). Those intervals start on multiples of 2^-12
      // unless the query is near-degenerate: such roots, and roots this close to a grid line, go to the
      // general filter, so the result is the one it gives.
      const double x = std::abs(f0.value), y = std::abs(f1.value);
      const double e0 = f0.error * kGrow + 4.0 * kUnitRoundoff * x;
      const double e1 = f1.error * kGrow + 4.0 * kUnitRoundoff * y;
      const double t = x / (x + y);
      const double spread = ((e0 + e1) / (x + y - e0 - e1) + 4.0 * kUnitRoundoff) * kGrow;
      const double margin = 256.0 * spread + 0x1p-50;
      const double cell = std::floor(t * scale);  // scaling by a power of two is exact
      const bool one_cell =
          std::floor((t - margin) * scale) == cell && std::floor((t + margin) * scale) == cell;
      const double lower = cell / scale;
      if (one_cell && std::floor(lower * 0x1p12) != lower * 0x1p12) {
        const double toi = std::nextafter(std::nextafter(lower, 0.0), 0.0);
        return contact_at(query(), toi, CcdPath::FILTER);
      }
    }
  }
  return point_triangle_ccd(query(), settings);
}

bool transversal_crossing(const VertexFaceQuery& query, CcdPath* path) {
  check_finite(query);
  if (path) *path = CcdPath::FILTER;
  const auto exact = [&] {
    if (path) *path = CcdPath::EXACT;
    return transversal_crossing_exact(query);
  };
  if (certainly_one_signed(query) || certainly_beside(query)) return false;
  Span root;
  root.t_lo = 0.0;
  root.t_hi = 1.0;
  std::array<V3, 3> normal;
  root.f = coplanarity(query, normal);
  if (!all_finite(root.f)) return exact();
  if (certainly_positive(root.f) || certainly_negative(root.f)) return false;
  root.g = inside_tests(query, normal);
  for (const auto& g : root.g) {
    if (!all_finite(g)) return exact();
  }
  // Any span where the filter certifies a contact holds a crossing: eq. 6 certainly changes sign between its
  // ends, so it has a root of odd multiplicity strictly inside (0, 1), and there the point is strictly inside
  // a face of nonzero area. Spans certified free of contact hold none. The order does not matter; the budget
  // is point_triangle_ccd's.
  return walk_spans(
             root, CcdSettings{}.max_filter_intervals, [](const Span&) { return true; },
             [&](const Span&) { return exact(); })
      .value_or(false);
}

}  // namespace drench::ccd
