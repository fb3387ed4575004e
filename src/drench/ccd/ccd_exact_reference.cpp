#include <drench/ccd/ccd_exact_reference.hpp>

#include <gmpxx.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

// Method. Every double is a rational, so the query is exact in rational arithmetic (GMP). The point
// lies in the closed triangle at time t exactly when one of three disjoint-in-kind conditions holds:
//   vertex:      p(t) = v(t) for a vertex v                                (3 linear equations)
//   open edge:   (p - u) x e = 0 and 0 < (p - u).e < e.e, e = w - u          (quadratics)
//   open face:   f(t) = 0 (eq. 6) and g_a, g_b, g_c > 0, where g_a = ((b - p) x (c - p)).n and n = (b-a) x
//   (c-a)
// A point in the closed triangle is on a vertex, inside an edge, or strictly inside a non-degenerate face; a
// zero-area triangle is covered by its edges and vertices, so no case needs a normal. Each condition is
// "common root of some polynomials at which other polynomials are positive", decided by the gcd of the
// equalities, Sturm root isolation of its square-free part on [t_from, 1], and the exact sign of the others
// at each isolated root (zero iff the root is shared with the gcd; else after refining until no root of
// theirs is left in the interval). When every equality vanishes identically (e.g. motion inside the
// triangle's plane) the condition holds on an open set, tested between consecutive roots of the inequalities.
// The earliest contact is the smallest infimum over the seven conditions; the set of contact times is closed,
// so that infimum is a contact. References: Sturm's theorem as in Basu, Pollack, Roy, "Algorithms in Real
// Algebraic Geometry", ch. 2; the case split follows the vertex/edge/face contact features of Bridson,
// Fedkiw, Anderson 2002, sec. 7.

namespace drench::ccd {
namespace {

// Every double is an integer times a power of two, so after scaling all coordinates by one power of two the
// polynomials have integer coefficients (GMP's mpz_class) and every time the algorithm looks at is a dyadic
// rational m / 2^k. Working over the integers avoids the gcd normalisation of rational arithmetic, which cost
// milliseconds per query.

/// Polynomial in t with integer coefficients, c[k] multiplies t^k; empty is the zero polynomial.
using Poly = std::vector<mpz_class>;

/// The dyadic rational m / 2^k.
struct Dyadic {
  mpz_class m;
  unsigned long k = 0;
};

Dyadic normalized(Dyadic d) {
  if (sgn(d.m) == 0) return {mpz_class(0), 0};
  const unsigned long zeros = mpz_scan1(d.m.get_mpz_t(), 0);
  const unsigned long shift = std::min(zeros, d.k);
  if (shift > 0) {
    mpz_fdiv_q_2exp(d.m.get_mpz_t(), d.m.get_mpz_t(), shift);
    d.k -= shift;
  }
  return d;
}

mpz_class shifted(const mpz_class& x, unsigned long bits) {
  mpz_class r;
  mpz_mul_2exp(r.get_mpz_t(), x.get_mpz_t(), bits);
  return r;
}

Dyadic midpoint(const Dyadic& a, const Dyadic& b) {
  const unsigned long k = std::max(a.k, b.k);
  return normalized({shifted(a.m, k - a.k) + shifted(b.m, k - b.k), k + 1});
}

int compare(const Dyadic& a, const Dyadic& b) {
  const unsigned long k = std::max(a.k, b.k);
  return cmp(shifted(a.m, k - a.k), shifted(b.m, k - b.k));
}

bool operator<(const Dyadic& a, const Dyadic& b) {
  return compare(a, b) < 0;
}
bool operator==(const Dyadic& a, const Dyadic& b) {
  return compare(a, b) == 0;
}

/// b - a.
Dyadic difference(const Dyadic& b, const Dyadic& a) {
  const unsigned long k = std::max(a.k, b.k);
  return normalized({shifted(b.m, k - b.k) - shifted(a.m, k - a.k), k});
}

mpq_class to_rational(const Dyadic& d) {
  mpq_class q(d.m, shifted(mpz_class(1), d.k));
  q.canonicalize();
  return q;
}

/// An exact double as a dyadic rational.
Dyadic to_dyadic(double x) {
  int exponent = 0;
  const double fraction = std::frexp(x, &exponent);  // x = fraction * 2^exponent, |fraction| in [0.5, 1)
  Dyadic d{mpz_class(std::ldexp(fraction, 53)), 0};
  const long e = static_cast<long>(exponent) - 53;
  if (e >= 0) {
    d.m = shifted(d.m, static_cast<unsigned long>(e));
  } else {
    d.k = static_cast<unsigned long>(-e);
  }
  return normalized(d);
}

void trim(Poly& p) {
  while (!p.empty() && sgn(p.back()) == 0)
    p.pop_back();
}

int degree(const Poly& p) {
  return static_cast<int>(p.size()) - 1;
}

Poly add(const Poly& a, const Poly& b) {
  Poly r(std::max(a.size(), b.size()));
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (k < a.size()) r[k] += a[k];
    if (k < b.size()) r[k] += b[k];
  }
  trim(r);
  return r;
}

Poly sub(const Poly& a, const Poly& b) {
  Poly r(std::max(a.size(), b.size()));
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (k < a.size()) r[k] += a[k];
    if (k < b.size()) r[k] -= b[k];
  }
  trim(r);
  return r;
}

