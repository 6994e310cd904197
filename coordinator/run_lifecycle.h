// The life of a coordinator run without the network: prepare (build the initial manifold, or
// resume by replaying the checkpointed batches), integrate each iteration's batch (insert,
// extract, statistics, checkpoint), and finish (final meshes, summary). The coordinator's
// network loop runs these steps on a background thread, one at a time; tests run them directly.
#pragma once

#include <atomic>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "base/log.h"
#include "coordinator/coordinator.h"
#include "coordinator/image_catalog.h"
#include "coordinator/insertion_batch.h"
#include "coordinator/job_builder.h"
#include "coordinator/run_store.h"
#include "coordinator/witness_cameras.h"
#include "manifold/delaunay_manifold.h"
#include "manifold/output_meshes.h"
#include "mesh/mesh.h"

namespace ms {

// What the network loop measured while an iteration's jobs were out.
struct SweepRound {
  int32_t jobs = 0;
  int32_t jobs_bad = 0;       // refused by the kernel (no points from that camera)
  int32_t jobs_requeued = 0;  // handed out again (lease expired, worker died or failed)
  int32_t cameras_skipped = 0;
  double seconds_jobs = 0;                   // building the jobs (while the sweep runs)
  int64_t job_bytes = 0, job_max_bytes = 0;  // job messages: all, the largest
  double seconds_sweep = 0;                  // first job out -> last result in
  int32_t jobs_smoothed = 0;                 // jobs whose images the kernel smoothed (noise)
  double image_noise_max = 0;                // the noisiest job's estimate, grey levels
  std::map<std::string, int64_t> jobs_by_worker;
  std::map<std::string, int64_t> points_by_worker;
  std::map<std::string, double> kernel_seconds_by_worker;
};

// What a step hands back: the next iteration's jobs, or the end of the run.
struct StepOutcome {
  bool stop = false;
  std::unique_ptr<IterationJobSource> jobs;  // unless stop; built as they are handed out
};

class RunLifecycle {
 public:
  // options.Check() must have passed; session_id goes into every job.
  RunLifecycle(const CoordinatorOptions& options, uint64_t session_id);
  ~RunLifecycle();

  // Where a fresh run keeps the scene's points from its build to its first checkpoint (in the
  // output directory).
  static constexpr const char* kSceneStash = "run.scene.h5";
  RunLifecycle(const RunLifecycle&) = delete;
  RunLifecycle& operator=(const RunLifecycle&) = delete;

  // Builds the initial manifold and writes initial.ply, or resumes from output_dir/run.h5 by
  // replaying its batches (checking each inserts what it did); then the first jobs, or the end
  // (the run is then finished). Throws InputError for bad input or a checkpoint of another run.
  StepOutcome Prepare();
  // While an iteration's sweep runs: inserts the points of the next cameras in order, whose
  // results are all in (DelaunayManifold::InsertPart), so that less is left for Integrate.
  // Each point first gets the rays of the cameras that see it (witness_cameras.h).
  void InsertEarly(std::vector<RayPoint> points);
  // An iteration's sweep is over: inserts `rest` (the points InsertEarly has not had, in
  // order), completes the insertion, extracts the surface, records the statistics, starts
  // writing the checkpoint in the background (it overlaps the next sweep); then the next jobs,
  // or the end (whose checkpoint is written before Integrate returns).
  StepOutcome Integrate(std::vector<RayPoint> rest, const SweepRound& round);
  // Waits for the checkpoint being written in the background, if any; rethrows its error.
  void WaitForCheckpoint();
  // While the sweep runs: rethrows the background checkpoint's error as soon as it is known
  // (a full disk stops the run then, not an iteration later). Never blocks.
  void CheckCheckpoint();

  // Safe to call while a step runs: the image catalog once Prepare has hashed the images (it
  // does not change afterwards), else null.
  const ImageCatalog* catalog() const { return catalog_ready_ ? catalog_.get() : nullptr; }

  // Between steps only.
  int completed_iterations() const { return record_.completed_iterations(); }
  int num_views() const { return static_cast<int>(record_.scene.views.size()); }
  const CoordinatorResult& final_result() const { return final_; }
  // The surface proper the next jobs are built from (the closed mesh is held only while the
  // meshes of an iteration are written).
  const Mesh& surface() const { return *surface_; }
  // Writes summary.json for a run stopped early (if the run's record got as far as loading).
  void WriteInterruptedSummary();

