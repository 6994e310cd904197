// The coordinator process (`manisweep coordinator`, and the heart of `manisweep reconstruct`):
// owns the scene, the Delaunay manifold and the job queue; builds the initial manifold, then
// per iteration extracts the surface, sends one sweep job per camera to the workers, collects
// their points, sorts them by (camera, pixel) and inserts them, writes statistics and a
// checkpoint, and stops when no point was inserted or after max_iterations
// (docs/design/distributed.md, proto/PROTOCOL.md).
//
// The network loop runs on the calling thread and never blocks on the manifold: building,
// inserting, extracting and checkpointing run on a background thread meanwhile, so heartbeats
// and image requests are answered at all times.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "base/options.h"
#include "coordinator/job_scheduler.h"
#include "coordinator/run_extension.h"
#include "manifold/manifold_options.h"
#include "mesh/visible_mesh.h"
#include "proto/transport.h"
#include "proto/wire_limits.h"
#include "scene/view_selection.h"
#include "sweep/sweep_options.h"

namespace ms {

// The run's own options (--max-iterations, --resume, ...).
struct RunOptions {
  static constexpr const char* kOptionGroup = "";
#define MS_OPTION_LIST "coordinator/run_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

// Everything a coordinator run takes: plain option groups, each declared once.
struct CoordinatorOptions {
  std::string input;       // the scene (any format ReadScene reads); optional with resume
  std::string output_dir;  // initial.ply, final.ply, run.h5, summary.json (run_store.h)
  RunOptions run;
  ManifoldOptions manifold;
  NeighbourOptions neighbours;
  VisibleMeshOptions visible;
  SweepOptions sweep;  // sent with every job
  SchedulerOptions scheduler;
  // `manisweep extend`: the finished run whose output folder this run extends with the new
  // cameras of `input` (coordinator/run_extension.h); empty for a plain run.
  std::string extend_run;
  ExtendOptions extend;
  // The workers stay after a finished run (no Shutdown): refinement follows on them
  // (coordinator/refine_dispatcher.h). Set by the commands, not a flag.
  bool keep_workers = false;
  void Check() const;        // throws InputError naming the flag
  void CheckGroups() const;  // Check() without --input and --output
  WireLimits Limits() const { return WireLimitsFromMiB(run.max_message_mb); }
};

struct CoordinatorResult {
  std::string status;       // "finished" or "interrupted"
  std::string stop_reason;  // why the iterations stopped
  int iterations = 0;       // completed iterations
  std::string final_mesh;   // path of final.ply ("" if interrupted)
  int64_t vertices = 0, faces = 0;
  bool final_is_closed_manifold = false;
};

// Options that change the result, as a fingerprint stored in checkpoints: a resumed run must
// use the same ones.
std::string OptionsFingerprint(const CoordinatorOptions& options);
// Every option of the groups a run takes (run, manifold, neighbours, visible, sweep, scheduler)
// with its value, in declaration order: summary.json records them for the run report.
OptionValues CoordinatorOptionValues(const CoordinatorOptions& options);

class Coordinator {
 public:
  // The transport is bound already; the coordinator does not own it.
  Coordinator(const CoordinatorOptions& options, ServerTransport* transport);
  ~Coordinator();
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  // Runs to the end, or until stop_requested() (polled every few ms; the step in progress is
  // completed and the last checkpoint stays valid). Tells every worker to shut down before
  // returning. Throws InputError for bad input, a job that failed on max_attempts workers, or a
  // checkpoint that does not match.
  CoordinatorResult Run(const std::function<bool()>& stop_requested);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