Poly mul(const Poly& a, const Poly& b) {
  if (a.empty() || b.empty()) return {};
  Poly r(a.size() + b.size() - 1);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j)
      r[i + j] += a[i] * b[j];
  }
  trim(r);
  return r;
}

Poly derivative(const Poly& p) {
  Poly r;
  for (std::size_t k = 1; k < p.size(); ++k)
    r.push_back(p[k] * static_cast<unsigned long>(k));
  trim(r);
  return r;
}

/// The same polynomial divided by the gcd of its coefficients (positive), so numbers stay small.
Poly primitive(Poly p) {
  if (p.empty()) return p;
  mpz_class content = 0;
  for (const auto& c : p)
    content = gcd(content, c);
  if (content != 1) {
    for (auto& c : p)
      mpz_divexact(c.get_mpz_t(), c.get_mpz_t(), content.get_mpz_t());
  }
  return p;
}

/// Sign of p(t) at the dyadic t = m / 2^k, from the integer 2^(k deg p) p(t) (Horner).
int sign_at_exact(const Poly& p, const Dyadic& t) {
  if (p.empty()) return 0;
  mpz_class value = p.back();
  for (std::size_t i = p.size() - 1; i-- > 0;) {
    value *= t.m;
    value += shifted(p[i], t.k * (p.size() - 1 - i));
  }
  return sgn(value);
}

/// t as a double when that is exact (always for the bisection points this file produces before depth 53).
bool exact_double(const Dyadic& t, double& out) {
  if (mpz_sizeinbase(t.m.get_mpz_t(), 2) > 53 || t.k > 1000) return false;
  out = std::ldexp(t.m.get_d(), -static_cast<int>(t.k));
  return true;
}

/// p(t) and a bound on |p(t) - value| (Horner in double, coefficients rounded to double). For t in [0, 1].
/// Returns false when the coefficients overflow double.
bool evaluate_double(const Poly& p, double t, double& value, double& error) {
  double v = 0.0;
  double magnitude = 0.0;
  for (std::size_t i = p.size(); i-- > 0;) {
    const double c = p[i].get_d();  // relative error below 2^-52 (truncation)
    v = v * t + c;
    magnitude = magnitude * t + std::abs(c);
  }
  // Coefficient conversion (1 ulp) plus 2 roundings per Horner step, with a wide margin (Higham 2002, 5.1).
  error = magnitude * static_cast<double>(4 * p.size() + 8) * 0x1p-53;
  value = v;
  return std::isfinite(magnitude) && std::isfinite(error);
}

/// Exact sign of p at the dyadic t: a floating-point filter first, exact integers when it cannot tell.
int sign_at(const Poly& p, const Dyadic& t) {
  if (p.empty()) return 0;
  double td = 0.0;
  double value = 0.0;
  double error = 0.0;
  if (exact_double(t, td) && evaluate_double(p, td, value, error)) {
    if (value > error) return 1;
    if (value < -error) return -1;
  }
  return sign_at_exact(p, t);
}

