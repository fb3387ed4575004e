// Point-triangle CCD on the labelled vertex-face queries of ../shared/data/ccd-vertex-face (Wang et al. 2021
// handcrafted sample; Belgrod et al. 2023 simulation sample; README.md there). The targets: mean time
// per query at most 5 us on the handcrafted part and 2 us on the simulation part, no miss. Tight-Inclusion,
// for comparison, misses none either but reports false positives and is far slower (docs/performance.md).
//
//   build-b/bench/bench_ccd --benchmark_out=bench/results/<machine>/ccd.csv --benchmark_out_format=csv
//       [--benchmark_filter='^ccd/(handcrafted|simulation-belgrod2023)$']
//
// Benchmarks: ccd/<part> and ccd/<part>/<file> time point_triangle_ccd over all queries of the part or file
// per iteration; ccd_exact/... the exact rational reference (point_triangle_ccd_exact), on the handcrafted
// part and cloth-funnel only because it is slow. Counters: us_per_query, false_negatives, false_positives
// (per pass over the queries), exact_fraction (share decided by the exact path), queries.
// One thread; the queries are read once, before any benchmark, and never timed.

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/ccd/ccd_query_file.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/error.hpp>

namespace {

using drench::ccd::CcdBenchmarkQuery;
namespace fs = std::filesystem;

/// The answer of one solver to one query, reduced to what the counters need.
struct Decision {
  bool hit = false;
  bool exact = false;  ///< decided by the exact rational path
};

Decision fast_solver(const drench::ccd::VertexFaceQuery& query) {
  const drench::ccd::CcdResult result = drench::ccd::point_triangle_ccd(query);
  return {result.hit, result.path == drench::ccd::CcdPath::EXACT};
}

Decision exact_solver(const drench::ccd::VertexFaceQuery& query) {
  return {drench::ccd::point_triangle_ccd_exact(query).hit, true};
}

/// Times `Solve` over every query of `queries` per iteration; the counts come from the last pass (the
/// solvers are deterministic, so every pass gives the same). A template, so no indirect call is timed.
template <Decision (*Solve)(const drench::ccd::VertexFaceQuery&)>
void run(benchmark::State& state, const std::vector<CcdBenchmarkQuery>& queries) {
  std::vector<Decision> decisions(queries.size());
  double seconds = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < queries.size(); ++i)
      decisions[i] = Solve(queries[i].query);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    benchmark::DoNotOptimize(decisions.data());
    benchmark::ClobberMemory();
    seconds += wall;
  }
  std::size_t false_negatives = 0, false_positives = 0, exact = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    false_negatives += queries[i].collides && !decisions[i].hit ? 1 : 0;
    false_positives += !queries[i].collides && decisions[i].hit ? 1 : 0;
    exact += decisions[i].exact ? 1 : 0;
  }
  const double n = static_cast<double>(queries.size());
  state.counters["queries"] = n;
  state.counters["us_per_query"] = 1e6 * seconds / (static_cast<double>(state.iterations()) * n);
  state.counters["false_negatives"] = static_cast<double>(false_negatives);
  state.counters["false_positives"] = static_cast<double>(false_positives);
  state.counters["exact_fraction"] = static_cast<double>(exact) / n;
}

constexpr const char* kDataDir = DRENCH_SOURCE_DIR "/../shared/data/ccd-vertex-face";

/// The data folder next to the repository, or std::nullopt when it is missing.
std::optional<std::string> data_dir() {
  std::error_code error;
  const fs::path dir = fs::weakly_canonical(kDataDir, error);
  if (error || !fs::is_directory(dir, error)) return std::nullopt;
  return dir.string();
}

/// A named set of queries; lives until the end of main, so the benchmarks can hold references to it.
struct QuerySet {
  std::string name;
  std::vector<CcdBenchmarkQuery> queries;
};

template <Decision (*Solve)(const drench::ccd::VertexFaceQuery&)>
void register_set(const std::string& prefix, const QuerySet& set) {
  benchmark::RegisterBenchmark((prefix + "/" + set.name).c_str(), [&set](benchmark::State& state) {
    run<Solve>(state, set.queries);
  })->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  const std::optional<std::string> dir = data_dir();
  if (!dir) {
    std::fprintf(stderr,
                 "bench_ccd: CCD query data not found at %s (the ccd-vertex-face set lives next to the "
                 "repository, in ../shared/data)\n",
                 fs::path(kDataDir).lexically_normal().c_str());
    return 1;
  }

  // Parts are the data folder's subfolders (handcrafted, simulation-belgrod2023); files are named without
  // the .vf.txt suffix, e.g. simulation-belgrod2023/cloth-funnel-227.
  std::map<std::string, QuerySet> parts;
  std::vector<QuerySet> files;
  try {
    for (const std::string& path : drench::ccd::list_ccd_query_files(*dir)) {
      const fs::path relative = fs::path(path).lexically_relative(*dir);
      std::string name = relative.generic_string();
      name.erase(name.size() - std::string(".vf.txt").size());
      QuerySet file{name, drench::ccd::read_ccd_query_file(path)};
      const std::string part = relative.begin()->string();
      QuerySet& set = parts[part];
      set.name = part;
      set.queries.insert(set.queries.end(), file.queries.begin(), file.queries.end());
      files.push_back(std::move(file));
    }
  } catch (const drench::Error& e) {
    std::fprintf(stderr, "bench_ccd: %s\n", e.what());
    return 1;
  }

  for (const auto& [name, set] : parts)
    register_set<fast_solver>("ccd", set);
  for (const QuerySet& file : files)
    register_set<fast_solver>("ccd", file);
  // The reference is tens of microseconds per query or more: the handcrafted part and the one simulation
  // file with many negatives keep a run short.
  const auto handcrafted = parts.find("handcrafted");
  if (handcrafted != parts.end()) register_set<exact_solver>("ccd_exact", handcrafted->second);
  for (const QuerySet& file : files) {
    if (file.name == "simulation-belgrod2023/cloth-funnel-227") register_set<exact_solver>("ccd_exact", file);
  }

  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
