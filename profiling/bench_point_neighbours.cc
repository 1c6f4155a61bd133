// Throughput of NearestWithin, the filter's neighbour search (the largest
// host cost of a filter pass: 11 % of a run's CPU time on the simulator's
// `city`, 9 % on Herz-Jesu-P8), on a synthetic cloud shaped as the matcher
// emits one: overlapping patches of points a working pixel apart on a rough
// surface, radii varying per point as slope footprints do. E.g.
//   ./build/profiling/bench_point_neighbours --benchmark_counters_tabular=true
// Host threads: OpenMP's default (OMP_NUM_THREADS).

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "match/point_neighbours.h"

namespace sapmvs {
namespace {

struct Cloud {
  std::vector<float> xyz;
  std::vector<double> radius;
};

// `n` points in square patches of 15 x 15 points (the 7 x 7 patches' emitted
// grids, about) at random places over a surface with relief, each patch a
// little off the surface as a matched plane is; two patches in three overlap
// another one.
Cloud MakeCloud(int n) {
  Cloud cloud;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0, 1);
  std::normal_distribution<float> noise(0, 0.15f);
  const int per_patch = 15 * 15;
  const int patches = (n + per_patch - 1) / per_patch;
  const float side = std::sqrt(static_cast<float>(patches) / 1.5f) * 15.0f;
  cloud.xyz.reserve(3 * static_cast<size_t>(n));
  for (int p = 0; p < patches && static_cast<int>(cloud.radius.size()) < n; ++p) {
    const float x0 = unit(rng) * side, y0 = unit(rng) * side, dz = noise(rng);
    const double r = 2.5 * (1.0 + 0.6 * unit(rng));
    for (int j = 0; j < per_patch && static_cast<int>(cloud.radius.size()) < n; ++j) {
      const float x = x0 + static_cast<float>(j % 15), y = y0 + static_cast<float>(j / 15);
      const float z = 3.0f * std::sin(0.05f * x) * std::cos(0.04f * y) + dz;
      cloud.xyz.insert(cloud.xyz.end(), {x + 5000.0f, y - 3000.0f, z + 120.0f});
      cloud.radius.push_back(r);
    }
  }
  return cloud;
}

void BM_NearestWithin(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Cloud cloud = MakeCloud(n);
  for (auto _ : state) {
    std::vector<float> xyz = cloud.xyz;
    auto nn = NearestWithin(std::move(xyz), cloud.radius, 16);
    benchmark::DoNotOptimize(nn.data());
  }
  state.counters["points/s"] =
      benchmark::Counter(static_cast<double>(n) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}
BENCHMARK(BM_NearestWithin)->Arg(10007)->Arg(400009)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace sapmvs

BENCHMARK_MAIN();