/// Sum of k |c_k|, a bound on |p'| over [0, 1], rounded up generously.
double derivative_bound(const Poly& p) {
  double bound = 0.0;
  for (std::size_t k = 1; k < p.size(); ++k)
    bound += static_cast<double>(k) * std::abs(p[k].get_d());
  return bound * (1.0 + 0x1p-40);
}

/// Pseudo-remainder: r = lc(b)^j a - q b with deg r < deg b; also reports the sign of lc(b)^j, so that
/// r * that sign has the sign pattern of the true remainder of a by b over the rationals. Also returns the
/// pseudo-quotient q (same scaling).
Poly pseudo_remainder(Poly a, const Poly& b, int* scale_sign = nullptr, Poly* quotient = nullptr) {
  int sign = 1;
  const int lead_sign = sgn(b.back());
  if (quotient) quotient->assign(a.size() >= b.size() ? a.size() - b.size() + 1 : 0, mpz_class(0));
  while (!a.empty() && a.size() >= b.size()) {
    const mpz_class lead_a = a.back();
    const std::size_t shift = a.size() - b.size();
    for (auto& c : a)
      c *= b.back();
    for (std::size_t k = 0; k < b.size(); ++k)
      a[k + shift] -= lead_a * b[k];
    if (quotient) {
      for (auto& c : *quotient)
        c *= b.back();
      (*quotient)[shift] += lead_a;
    }
    sign *= lead_sign;
    trim(a);
  }
  if (scale_sign) *scale_sign = sign;
  if (quotient) trim(*quotient);
  return a;
}

/// Primitive gcd (up to a constant factor); gcd(0, 0) = 0 (the empty polynomial), a constant gcd is {1}.
Poly gcd(Poly a, Poly b) {
  a = primitive(std::move(a));
  b = primitive(std::move(b));
  while (!b.empty()) {
    Poly r = primitive(pseudo_remainder(std::move(a), b));
    a = std::move(b);
    b = std::move(r);
  }
  if (degree(a) == 0) return Poly{mpz_class(1)};
  return a;
}

Poly square_free(const Poly& p) {
  if (degree(p) < 1) return p;
  const Poly g = gcd(p, derivative(p));
  if (degree(g) < 1) return primitive(p);
  Poly quotient;
  pseudo_remainder(p, g, nullptr, &quotient);
  return primitive(std::move(quotient));
}

/// Sturm sequence of a square-free polynomial of degree >= 1 (signed pseudo-remainders, Collins' rule).
struct Sturm {
  std::vector<Poly> chain;

  explicit Sturm(const Poly& p) {
    chain.push_back(p);
    chain.push_back(derivative(p));
    while (degree(chain.back()) > 0) {
      int scale_sign = 1;
      Poly r = pseudo_remainder(chain[chain.size() - 2], chain.back(), &scale_sign);
      if (r.empty()) break;
      if (scale_sign > 0) {
        for (auto& c : r)
          c = -c;
      }
      chain.push_back(primitive(std::move(r)));
    }
  }

  int variations(const Dyadic& t) const {
    int count = 0;
    int previous = 0;
    for (const Poly& s : chain) {
      const int sign = sign_at(s, t);
      if (sign == 0) continue;
      if (previous != 0 && sign != previous) ++count;
      previous = sign;
    }
    return count;
  }

  /// Number of distinct roots in (a, b], a < b.
  int count(const Dyadic& a, const Dyadic& b) const { return variations(a) - variations(b); }
};

/// A real root: exactly `lo` when lo == hi, else the only root of its polynomial in the open (lo, hi), where
/// the polynomial is non-zero at both ends.
struct Root {
  Dyadic lo, hi;
  bool exact() const { return lo == hi; }
};

/// Narrows an isolating interval of a simple root of p to width <= width (or to the exact root).
void refine(const Poly& p, Root& root, const Dyadic& width) {
  if (root.exact()) return;
  const int sign_lo = sign_at(p, root.lo);
  while (width < difference(root.hi, root.lo)) {
    const Dyadic mid = midpoint(root.lo, root.hi);
    const int s = sign_at(p, mid);
    if (s == 0) {
      root.lo = root.hi = mid;
      return;
    }
    if (s == sign_lo) {
      root.lo = mid;
    } else {
      root.hi = mid;
    }
  }
}

