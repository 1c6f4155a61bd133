// Throughput of the ncc_score kernel against its double-precision reference on
// a synthetic batch: 4 random textured 640x480 images, one nadir-ish camera
// each over a ground plane, patches under random reference pixels, each paired
// with the three other images. The device comes from SAPMVS_DEVICE (default
// device otherwise), e.g.
//   SAPMVS_DEVICE=pocl ./build/profiling/bench_ncc_scorer --benchmark_counters_tabular=true
// "pairs/s" counts (patch, view) scores; "ncc_samples/s" counts the 2 μ²
// bilinear samples behind each. Kernel runs use wall time for the whole
// Score() round trip (batch upload, kernel, read-back: what the matcher pays);
// the DeviceTime variant the kernel's profiling timestamps only, and reports
// "of_probe": its pairs/s as a fraction of the roofline probe's NCC windows/s
// at the same mu (kernels/roofline_probe.cl; BM_RooflineNccWindows measures
// it, BM_RooflineCopy the device's memory bandwidth).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <exception>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_batch.h"
#include "bench_context.h"
#include "device/cl_runtime.h"
#include "device/ncc_scorer.h"
#include "device/roofline_probe.h"

namespace sapmvs {
namespace {

using bench::Shared;
using bench::SharedContext;

void SetRates(benchmark::State& state, int num_pairs, int patch_size) {
  const double pairs = static_cast<double>(num_pairs) * static_cast<double>(state.iterations());
  state.counters["pairs/s"] = benchmark::Counter(pairs, benchmark::Counter::kIsRate);
  state.counters["ncc_samples/s"] =
      benchmark::Counter(pairs * 2.0 * patch_size * patch_size, benchmark::Counter::kIsRate);
}

void RunKernel(benchmark::State& state, bool device_time) {
  SharedContext& shared = Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  const int num_pairs = static_cast<int>(state.range(0));
  NccScorerOptions options;
  options.patch_size = static_cast<int>(state.range(1));
  const Batch batch = MakeBatch(num_pairs);
  NccScorer scorer(*shared.context, options);
  scorer.SetGroup(batch.group);              // Once: the images stay on the device.
  scorer.Score(batch.patches, batch.pairs);  // Warm-up.
  for (auto _ : state) {
    ClEvent event;
    std::vector<float> scores = scorer.Score(batch.patches, batch.pairs, &event);
    benchmark::DoNotOptimize(scores.data());
    if (device_time) state.SetIterationTime(static_cast<double>(event.DeviceTimeNs()) * 1e-9);
  }
  SetRates(state, num_pairs, options.patch_size);
}

// Contiguous windows: 2^18 pairs tiled over two random 1024 x 1024 images,
// a window and its right neighbour, so reads are as coalesced as they get.
struct ProbeBatch {
  int width = 1024, height = 1024;
  std::vector<float> a, b;
  std::vector<cl_int4> corners;
};

ProbeBatch MakeProbeBatch(int patch_size, int num_pairs) {
  ProbeBatch p;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(0.0f, 255.0f);
  p.a.resize(static_cast<size_t>(p.width) * p.height);
  p.b.resize(p.a.size());
  for (float& v : p.a) v = value(rng);
  for (float& v : p.b) v = value(rng);
  const int per_row = p.width - patch_size;
  for (int i = 0; i < num_pairs; ++i) {
    const int x = i % per_row, y = (i / per_row) % (p.height - patch_size);
    p.corners.push_back({{x, y, x + 1 > per_row - 1 ? x : x + 1, y}});
  }
  return p;
}

// Best device-time rate of the probe's NCC windows, pairs/s, for `patch_size`
// (measured once per size per process).
double ProbeNccRate(ClContext& context, int patch_size) {
  static std::map<int, double> rates;
  if (rates.count(patch_size)) return rates[patch_size];
  constexpr int kPairs = 1 << 18;
  const ProbeBatch p = MakeProbeBatch(patch_size, kPairs);
  RooflineProbeOptions o;
  o.patch_size = patch_size;
  RooflineProbe probe(context, o);
  const size_t pixels = p.a.size();
  ClBuffer a(context, pixels * sizeof(float)), b(context, pixels * sizeof(float));
  a.WriteVector(p.a);
  b.WriteVector(p.b);
  ClBuffer corners(context, p.corners.size() * sizeof(cl_int4));
  corners.WriteVector(p.corners);
  ClBuffer scores(context, p.corners.size() * sizeof(float));
  double best = 0;
  for (int k = 0; k < 5; ++k) {
    ClEvent e = probe.NccWindows(a, b, p.width, p.height, corners, kPairs, scores);
    e.Wait();
    best = std::max(best, kPairs / (1e-9 * static_cast<double>(e.DeviceTimeNs())));
  }
  return rates[patch_size] = best;
}

void BM_NccKernel(benchmark::State& state) { RunKernel(state, false); }
void BM_NccKernelDeviceTime(benchmark::State& state) {
  RunKernel(state, true);
  SharedContext& shared = Shared();
  if (!shared.context) return;
  const double probe = ProbeNccRate(*shared.context, static_cast<int>(state.range(1)));
  // pairs/s over device time (manual time) divided by the probe's.
  const double pairs = static_cast<double>(state.range(0)) * state.iterations();
  state.counters["of_probe"] = benchmark::Counter(pairs / probe, benchmark::Counter::kIsRate);
}

void BM_RooflineNccWindows(benchmark::State& state) {
  SharedContext& shared = Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  const int patch_size = static_cast<int>(state.range(0));
  constexpr int kPairs = 1 << 18;
  const ProbeBatch p = MakeProbeBatch(patch_size, kPairs);
  RooflineProbeOptions o;
  o.patch_size = patch_size;
  RooflineProbe probe(*shared.context, o);
  ClBuffer a(*shared.context, p.a.size() * sizeof(float));
  ClBuffer b(*shared.context, p.b.size() * sizeof(float));
  a.WriteVector(p.a);
  b.WriteVector(p.b);
  ClBuffer corners(*shared.context, p.corners.size() * sizeof(cl_int4));
  corners.WriteVector(p.corners);
  ClBuffer scores(*shared.context, p.corners.size() * sizeof(float));
  for (auto _ : state) {
    ClEvent e = probe.NccWindows(a, b, p.width, p.height, corners, kPairs, scores);
    e.Wait();
    state.SetIterationTime(1e-9 * static_cast<double>(e.DeviceTimeNs()));
  }
  SetRates(state, kPairs, patch_size);
}

void BM_RooflineCopy(benchmark::State& state) {
  SharedContext& shared = Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  const int n = static_cast<int>(state.range(0));  // float4 elements
  ClBuffer src(*shared.context, static_cast<size_t>(n) * sizeof(cl_float4));
  ClBuffer dst(*shared.context, static_cast<size_t>(n) * sizeof(cl_float4));
  src.WriteVector(std::vector<cl_float4>(n, cl_float4{{1, 2, 3, 4}}));
  RooflineProbe probe(*shared.context);
  for (auto _ : state) {
    ClEvent e = probe.Copy(src, dst, n);
    e.Wait();
    state.SetIterationTime(1e-9 * static_cast<double>(e.DeviceTimeNs()));
  }
  // Read and write: 2 x 16 bytes per element.
  state.counters["bytes/s"] =
      benchmark::Counter(32.0 * n * state.iterations(), benchmark::Counter::kIsRate,
                         benchmark::Counter::OneK::kIs1024);
}

void BM_NccReference(benchmark::State& state) {
  const int num_pairs = static_cast<int>(state.range(0));
  const int patch_size = static_cast<int>(state.range(1));
  const Batch batch = MakeBatch(num_pairs);
  for (auto _ : state) {
    std::vector<double> scores =
        NccScoreReference(batch.group, batch.patches, batch.pairs, patch_size);
    benchmark::DoNotOptimize(scores.data());
  }
  SetRates(state, num_pairs, patch_size);
}

BENCHMARK(BM_NccKernel)
    ->ArgsProduct({{20000}, {7, 11}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NccKernelDeviceTime)
    ->ArgsProduct({{20000}, {7, 11}})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RooflineNccWindows)
    ->Arg(7)
    ->Arg(11)
    ->Arg(21)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RooflineCopy)->Arg(1 << 22)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NccReference)
    ->ArgsProduct({{20000}, {7, 11}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sapmvs

int main(int argc, char** argv) { return sapmvs::bench::RunMain(argc, argv); }
