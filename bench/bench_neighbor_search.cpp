// The fluid's grid search alone: build + find on a block of 39^3 = 59,319 points at spacing 0.025 m, jittered
// by up to 0.1 spacing and z-ordered as the fluid solver keeps its particles, support 0.05 m (the 59K dam
// break's). Fluid onto itself, self excluded. Argument: the scan (NeighborSearch::set_candidate_scan), 2
// AVX-512's compress (the default where the CPU has it), 1 AVX2's permute, 0 four lanes (CPUs without AVX2).
//
//   build-bench/bench/bench_neighbor_search --benchmark_repetitions=5
// Thread count: OMP_NUM_THREADS.

#include <benchmark/benchmark.h>

#include <random>

#include <drench/sph/neighbor_search.hpp>

namespace {

void build_and_find_59k(benchmark::State& state) {
  const double spacing = 0.025;  // m
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> jitter(-0.1 * spacing, 0.1 * spacing);
  drench::Vec3Array lattice;
  for (int a = 0; a < 39; ++a) {
    for (int b = 0; b < 39; ++b) {
      for (int c = 0; c < 39; ++c)
        lattice.emplace_back(a * spacing + jitter(rng), b * spacing + jitter(rng), c * spacing + jitter(rng));
    }
  }
  drench::NeighborSearch search(2.0 * spacing);
  if (!search.set_candidate_scan(static_cast<drench::CandidateScan>(state.range(0)))) {
    state.SkipWithError("this CPU or build cannot run this scan");
    return;
  }
  const drench::IndexArray order = search.z_order(lattice);
  drench::Vec3Array points(lattice.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    points[k] = lattice[order[k]];
  drench::NeighborList list;
  for (auto _ : state) {
    search.build(points);
    search.find(points, list, /*exclude_self=*/true);
    benchmark::DoNotOptimize(list.indices.data());
  }
  state.counters["pairs"] = static_cast<double>(list.indices.size());
  state.counters["queries_per_s"] =
      benchmark::Counter(static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(build_and_find_59k)->Arg(2)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