/// All roots of the square-free p (degree >= 1) in [lo, hi], in increasing order.
std::vector<Root> isolate_roots(const Poly& p, const Dyadic& lo, const Dyadic& hi) {
  std::vector<Root> roots;
  if (sign_at(p, lo) == 0) roots.push_back({lo, lo});
  if (lo == hi) return roots;
  const Sturm sturm(p);
  // Depth-first over (a, b], left first, so the roots come out sorted.
  std::vector<std::pair<Dyadic, Dyadic>> stack{{lo, hi}};
  while (!stack.empty()) {
    auto [a, b] = stack.back();
    stack.pop_back();
    const int n = sturm.count(a, b);
    if (n == 0) continue;
    if (n > 1) {
      const Dyadic mid = midpoint(a, b);
      stack.emplace_back(mid, b);
      stack.emplace_back(a, mid);
      continue;
    }
    if (sign_at(p, b) == 0) {
      roots.push_back({b, b});
      continue;
    }
    // One root in (a, b) and p(b) != 0; move a off a root of p (a may be the previous, exact root).
    while (sign_at(p, a) == 0) {
      const Dyadic mid = midpoint(a, b);
      if (sign_at(p, mid) == 0) {
        a = b = mid;
        break;
      }
      if (sturm.count(mid, b) == 1) {
        a = mid;
      } else {
        b = mid;
      }
    }
    roots.push_back({a, b});
  }
  return roots;
}

/// Exact sign of q at the root of the square-free p (degree >= 1) that `root` isolates.
int sign_at_root(const Poly& p, Root root, const Poly& q) {
  if (root.exact()) return sign_at(q, root.lo);
  if (q.empty()) return 0;
  if (degree(q) == 0) return sgn(q[0]);
  // Usually q is far from zero at the root: narrow the interval until q(lo) is certainly larger than anything
  // q can change by across it (|q'| <= sum k |c_k| on [0, 1]); then q has that sign on the whole interval.
  const double slope = derivative_bound(q);
  if (std::isfinite(slope)) {
    const int sign_p_lo = sign_at(p, root.lo);
    for (int step = 0; step < 64; ++step) {
      double lo = 0.0;
      double hi = 0.0;
      double value = 0.0;
      double error = 0.0;
      if (!exact_double(root.lo, lo) || !exact_double(root.hi, hi) || !evaluate_double(q, lo, value, error))
        break;
      const double change = slope * (hi - lo) * (1.0 + 0x1p-40);  // hi - lo is exact (Sterbenz) or tiny
      if (std::abs(value) > error + change) return value > 0.0 ? 1 : -1;
      if (change < error) break;  // rounding, not the interval, is the limit: q is (nearly) zero here
      const Dyadic mid = midpoint(root.lo, root.hi);
      const int s = sign_at(p, mid);
      if (s == 0) return sign_at(q, mid);
      if (s == sign_p_lo) {
        root.lo = mid;
      } else {
        root.hi = mid;
      }
    }
  }
  const Poly g = gcd(p, q);
  if (degree(g) >= 1 && sign_at(g, root.lo) * sign_at(g, root.hi) < 0) return 0;
  // q does not vanish at the root: shrink the interval until q has no root left in it.
  const Poly q_free = square_free(q);
  const Sturm sturm(q_free);
  const int sign_lo = sign_at(p, root.lo);
  while (sign_at(q_free, root.lo) == 0 || sturm.count(root.lo, root.hi) > 0) {
    const Dyadic mid = midpoint(root.lo, root.hi);
    const int s = sign_at(p, mid);
    if (s == 0) return sign_at(q, mid);
    if (s == sign_lo) {
      root.lo = mid;
    } else {
      root.hi = mid;
    }
  }
  return sign_at(q, root.hi);
}

/// The polynomials of one contact condition: all `zeros` vanish and all `positives` are > 0.
struct Condition {
  std::vector<Poly> zeros;
  /// Builds the positives; called only when the zeros have a common root in range, since most conditions
  /// fail on the zeros alone and building the quartics of the face test is a large part of the cost.
  std::function<std::vector<Poly>()> positives;
};

