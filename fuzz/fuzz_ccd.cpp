/// libFuzzer target: the fast point-triangle CCD (point_triangle_ccd) against the exact GMP reference
/// (point_triangle_ccd_exact) on queries decoded by ccd_fuzz_input.hpp, which makes degenerate cases
/// frequent. Aborts, after printing the query (24 doubles, %.17g, in the data files' order) and both answers,
/// when:
///   - a non-finite query does not throw InvalidQueryError from both solvers;
///   - the fast and the exact contact decisions differ;
///   - the fast toi is not a valid lower bound: the true first contact t* is in [toi, toi + toi_tolerance]
///     (point_triangle_ccd.hpp) and in [toi_lower, toi_upper] (ccd_exact_reference.hpp), so
///     toi <= toi_upper and toi + toi_tolerance >= toi_lower must hold;
///   - an output is NaN or infinite, toi is outside [0, 1], a barycentric weight is outside [0, 1] or the
///     weights do not sum to 1 within 1e-12, a miss does not report toi 1 and zero weights;
///   - two calls on the same query disagree (catches reads of uninitialised memory, which ASan does not).
/// Run it with scripts/fuzz; scripts/test replays fuzz/corpus/ccd and fuzz/regressions/ccd.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include "ccd_fuzz_input.hpp"

namespace {

using drench::ccd::CcdResult;
using drench::ccd::CcdSettings;
using drench::ccd::ExactCcdResult;
using drench::ccd::VertexFaceQuery;

/// The exact bracket is asked this much narrower than the fast one, so that a fast toi off by more than
/// toi_tolerance cannot hide in the width of the reference's bracket.
constexpr double kExactTighteningFactor = 1.0 / 16.0;

void print_query(const VertexFaceQuery& query) {
  std::fprintf(stderr, "query (p_t0 a_t0 b_t0 c_t0 p_t1 a_t1 b_t1 c_t1, x y z each):\n");
  const auto x = drench::fuzz::query_coordinates(query);
  for (int i = 0; i < 24; ++i)
    std::fprintf(stderr, "%.17g%c", x[i], i == 23 ? '\n' : ' ');
}

void print_fast(const char* name, const CcdResult& r) {
  std::fprintf(stderr, "%s: hit %d toi %.17g barycentric %.17g %.17g %.17g path %d\n", name, r.hit ? 1 : 0,
               r.toi, r.barycentric[0], r.barycentric[1], r.barycentric[2], static_cast<int>(r.path));
}

[[noreturn]] void fail(const VertexFaceQuery& query, const std::string& why, const CcdResult* fast = nullptr,
                       const ExactCcdResult* exact = nullptr) {
  std::fprintf(stderr, "\nfuzz_ccd: %s\n", why.c_str());
  print_query(query);
  if (fast != nullptr) print_fast("fast", *fast);
  if (exact != nullptr) {
    std::fprintf(stderr, "exact: hit %d toi in [%.17g, %.17g]\n", exact->hit ? 1 : 0, exact->toi_lower,
                 exact->toi_upper);
  }
  std::fflush(stderr);
  std::abort();
}

bool query_finite(const VertexFaceQuery& query) {
  for (double x : drench::fuzz::query_coordinates(query)) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

/// Both solvers must reject a non-finite query with InvalidQueryError, and with nothing else.
void check_rejected(const VertexFaceQuery& query) {
  const auto expect_invalid = [&](const char* name, auto&& call) {
    try {
      call();
    } catch (const drench::ccd::InvalidQueryError&) {
      return;
    } catch (const std::exception& e) {
      fail(query, std::string(name) + " threw another exception on a non-finite query: " + e.what());
    } catch (...) {
      fail(query, std::string(name) + " threw a non-std exception on a non-finite query");
    }
    fail(query, std::string(name) + " accepted a non-finite query without throwing InvalidQueryError");
  };
  expect_invalid("point_triangle_ccd", [&] { drench::ccd::point_triangle_ccd(query); });
  expect_invalid("point_triangle_ccd_exact", [&] { drench::ccd::point_triangle_ccd_exact(query); });
}

/// The contract of CcdResult alone (point_triangle_ccd.hpp), whatever the reference says.
void check_result_contract(const VertexFaceQuery& query, const CcdResult& fast) {
  const auto& w = fast.barycentric;
  if (!std::isfinite(fast.toi) || !w.allFinite()) fail(query, "non-finite output", &fast);
  if (!(fast.toi >= 0.0 && fast.toi <= 1.0)) fail(query, "toi outside [0, 1]", &fast);
  if (fast.path != drench::ccd::CcdPath::FILTER && fast.path != drench::ccd::CcdPath::EXACT) {
    fail(query, "path is neither FILTER nor EXACT", &fast);
  }
  if (!fast.hit) {
    if (fast.toi != 1.0 || w != drench::Vec3::Zero())
      fail(query, "a miss must report toi 1, weights 0", &fast);
    return;
  }
  for (int k = 0; k < 3; ++k) {
    if (!(w[k] >= 0.0 && w[k] <= 1.0)) fail(query, "barycentric weight outside [0, 1]", &fast);
  }
  if (!(std::fabs(w.sum() - 1.0) <= 1e-12)) fail(query, "barycentric weights do not sum to 1 (1e-12)", &fast);
}

bool same_result(const CcdResult& a, const CcdResult& b) {
  return a.hit == b.hit && a.toi == b.toi && a.barycentric == b.barycentric && a.path == b.path;
}

void check_against_exact(const VertexFaceQuery& query) {
  const CcdSettings settings;
  CcdResult fast;
  ExactCcdResult exact;
  try {
    fast = drench::ccd::point_triangle_ccd(query, settings);
    check_result_contract(query, fast);
    if (!same_result(fast, drench::ccd::point_triangle_ccd(query, settings))) {
      fail(query, "two calls on the same query disagree", &fast);
    }
    exact =
        drench::ccd::point_triangle_ccd_exact(query, 0.0, settings.toi_tolerance * kExactTighteningFactor);
  } catch (const std::exception& e) {
    fail(query, std::string("exception on a finite query: ") + e.what());
  }
  if (fast.hit != exact.hit) fail(query, "fast and exact contact decisions differ", &fast, &exact);
  if (!fast.hit) return;
  if (!(fast.toi <= exact.toi_upper)) {
    fail(query, "fast toi is later than the exact bracket: not a lower bound", &fast, &exact);
  }
  // The sum in long double (64-bit significand): its rounding is far below the doubles compared.
  const long double fast_upper = static_cast<long double>(fast.toi) + settings.toi_tolerance;
  if (!(fast_upper >= static_cast<long double>(exact.toi_lower))) {
    fail(query, "fast toi + toi_tolerance is earlier than the exact bracket", &fast, &exact);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const VertexFaceQuery query = drench::fuzz::decode_query(data, size);
  if (!query_finite(query)) {
    check_rejected(query);
  } else {
    check_against_exact(query);
  }
  return 0;
}
