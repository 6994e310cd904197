// Pixel-hypotheses per second (pixels x offsets x neighbours) of the C++ reference sweep on the
// synthetic pyramid (sweep/sweep_test_scene.h) at 640x480 and 1280x960, default options
// (N = 20, sigma = 8 px, 100 px tiles, full resolution), on one thread (OpenCV's filters would
// otherwise use every core, which makes numbers on a shared machine meaningless). The rate is per
// CPU second of that thread. Numbers: docs/sweep.md.
#include <benchmark/benchmark.h>

#include <map>
#include <opencv2/core/utility.hpp>

#include "sweep/reference_sweep.h"
#include "sweep/sweep_test_scene.h"

namespace ms {
namespace {

const SweepJob& JobFor(int width) {
  static std::map<int, SweepJob> jobs;
  auto it = jobs.find(width);
  if (it != jobs.end()) return it->second;
  return jobs.emplace(width, MakeBenchmarkSweepJob(width)).first->second;
}

void BM_ReferenceSweep(benchmark::State& state) {
  cv::setNumThreads(1);
  const SweepJob& job = JobFor(static_cast<int>(state.range(0)));
  ReferenceSweepKernel kernel;
  int64_t hypotheses = 0;
  SweepStats last;
  for (auto _ : state) {
    const SweepResult result = kernel.Run(job);
    hypotheses += result.stats.hypotheses;
    last = result.stats;
    benchmark::DoNotOptimize(result.points.data());
  }
  state.counters["hypotheses/s"] =
      benchmark::Counter(static_cast<double>(hypotheses), benchmark::Counter::kIsRate);
  state.counters["raster_s"] = last.raster_s;
  state.counters["reproject_s"] = last.reproject_s;
  state.counters["ncc_s"] = last.ncc_s;
}
BENCHMARK(BM_ReferenceSweep)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ms

BENCHMARK_MAIN();
