// The replay kernel (`manisweep worker --kernel replay`): instead of sweeping, it hands back the
// points an earlier run of the same scene found for the same iteration and camera, after a set
// delay. Jobs are deterministic (docs/design/distributed.md), so a run driven by replaying workers
// inserts exactly the recorded batches and builds exactly the recorded jobs: it is the real
// coordinator at the speed of a GPU cluster, on any machine, with no images (coordinator
// --no-images). bench/scalability/capacity.sh measures the coordinator's capacity with it.
//
// The source is a run's checkpoint (run.h5, /checkpoint, read by the worker command): the
// recorded scene's views and every iteration's batch, whose points list their camera C first. What
// a batch does not keep is filled in: the pixel is the centre of the swept pixel the position
// projects into (where the sweep found it), the NCC is the job's t_NCC and the offset 0; neither of
// these two changes what the coordinator inserts.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "base/options.h"
#include "manifold/delaunay_manifold.h"
#include "scene/scene.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct ReplayKernelOptions {
  static constexpr const char* kOptionGroup = "replay";
#define MS_OPTION_LIST "worker/replay_options_def.h"
#include "base/option_group_members.h"
  void Check() const;  // throws InputError naming the flag
};

class ReplayKernel : public SweepKernel {
 public:
  // `batches[i]`: iteration i + 1's batch of the run in options.run, of the scene `views`.
  // Throws InputError for a point without cameras.
  ReplayKernel(const ReplayKernelOptions& options, std::vector<View> views,
               std::vector<std::vector<RayPoint>> batches);

  // The recorded points of (job.iteration, job.camera), after the delay. Throws InputError for
  // an iteration the run did not record, or a camera that is not the recorded scene's (another
  // scene, or other poses).
  SweepResult Run(const SweepJob& job) override;
  std::string Name() const override { return "replay"; }
  bool NeedsImages() const override { return false; }

  int recorded_iterations() const { return static_cast<int>(batches_.size()); }

 private:
  ReplayKernelOptions options_;
  std::vector<View> views_;  // the recorded scene's
  // batches_[i][camera]: the points of iteration i + 1 whose first camera is `camera`.
  std::vector<std::map<int32_t, std::vector<RayPoint>>> batches_;
};

}  // namespace ms
