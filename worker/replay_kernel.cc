#include "worker/replay_kernel.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "base/error.h"
#include "base/log.h"

namespace ms {
namespace {

// Same camera up to the last bits a file round trip may change.
bool SameView(const View& a, const View& b) {
  const double scale = 1 + b.t.norm();
  return a.intrinsics == b.intrinsics && (a.R - b.R).cwiseAbs().maxCoeff() <= 1e-12 &&
         (a.t - b.t).cwiseAbs().maxCoeff() <= 1e-12 * scale;
}

}  // namespace

void ReplayKernelOptions::Check() const {
  CheckOptionGroup(*this);
  if (run.empty()) throw InputError("--kernel replay needs --replay.run (an earlier run's run.h5)");
}

ReplayKernel::ReplayKernel(const ReplayKernelOptions& options, std::vector<View> views,
                           std::vector<std::vector<RayPoint>> batches)
    : options_(options), views_(std::move(views)) {
  options_.Check();
  for (std::vector<RayPoint>& batch : batches) {
    std::map<int32_t, std::vector<RayPoint>>& by_camera = batches_.emplace_back();
    for (RayPoint& p : batch) {
      if (p.cameras.empty()) {
        throw InputError(
            fmt::format("{}: /checkpoint holds a point without cameras", options_.run));
      }
      by_camera[p.cameras.front()].push_back(std::move(p));
    }
  }
}

SweepResult ReplayKernel::Run(const SweepJob& job) {
  Timer timer;
  const int32_t id = job.camera.id;
  if (job.iteration < 1 || job.iteration > batches_.size()) {
    throw InputError(fmt::format("{} recorded {} iterations; the job is of iteration {}",
                                 options_.run, batches_.size(), job.iteration));
  }
  if (id < 0 || id >= static_cast<int32_t>(views_.size()) ||
      !SameView(job.camera.view, views_[id])) {
    throw InputError(fmt::format(
        "camera {} of the job is not camera {} of the run recorded in {} (another scene?)", id, id,
        options_.run));
  }
  const Intrinsics& k = job.camera.view.intrinsics;
  const int level = SweepPyramidLevel(std::max(k.width, k.height), job.options);
  const cv::Size swept = SweptImageSize(k.width, k.height, level);
  const double scale_x = static_cast<double>(swept.width) / k.width;
  const double scale_y = static_cast<double>(swept.height) / k.height;

  SweepResult result;
  result.stats.image_width = swept.width;
  result.stats.image_height = swept.height;
  result.stats.pyramid_level = level;
  result.stats.num_neighbours = static_cast<int>(job.neighbours.size());
  const auto& by_camera = batches_[job.iteration - 1];
  if (auto it = by_camera.find(id); it != by_camera.end()) {
    for (const RayPoint& recorded : it->second) {
      Eigen::Vector2d projected;
      if (!job.camera.view.Project(recorded.position, &projected)) {
        throw InputError(
            fmt::format("{}: a recorded point of camera {} is behind it", options_.run, id));
      }
      // The swept pixel the sweep found it at, and its centre as MakeSweepPoint writes it.
      const int col = static_cast<int>(std::floor(projected.x() * scale_x));
      const int row = static_cast<int>(std::floor(projected.y() * scale_y));
      SweepPoint& point = result.points.emplace_back();
      point.position = recorded.position;
      point.pixel = {static_cast<float>((col + 0.5) / scale_x),
                     static_cast<float>((row + 0.5) / scale_y)};
      point.ncc = static_cast<float>(job.options.ncc_threshold);
      // The recorded cameras are the matching ones, then the witnesses the coordinator added
      // (coordinator/witness_cameras.h); a sweep returns only the job's, and the coordinator
      // adds the witnesses again.
      for (int32_t c : recorded.cameras) {
        const bool in_job = c == id || std::any_of(job.neighbours.begin(), job.neighbours.end(),
                                                   [c](const SweepCamera& n) { return n.id == c; });
        if (in_job) point.cameras.push_back(c);
      }
    }
  }
  const double left = options_.delay_s - timer.Seconds();
  if (left > 0) std::this_thread::sleep_for(std::chrono::duration<double>(left));
  result.stats.total_s = timer.Seconds();
  return result;
}

}  // namespace ms
