// Pixel-hypotheses per second (pixels x offsets x neighbours) of the GLSL sweep kernel, against
// the C++ reference on the same jobs and in the same process: the synthetic pyramid
// (sweep/sweep_test_scene.h) at 640x480 and 1280x960, default options (N = 20, sigma = 8 px,
// 100 px tiles, full resolution). Whatever GlContext picks runs it: llvmpipe on a CPU machine,
// the GPU where there is one. Counters: hypotheses per second of wall time and per second of
// process CPU time (all threads: llvmpipe's workers, OpenCV pinned to one thread), per-stage
// seconds, and whether the two kernels found the same tile winners. Numbers: docs/sweep.md.
#include <benchmark/benchmark.h>

#include <ctime>
#include <map>
#include <memory>
#include <opencv2/core/utility.hpp>

#include "base/log.h"
#include "sweep/glsl_sweep.h"
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

double ProcessCpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

GlslSweepKernel& Kernel() {
  static std::unique_ptr<GlslSweepKernel> kernel = [] {
    auto k = std::make_unique<GlslSweepKernel>();
    spdlog::info("GL: {}", k->gl_info().Summary());
    return k;
  }();
  return *kernel;
}

// The reference's result per image width, to compare the GLSL kernel's winners with.
const SweepResult& ReferenceResult(int width) {
  static std::map<int, SweepResult> results;
  auto it = results.find(width);
  if (it == results.end()) {
    cv::setNumThreads(1);
    it = results.emplace(width, ReferenceSweepKernel().Run(JobFor(width))).first;
  }
  return it->second;
}

void Report(benchmark::State& state, int64_t hypotheses, double wall, double cpu,
            const SweepStats& last) {
  state.counters["hyp/s_wall"] = static_cast<double>(hypotheses) / wall;
  state.counters["hyp/s_cpu"] = static_cast<double>(hypotheses) / cpu;
  state.counters["raster_s"] = last.raster_s;
  state.counters["reproject_s"] = last.reproject_s;
  state.counters["ncc_s"] = last.ncc_s;
  state.counters["reduce_s"] = last.reduce_s;
}

void BM_GlslSweep(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const SweepJob& job = JobFor(width);
  GlslSweepKernel& kernel = Kernel();
  SweepResult result = kernel.Run(job);  // warm-up: shader JIT, texture allocation
  int64_t hypotheses = 0;
  double wall = 0, cpu = 0;
  for (auto _ : state) {
    Timer timer;
    const double cpu0 = ProcessCpuSeconds();
    result = kernel.Run(job);
    cpu += ProcessCpuSeconds() - cpu0;
    wall += timer.Seconds();
    state.SetIterationTime(timer.Seconds());
    hypotheses += result.stats.hypotheses;
  }
  Report(state, hypotheses, wall, cpu, result.stats);
  // Same output as the reference: tile winners at the same pixel and offset.
  const SweepResult& reference = ReferenceResult(width);
  std::map<std::pair<float, float>, int> ref_offsets;
  for (const SweepPoint& p : reference.points) ref_offsets[{p.pixel.x(), p.pixel.y()}] = p.offset;
  int same = 0;
  for (const SweepPoint& p : result.points) {
    auto it = ref_offsets.find({p.pixel.x(), p.pixel.y()});
    same += it != ref_offsets.end() && it->second == p.offset;
  }
  state.counters["points"] = static_cast<double>(result.points.size());
  state.counters["ref_points"] = static_cast<double>(reference.points.size());
  state.counters["same_winners"] = same;
}
BENCHMARK(BM_GlslSweep)
    ->Arg(640)
    ->Arg(1280)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(3);

void BM_ReferenceSweep(benchmark::State& state) {
  cv::setNumThreads(1);
  const SweepJob& job = JobFor(static_cast<int>(state.range(0)));
  ReferenceSweepKernel kernel;
  int64_t hypotheses = 0;
  double wall = 0, cpu = 0;
  SweepStats last;
  for (auto _ : state) {
    Timer timer;
    const double cpu0 = ProcessCpuSeconds();
    const SweepResult result = kernel.Run(job);
    cpu += ProcessCpuSeconds() - cpu0;
    wall += timer.Seconds();
    hypotheses += result.stats.hypotheses;
    last = result.stats;
  }
  Report(state, hypotheses, wall, cpu, last);
}
BENCHMARK(BM_ReferenceSweep)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace ms

BENCHMARK_MAIN();