/// Earliest t in [lo, 1] where the condition holds, or its infimum when it holds on an open set; the root's
/// polynomial comes along so the caller can refine the bracket.
struct Earliest {
  Root root;
  Poly polynomial;  // empty when root is exact
};

bool all_positive_at(const std::vector<Poly>& polys, const Dyadic& t) {
  for (const Poly& q : polys) {
    if (sign_at(q, t) <= 0) return false;
  }
  return true;
}

std::optional<Earliest> earliest(const Condition& condition, const Dyadic& lo, const Dyadic& hi) {
  std::vector<Poly> positives;
  Poly h;
  for (const Poly& z : condition.zeros) {
    h = gcd(h, z);
    if (degree(h) == 0) return std::nullopt;  // no common root at all
  }
  if (!h.empty()) {
    const Poly p = square_free(h);
    const std::vector<Root> roots = isolate_roots(p, lo, hi);
    if (!roots.empty()) positives = condition.positives();
    for (const Root& root : roots) {
      bool holds = true;
      for (const Poly& q : positives) {
        if (sign_at_root(p, root, q) <= 0) {
          holds = false;
          break;
        }
      }
      if (holds) return Earliest{root, root.exact() ? Poly{} : p};
    }
    return std::nullopt;
  }
  // Every equality vanishes identically: the condition holds on an open subset of [lo, hi] (or everywhere).
  positives = condition.positives();
  if (all_positive_at(positives, lo)) return Earliest{{lo, lo}, {}};
  Poly product{mpz_class(1)};
  for (const Poly& q : positives) {
    if (q.empty()) return std::nullopt;  // a positive that is identically zero never holds
    product = mul(product, q);
  }
  const Poly critical = degree(product) >= 1 ? square_free(product) : Poly{};
  std::vector<Root> roots;
  if (!critical.empty()) roots = isolate_roots(critical, lo, hi);
  // Signs are constant between consecutive roots: sample one point in each gap, left to right. The infimum of
  // the first gap where the condition holds is its left end.
  std::optional<Root> gap_root;  // the root at the gap's left end (none for the first gap)
  for (std::size_t k = 0; k <= roots.size(); ++k) {
    const Dyadic& right = k < roots.size() ? roots[k].lo : hi;
    const Dyadic& left = gap_root ? gap_root->hi : lo;
    if (left < right && all_positive_at(positives, midpoint(left, right))) {
      if (!gap_root) return Earliest{{lo, lo}, {}};
      return Earliest{*gap_root, gap_root->exact() ? Poly{} : critical};
    }
    if (k < roots.size()) gap_root = roots[k];
  }
  return std::nullopt;
}

/// A linear polynomial per coordinate: x(t) = x_t0 + t (x_t1 - x_t0), in integer units of 2^-scale.
using PolyVec = std::array<Poly, 3>;

PolyVec sub(const PolyVec& a, const PolyVec& b) {
  return {sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])};
}

PolyVec cross(const PolyVec& a, const PolyVec& b) {
  return {sub(mul(a[1], b[2]), mul(a[2], b[1])), sub(mul(a[2], b[0]), mul(a[0], b[2])),
          sub(mul(a[0], b[1]), mul(a[1], b[0]))};
}

Poly dot(const PolyVec& a, const PolyVec& b) {
  return add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]));
}

/// The query's linear motions as integer polynomials: all 24 coordinates times 2^k with one k (the largest k
/// of their dyadic forms), which changes no sign and no root.
std::array<PolyVec, 4> integer_motion(const VertexFaceQuery& query) {
  // All 24 coordinates as integers times 2^-k with one k: the largest k of their dyadic forms.
  const Vec3* vertices[8] = {&query.p_t0, &query.a_t0, &query.b_t0, &query.c_t0,
                             &query.p_t1, &query.a_t1, &query.b_t1, &query.c_t1};
  std::array<Dyadic, 24> coordinate;
  unsigned long scale = 0;
  for (int v = 0; v < 8; ++v) {
    for (int k = 0; k < 3; ++k) {
      coordinate[3 * v + k] = to_dyadic((*vertices[v])[k]);
      scale = std::max(scale, coordinate[3 * v + k].k);
    }
  }
  std::array<PolyVec, 4> motion;
  for (int v = 0; v < 4; ++v) {
    for (int k = 0; k < 3; ++k) {
      const Dyadic& start = coordinate[3 * v + k];
      const Dyadic& end = coordinate[3 * (v + 4) + k];
      const mpz_class x_t0 = shifted(start.m, scale - start.k);
      const mpz_class x_t1 = shifted(end.m, scale - end.k);
      motion[v][k] = Poly{x_t0, x_t1 - x_t0};
      trim(motion[v][k]);
    }
  }
  return motion;
}

