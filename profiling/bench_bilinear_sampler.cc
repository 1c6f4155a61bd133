// Throughput of the bilinear_sample kernel against its double-precision
// reference on synthetic batches. The device comes from SAPMVS_DEVICE (default
// device otherwise), e.g.
//   SAPMVS_DEVICE=pocl ./build/bench_bilinear_sampler --benchmark_counters_tabular=true
// Kernel timings use wall time (the host thread only waits), the DeviceTime
// variant the queue's profiling timestamps.

#include <benchmark/benchmark.h>

#include <exception>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_context.h"
#include "device/bilinear_sampler.h"
#include "device/cl_runtime.h"

namespace sapmvs {
namespace {

constexpr int kWidth = 1024;
constexpr int kHeight = 768;

struct Batch {
  std::vector<float> pixels;
  FloatImageView image;
  std::vector<Eigen::Vector2f> points;
};

// A random image and points spread slightly beyond it, so a few percent take
// the NaN path as in real matching near image borders.
Batch MakeBatch(int num_points) {
  Batch batch;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(0.0f, 255.0f);
  batch.pixels.resize(static_cast<size_t>(kWidth) * kHeight);
  for (float& p : batch.pixels) p = value(rng);
  batch.image = {batch.pixels.data(), {kWidth, kHeight, kWidth}};
  std::uniform_real_distribution<float> x(-4.0f, kWidth + 3.0f);
  std::uniform_real_distribution<float> y(-4.0f, kHeight + 3.0f);
  batch.points.reserve(num_points);
  for (int i = 0; i < num_points; ++i) batch.points.emplace_back(x(rng), y(rng));
  return batch;
}

using bench::Shared;
using bench::SharedContext;

void SetRate(benchmark::State& state, int num_points) {
  state.counters["samples/s"] =
      benchmark::Counter(static_cast<double>(num_points) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}

// Device-resident: the kernel alone, as the matching pipeline will use it.
void RunKernel(benchmark::State& state, bool device_time) {
  SharedContext& shared = Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  ClContext& context = *shared.context;
  const int n = static_cast<int>(state.range(0));
  const Batch batch = MakeBatch(n);
  const size_t image_bytes = batch.pixels.size() * sizeof(float);
  ClBuffer image(context, image_bytes, CL_MEM_READ_ONLY);
  image.Write(batch.pixels.data(), image_bytes);
  const size_t point_bytes = batch.points.size() * sizeof(Eigen::Vector2f);
  ClBuffer points(context, point_bytes, CL_MEM_READ_ONLY);
  points.Write(batch.points.data(), point_bytes);
  ClBuffer values(context, static_cast<size_t>(n) * sizeof(float), CL_MEM_WRITE_ONLY);
  BilinearSampler sampler(context);
  sampler.Sample(image, batch.image.layout, points, n, values).Wait();  // Warm-up.

  for (auto _ : state) {
    ClEvent event = sampler.Sample(image, batch.image.layout, points, n, values);
    event.Wait();
    if (device_time) state.SetIterationTime(static_cast<double>(event.DeviceTimeNs()) * 1e-9);
  }
  SetRate(state, n);
}

void BM_BilinearKernel(benchmark::State& state) { RunKernel(state, false); }
void BM_BilinearKernelDeviceTime(benchmark::State& state) { RunKernel(state, true); }

// Host in, host out: buffer allocation and both transfers included.
void BM_BilinearKernelRoundTrip(benchmark::State& state) {
  SharedContext& shared = Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  const int n = static_cast<int>(state.range(0));
  const Batch batch = MakeBatch(n);
  BilinearSampler sampler(*shared.context);
  for (auto _ : state) {
    std::vector<float> values = sampler.Sample(batch.image, batch.points);
    benchmark::DoNotOptimize(values.data());
  }
  SetRate(state, n);
}

void BM_BilinearReference(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Batch batch = MakeBatch(n);
  for (auto _ : state) {
    std::vector<double> values = BilinearSampleReference(batch.image, batch.points);
    benchmark::DoNotOptimize(values.data());
  }
  SetRate(state, n);
}

BENCHMARK(BM_BilinearKernel)
    ->RangeMultiplier(16)
    ->Range(1 << 10, 1 << 22)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BilinearKernelDeviceTime)
    ->RangeMultiplier(16)
    ->Range(1 << 10, 1 << 22)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BilinearKernelRoundTrip)
    ->RangeMultiplier(16)
    ->Range(1 << 10, 1 << 22)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BilinearReference)
    ->RangeMultiplier(16)
    ->Range(1 << 10, 1 << 22)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace sapmvs

int main(int argc, char** argv) { return sapmvs::bench::RunMain(argc, argv); }
