// Throughput of the patch_refine kernel against its double-precision
// reference on the shared synthetic batch (bench_batch.h): each patch is
// refined against its three views, starting a quarter of a footprint off the
// plane and with its normal tilted 10 degrees, as propagation candidates
// start. "patches/s" counts refined patches; "ncc_evals/s" the (1 + 6 x
// iterations) x views NCC evaluations each patch's search scores at most
// (an early stop after max_halvings scores fewer).
// The fourth argument picks the layout (RefineLayout: 1 a work-item per
// patch, 2 a work-group).
//   SAPMVS_DEVICE=pocl ./build/profiling/bench_patch_refiner --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "bench_batch.h"
#include "bench_context.h"
#include "device/patch_refiner.h"

namespace sapmvs {
namespace {

struct RefineBatch {
  Batch batch;
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
};

RefineBatch MakeRefineBatch(int num_patches) {
  RefineBatch r;
  r.batch = MakeBatch(3 * num_patches);
  const double tilt = 10.0 * M_PI / 180.0;
  for (const NccPatch& p : r.batch.patches) {
    NccPatch q = p;
    q.center.s[2] += 0.25f * 40.0f / 600.0f;  // a quarter footprint up
    q.normal = {
        {static_cast<float>(std::sin(tilt)), 0.0f, static_cast<float>(std::cos(tilt)), 0.0f}};
    r.patches.push_back(q);
    std::vector<int> v;
    for (int i = 0; i < kNumImages; ++i)
      if (i != p.reference) v.push_back(i);
    r.views.push_back(v);
  }
  return r;
}

void SetRates(benchmark::State& state, const RefineBatch& r, const PatchRefinerOptions& o) {
  const double patches = static_cast<double>(r.patches.size()) * state.iterations();
  state.counters["patches/s"] = benchmark::Counter(patches, benchmark::Counter::kIsRate);
  state.counters["ncc_evals/s"] =
      benchmark::Counter(patches * 3.0 * (1 + 6 * o.iterations), benchmark::Counter::kIsRate);
}

void BM_RefineKernelDeviceTime(benchmark::State& state) {
  bench::SharedContext& shared = bench::Shared();
  if (!shared.context) {
    state.SkipWithError(shared.error.c_str());
    return;
  }
  PatchRefinerOptions o;
  o.patch_size = static_cast<int>(state.range(1));
  o.max_halvings = static_cast<int>(state.range(2));
  o.layout = state.range(3) == 1 ? RefineLayout::kPatchPerItem : RefineLayout::kPatchPerGroup;
  const RefineBatch r = MakeRefineBatch(static_cast<int>(state.range(0)));
  PatchRefiner refiner(*shared.context, o);
  refiner.SetGroup(r.batch.group);
  refiner.Refine(r.patches, r.views);  // warm-up
  for (auto _ : state) {
    ClEvent event;
    std::vector<RefinedPatch> out = refiner.Refine(r.patches, r.views, &event);
    benchmark::DoNotOptimize(out.data());
    state.SetIterationTime(1e-9 * static_cast<double>(event.DeviceTimeNs()));
  }
  SetRates(state, r, o);
}

void BM_RefineReference(benchmark::State& state) {
  PatchRefinerOptions o;
  o.patch_size = static_cast<int>(state.range(1));
  const RefineBatch r = MakeRefineBatch(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    std::vector<RefinedPatchReference> out =
        PatchRefineReference(r.batch.group, r.patches, r.views, o);
    benchmark::DoNotOptimize(out.data());
  }
  SetRates(state, r, o);
}

// Third argument: max_halvings, the default against never stopping early
// (kMaxRefineIterations), to show what the early stop saves on a device.
// Fourth: the layout, 1 a work-item per patch, 2 a work-group (RefineLayout);
// 64 patches is a launch of the polish sizes (about 60 on Herz-Jesu-P8).
BENCHMARK(BM_RefineKernelDeviceTime)
    ->ArgsProduct({{2000, 64}, {7, 21}, {kDefaultRefineHalvings}, {1, 2}})
    ->ArgsProduct({{2000}, {7, 21}, {kMaxRefineIterations}, {1}})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineReference)
    ->Args({100, 7})
    ->Args({20, 21})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sapmvs

int main(int argc, char** argv) { return sapmvs::bench::RunMain(argc, argv); }