double round_down(const mpq_class& x) {
  double d = x.get_d();  // truncates toward zero, so d <= x for x >= 0
  if (mpq_class(d) > x) d = std::nextafter(d, -std::numeric_limits<double>::infinity());
  return d;
}

double round_up(const mpq_class& x) {
  double d = x.get_d();
  if (mpq_class(d) < x) d = std::nextafter(d, std::numeric_limits<double>::infinity());
  return d;
}

}  // namespace

ExactCcdResult point_triangle_ccd_exact(const VertexFaceQuery& query, double t_from, double toi_tolerance) {
  check_query_finite(query);
  if (!(t_from >= 0.0 && t_from <= 1.0)) {
    throw InvalidQueryError("point_triangle_ccd_exact: t_from must be in [0, 1], got " +
                            format_number(t_from));
  }
  if (!(toi_tolerance > 0.0)) {
    throw InvalidQueryError("point_triangle_ccd_exact: toi_tolerance must be > 0, got " +
                            format_number(toi_tolerance));
  }
  const std::array<PolyVec, 4> motion = integer_motion(query);  // p, a, b, c
  const PolyVec& p = motion[0];
  const std::array<PolyVec, 3> tri = {motion[1], motion[2], motion[3]};

  // Vertices first, then edges, then the face: cheap conditions first, and a contact found early narrows the
  // range the expensive face test searches.
  std::vector<Condition> conditions;
  for (int i = 0; i < 3; ++i) {
    const PolyVec d = sub(p, tri[i]);
    conditions.push_back({{d[0], d[1], d[2]}, [] { return std::vector<Poly>{}; }});
  }
  for (int i = 0; i < 3; ++i) {
    const PolyVec& u = tri[i];
    const PolyVec e = sub(tri[(i + 1) % 3], u);
    const PolyVec r = sub(p, u);
    const PolyVec c = cross(r, e);
    conditions.push_back({{c[0], c[1], c[2]}, [e, r] {
                            const Poly along = dot(r, e);
                            return std::vector<Poly>{along, sub(dot(e, e), along)};
                          }});
  }
  const PolyVec n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
  conditions.push_back({{dot(sub(p, tri[0]), n)},  // eq. 6
                        [&p, &tri, &n] {
                          std::vector<Poly> inside;
                          for (int i = 0; i < 3; ++i) {
                            inside.push_back(
                                dot(cross(sub(tri[(i + 1) % 3], p), sub(tri[(i + 2) % 3], p)), n));
                          }
                          return inside;
                        }});

  const Dyadic lo = to_dyadic(t_from);
  const Dyadic hi{mpz_class(1), 0};
  const Dyadic width = to_dyadic(toi_tolerance);
  std::optional<Root> first;
  for (const Condition& condition : conditions) {
    // A contact found already bounds the search: a later condition only matters if it holds before that.
    std::optional<Earliest> e = earliest(condition, lo, first ? first->hi : hi);
    if (!e) continue;
    if (!e->root.exact()) refine(e->polynomial, e->root, width);
    if (!first || e->root.lo < first->lo) {
      const Dyadic upper = first && first->hi < e->root.hi ? first->hi : e->root.hi;
      first = Root{e->root.lo, upper};
    } else if (e->root.hi < first->hi) {
      first->hi = e->root.hi;
    }
  }
  ExactCcdResult result;
  if (first) {
    result.hit = true;
    result.toi_lower = round_down(to_rational(first->lo));
    result.toi_upper = round_up(to_rational(first->hi));
  }
  return result;
}