 private:
  std::string Path(const std::string& name) const;
  // How Prepare starts: a new run, a resumed one, or the extension of a finished one.
  enum class Start { kNew, kResume, kExtend };
  void BuildOrReplay(Start start, const std::string& run_file);
  // The finished run --extend-run, its scene extended by `model` and the extension recorded
  // (its batch not yet inserted).
  RunRecord ExtendedRecord(Scene model);
  // Inserts iteration `iteration`'s batch: Insert, or the rebuild of an extension.
  InsertionStats InsertBatch(int iteration, const std::vector<RayPoint>& batch);
  InsertionStats RebuildWithExtension(const RunExtension& e, const std::vector<RayPoint>& batch);
  // An iteration's row as far as its insertion and the extracted mesh tell it.
  IterationStats InsertionRow(int iteration, size_t found, const InsertionStats& s) const;
  // Inserts the last extension's batch: its iteration's statistics, then a checkpoint.
  void InsertExtension();
  // Sweep iterations since the start or the last extension.
  int SweepIterationsDone() const;
  void WriteInitial(const BuildStats& stats, double build_s);
  // Cameras inside the matter after an iteration, warned about by number (should be none).
  int64_t CountCamerasInMatter(int iteration);
  // mesh_ (and surface_info_) from the manifold as it is now; the sweep's surface is made from
  // it when the next jobs need it (MakeSweepSurface).
  void Extract();
  // mesh_, handed over (extracted again where an earlier step took it: the same mesh while the
  // manifold does not change).
  Mesh TakeMesh(SurfaceInfo* info);
  // surface_, the surface proper the jobs are built from; takes mesh_.
  void MakeSweepSurface();
  // Writes NAME.ply (and NAME_surface.ply with `with_surface`): the meshes users get, made
  // robust in floating point; their size and the cleanup's counts go into `row`. Takes mesh_
  // and lets the sweep's surface go (MakeSweepSurface makes it again).
  OutputMeshes WriteOutputMeshes(const std::string& name, bool with_surface, IterationStats* row);
  RunRecord ReadCheckpoint(const std::string& run_file);
  // Writes run.h5 and summary.json now (after waiting for one in the background).
  void Checkpoint();
  // The same on a background thread; record_ must not change until WaitForCheckpoint.
  void CheckpointInBackground();
  void WriteCheckpoint();
  // Once run.h5 holds the whole scene: frees the scene's points (run_store.h), or, where they
  // went to the stash before the build, removes the stash.
  void ReleaseScenePointsOnce();
  // Removes the stash of the scene's points, if the record still copies from it.
  void RemoveSceneStash();
  StepOutcome NextOrStop();
  void Finish(const std::string& reason);
  RunSummaryInfo SummaryInfo(const std::string& status) const;

  CoordinatorOptions options_;
  uint64_t session_id_;
  JobBuildOptions job_options_;
  Timer process_timer_;

  RunRecord record_;
  std::atomic<bool> record_loaded_{false};
  bool resumed_ = false;
  std::unique_ptr<ImageCatalog> catalog_;
  std::atomic<bool> catalog_ready_{false};
  std::vector<std::vector<int>> neighbours_;
  std::vector<std::vector<int>> witness_candidates_;  // empty when witness rays are off
  // The cameras that get jobs: empty (every camera), or an extension's (run_extension.h).
  std::vector<uint8_t> swept_;
  std::unique_ptr<DelaunayManifold> manifold_;
  // This iteration's insertion while its sweep runs: open, the points given, the seconds taken.
  bool insert_open_ = false;
  std::vector<RayPoint> early_points_;
  double early_seconds_ = 0;
  // The cameras that see the iteration's points through its closed mesh (null when off; made
  // with surface_), and how many they added so far.
  std::unique_ptr<WitnessCameras> witnesses_;
  int64_t witness_rays_ = 0;
  // The closed manifold (from Extract until the iteration's meshes are written), and the surface
  // proper (without the Steiner faces that close it): what the sweep jobs are built from
  // (docs/design/manifold.md), shared with the iteration's job source.
  Mesh mesh_;
  std::shared_ptr<const Mesh> surface_;
  SurfaceInfo surface_info_;  // of mesh_
  CoordinatorResult final_;
  std::string final_check_;
  std::future<void> checkpoint_;  // the checkpoint being written in the background
};

}  // namespace ms
