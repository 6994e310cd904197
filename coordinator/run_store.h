// What a coordinator run leaves in its output directory and how it resumes
// (docs/design/distributed.md):
//
//   initial.ply          the surface after Build (the paper's initial manifold)
//   iteration_NN.ply     the surface after iteration NN (with --save-iterations)
//   final.ply            the surface at the end
//   run.h5               /scene: the scene; /stats/iterations and /stats/workers: per-iteration
//                        statistics; /checkpoint: every iteration's accepted, sorted batch of
//                        points (the input of DelaunayManifold::Insert), and the extensions
//                        (`manisweep extend`) with the iterations that added their cameras
//   run.prev.h5          the checkpoint before run.h5 (a hard link or copy), the fallback when
//                        run.h5 is damaged: /checkpoint carries an XXH64 content hash of what a
//                        resume replays, checked before use
//   summary.json         the numbers for scripts
//
// Checkpoints work by deterministic replay: Build(scene points) followed by Insert(batch 1),
// Insert(batch 2), ... gives the identical manifold, so a resumed run continues exactly where
// the interrupted one was. Every file is written atomically (temporary name, then rename), so a
// killed coordinator leaves the previous complete version.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/options.h"
#include "coordinator/run_extension.h"
#include "manifold/delaunay_manifold.h"
#include "scene/scene.h"

namespace ms {

// One row of /stats/iterations. Iteration 0 is the initial build.
struct IterationStats {
  int32_t iteration = 0;
  int32_t jobs = 0;             // jobs sent (one per camera that has neighbours and sees faces)
  int32_t jobs_bad = 0;         // jobs the kernel refused (no points from that camera)
  int32_t jobs_requeued = 0;    // hand-outs repeated after a dead worker or an expired lease
  int32_t cameras_skipped = 0;  // no neighbour, or no visible face
  int32_t workers = 0;          // distinct workers that delivered
  int64_t points_found = 0;     // returned by the workers (iteration 0: input points)
  int64_t points_inserted = 0;
  int64_t discarded_conflict = 0;
  int64_t discarded_duplicate = 0;
  int64_t discarded_outside = 0;
  int64_t vertices = 0;  // of the surface after the iteration (as written, where it was)
  int64_t faces = 0;
  int64_t outside_cells = 0;
  // Cameras whose centre is in no cell of O after the iteration (manifold.h CamerasInMatter):
  // they see the surface from inside the matter. Should be 0.
  int64_t cameras_in_matter = 0;
  int64_t job_bytes = 0;      // this iteration's job messages (visible meshes), all of them
  int64_t job_max_bytes = 0;  // the largest one
  // The kernels' noise estimates (sweep/image_noise.h): jobs whose images were smoothed, and
  // the noisiest job's estimate in grey levels of 255.
  int32_t jobs_smoothed = 0;
  double image_noise_max = 0;
  // Rays added to the found points from cameras that see them besides the matching ones
  // (coordinator/witness_cameras.h).
  int64_t witness_rays = 0;
  // The float cleanup of the mesh written after this iteration (manifold/output_meshes.h): 0
  // when none was written; float_problems_left > 0 when it could not clean everything.
  int64_t cleanup_collapses = 0;
  int64_t cleanup_splits = 0;
  int64_t float_problems_left = 0;
  double seconds_jobs = 0;          // building this iteration's jobs, during the sweep
  double seconds_sweep = 0;         // first job sent -> last result in
  double seconds_kernel = 0;        // sum of the workers' kernel times
  double seconds_insert = 0;        // Insert (Build for iteration 0), after the sweep
  double seconds_insert_early = 0;  // inserting while the sweep ran (RunLifecycle::InsertEarly)
  double seconds_extract = 0;       // surface extraction and mesh files
  double seconds_checkpoint = 0;    // writing run.h5, during the next iteration's sweep
  double seconds_total = 0;         // sweep + insert + extract (iteration 0: Build + extract)
};

// One row of /stats/workers: what one worker did in one iteration.
struct WorkerIterationStats {
  int32_t iteration = 0;
  std::string worker;
  int64_t jobs = 0;
  int64_t points = 0;
  double seconds_kernel = 0;
};

struct RunRecord {
  // The scene's points are needed only to build the initial manifold, which keeps what it uses;
  // once a run file holds the whole scene, ReleaseScenePoints frees them (about 200 bytes a
  // point) and later run files copy /scene from that file.
  Scene scene;
  int64_t scene_points = 0;         // scene.points.size() before any release
  std::string scene_copy_from;      // the run file /scene is copied from; empty: write `scene`
  std::string scene_fingerprint;    // HashHex of the scene's content
  std::string options_fingerprint;  // options that change the result (manifold, sweep, ...)
  std::vector<std::vector<RayPoint>> batches;  // iterations 1..N, sorted as inserted
  // In order; the manifold is built from the views and points before the first one (all of
  // them without one).
  std::vector<RunExtension> extensions;
  std::vector<IterationStats> iterations;  // 0..N
  std::vector<WorkerIterationStats> workers;
  std::string stop_reason;  // empty while running
  int completed_iterations() const { return static_cast<int>(batches.size()); }
  int32_t build_views() const;
  int64_t build_points() const;
};

// Frees record->scene's points; WriteRunFile then copies /scene from `run_file`, which must hold
// the whole scene (a run file written or read before the release).
void ReleaseScenePoints(const std::string& run_file, RunRecord* record);

// Writes record->scene to `path` (an HDF5 file with /scene) and frees its points: the first
// checkpoint copies /scene from there, so the points need not stay in memory while the initial
// manifold is built.
void StashScenePoints(const std::string& path, RunRecord* record);

// A stable hash of everything in the scene that the reconstruction uses.
std::string SceneFingerprint(const Scene& scene);

// Writes run.h5 atomically, with the content hash. Throws InputError naming the file on failure.
void WriteRunFile(const RunRecord& record, const std::string& path);
// Reads and checks it. Throws InputError naming the file and the dataset.
RunRecord ReadRunFile(const std::string& path);

// summary.json: scene, options, per-iteration statistics, worker counts, final mesh.
struct RunSummaryInfo {
  std::string status;          // "running", "finished", "interrupted", "failed"
  std::string input;           // the scene file, as given
  std::string input_absolute;  // the same, absolute (the report finds it from anywhere)
  OptionValues options;        // every option of the run (CoordinatorOptionValues)
  std::string final_mesh;      // path, when finished
  std::string mesh_check;      // one line from CheckMesh of the final mesh
  bool final_is_closed_manifold = false;
  double seconds = 0;  // wall time of this process
  bool resumed = false;
};
void WriteSummaryJson(const RunRecord& record, const RunSummaryInfo& info, const std::string& path);

}  // namespace ms