int coplanarity_sign_exact(const VertexFaceQuery& query, bool at_end) {
  const std::array<const Vec3*, 4> x =
      at_end ? std::array<const Vec3*, 4>{&query.p_t1, &query.a_t1, &query.b_t1, &query.c_t1}
             : std::array<const Vec3*, 4>{&query.p_t0, &query.a_t0, &query.b_t0, &query.c_t0};
  std::array<Dyadic, 12> d;
  unsigned long scale = 0;
  for (int v = 0; v < 4; ++v) {
    for (int k = 0; k < 3; ++k) {
      d[3 * v + k] = to_dyadic((*x[v])[k]);
      scale = std::max(scale, d[3 * v + k].k);
    }
  }
  auto coordinate = [&](int v, int k) { return shifted(d[3 * v + k].m, scale - d[3 * v + k].k); };
  std::array<std::array<mpz_class, 3>, 3> m;  // rows p - a, b - a, c - a
  for (int k = 0; k < 3; ++k) {
    const mpz_class a = coordinate(1, k);
    m[0][k] = coordinate(0, k) - a;
    m[1][k] = coordinate(2, k) - a;
    m[2][k] = coordinate(3, k) - a;
  }
  const mpz_class det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                        m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                        m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return sgn(det);
}

bool transversal_crossing_exact(const VertexFaceQuery& query) {
  check_query_finite(query);
  const std::array<PolyVec, 4> motion = integer_motion(query);
  const PolyVec& p = motion[0];
  const std::array<PolyVec, 3> tri = {motion[1], motion[2], motion[3]};
  const PolyVec n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
  const Poly f = dot(sub(p, tri[0]), n);  // eq. 6: the side of the triangle, up to the sign of n
  if (degree(f) < 1) return false;        // never or always coplanar: no side changes
  const Poly root_poly = square_free(f);
  const Dyadic zero{mpz_class(0), 0};
  const Dyadic one{mpz_class(1), 0};
  for (const Root& root : isolate_roots(root_poly, zero, one)) {
    if (root.exact() && (root.lo == zero || root.lo == one)) continue;  // at the ends: no "just after/before"
    // The side changes exactly when the root has odd multiplicity in f.
    bool odd = false;
    if (root.exact()) {
      Poly derivative_k = f;
      int order = 0;
      while (sign_at_exact(derivative_k, root.lo) == 0) {
        derivative_k = derivative(derivative_k);
        ++order;
      }
      odd = order % 2 == 1;
    } else {
      odd = sign_at(f, root.lo) * sign_at(f, root.hi) < 0;  // f has no other root in the interval
    }
    if (!odd) continue;
    const auto zero_at = [&](const Poly& q) { return sign_at_root(root_poly, root, q) == 0; };
    const auto nonnegative_at = [&](const Poly& q) { return sign_at_root(root_poly, root, q) >= 0; };
    // In the closed triangle at the root: strictly or on the boundary of a non-degenerate face ...
    std::array<int, 3> g_sign{};
    for (int i = 0; i < 3; ++i) {
      g_sign[i] =
          sign_at_root(root_poly, root, dot(cross(sub(tri[(i + 1) % 3], p), sub(tri[(i + 2) % 3], p)), n));
    }
    if (g_sign[0] >= 0 && g_sign[1] >= 0 && g_sign[2] >= 0 && (g_sign[0] + g_sign[1] + g_sign[2]) > 0)
      return true;
    // ... or on an edge or a vertex of a degenerate one.
    for (int i = 0; i < 3; ++i) {
      const PolyVec& u = tri[i];
      const PolyVec e = sub(tri[(i + 1) % 3], u);
      const PolyVec r = sub(p, u);
      const Poly ee = dot(e, e);
      if (zero_at(ee)) {
        if (zero_at(r[0]) && zero_at(r[1]) && zero_at(r[2])) return true;  // on the vertex u = w
        continue;
      }
      const PolyVec c = cross(r, e);
      const Poly along = dot(r, e);
      if (zero_at(c[0]) && zero_at(c[1]) && zero_at(c[2]) && nonnegative_at(along) &&
          nonnegative_at(sub(ee, along)))
        return true;
    }
  }
  return false;
}

}  // namespace drench::ccd
