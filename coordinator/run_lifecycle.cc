#include "coordinator/run_lifecycle.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include "base/check.h"
#include "base/error.h"
#include "base/memory.h"
#include "manifold/scene_rays.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "scene/view_selection.h"

namespace ms {
namespace fs = std::filesystem;
namespace {

// Sorted indices as runs: "1, 7-12" (what `convert --keep-views` reads).
std::string IndexRanges(const std::vector<int>& sorted) {
  std::string out;
  for (size_t i = 0; i < sorted.size();) {
    size_t j = i;
    while (j + 1 < sorted.size() && sorted[j + 1] == sorted[j] + 1) ++j;
    if (!out.empty()) out += ", ";
    out += j == i ? fmt::format("{}", sorted[i]) : fmt::format("{}-{}", sorted[i], sorted[j]);
    i = j + 1;
  }
  return out;
}

}  // namespace

RunLifecycle::RunLifecycle(const CoordinatorOptions& options, uint64_t session_id)
    : options_(options), session_id_(session_id) {
  job_options_.visible = options_.visible;
  job_options_.sweep = options_.sweep;
  job_options_.lease_s = options_.scheduler.lease_s;
  job_options_.limits = options_.Limits();
}

RunLifecycle::~RunLifecycle() {
  if (checkpoint_.valid()) checkpoint_.wait();
  RemoveSceneStash();  // a run that stopped before its first checkpoint leaves none behind
}

void RunLifecycle::RemoveSceneStash() {
  if (record_.scene_copy_from != Path(kSceneStash)) return;
  std::error_code ec;
  fs::remove(record_.scene_copy_from, ec);
  record_.scene_copy_from.clear();
}

std::string RunLifecycle::Path(const std::string& name) const {
  return (fs::path(options_.output_dir) / name).string();
}

StepOutcome RunLifecycle::Prepare() {
  std::error_code same_error;
  if (!options_.extend_run.empty() &&
      fs::equivalent(options_.extend_run, options_.output_dir, same_error)) {
    throw InputError("--output " + options_.output_dir +
                     ": the extension goes to another folder than --run (the run stays as it is)");
  }
  fs::create_directories(options_.output_dir);
  const std::string run_file = Path("run.h5");
  const std::string fingerprint = OptionsFingerprint(options_);
  bool resuming = false;
  if (fs::exists(run_file)) {
    if (!options_.run.resume) {
      throw InputError(options_.output_dir +
                       " holds a run already (run.h5): pass --resume to continue it, or "
                       "choose another --output");
    }
    resuming = true;
  } else if (options_.run.resume) {
    spdlog::warn("--resume: no {} yet; starting a new run", run_file);
    if (options_.input.empty()) throw InputError("--resume without a run.h5 needs --input");
  }
  resumed_ = resuming;
  Scene input;
  if (!options_.input.empty()) {
    input = ReadScene(options_.input);
    input.Validate();
  }
  const Start start = resuming                       ? Start::kResume
                      : !options_.extend_run.empty() ? Start::kExtend
                                                     : Start::kNew;
  if (resuming) {
    record_ = ReadCheckpoint(run_file);
    if (record_.options_fingerprint != fingerprint) {
      throw InputError(run_file +
                       ": the run was made with other options (manifold, sweep, "
                       "neighbour or visible-mesh options differ); resume with the same ones");
    }
    // An extended run's scene is the run's and the model's together.
    if (!options_.input.empty() && record_.extensions.empty() &&
        SceneFingerprint(input) != record_.scene_fingerprint) {
      throw InputError(options_.input + ": not the scene of the run in " + run_file);
    }
    spdlog::info("resuming {}: {} iterations done", run_file, record_.completed_iterations());
  } else if (start == Start::kExtend) {
    record_ = ExtendedRecord(std::move(input));
  } else {
    record_ = RunRecord();
    record_.scene = std::move(input);
    record_.scene_points = static_cast<int64_t>(record_.scene.points.size());
    record_.scene_fingerprint = SceneFingerprint(record_.scene);
    record_.options_fingerprint = fingerprint;
  }
  record_loaded_ = true;
  const Scene& scene = record_.scene;
  spdlog::info("scene: {}", scene.Summary());
  spdlog::info("memory after the scene: {}", MemoryReport());
  if (options_.run.no_images) {
    catalog_ = std::make_unique<ImageCatalog>(ImageCatalog::WithoutImages(scene));
    spdlog::info("--no-images: jobs carry no image; only replay workers can take them");
  } else {
    Timer hashing;
    catalog_ = std::make_unique<ImageCatalog>(scene);
    spdlog::info("hashed {} image files ({:.1f} MiB) in {:.2f} s", catalog_->size(),
                 catalog_->total_bytes() / 1048576.0, hashing.Seconds());
  }
  catalog_ready_ = true;
  neighbours_.clear();
  for (size_t c = 0; c < scene.views.size(); ++c) {
    neighbours_.push_back(SelectNeighbours(scene, static_cast<int>(c), options_.neighbours));
  }
  if (options_.manifold.witness_tolerance > 0) witness_candidates_ = WitnessCandidates(scene);
  // While the scene's points are here: the first checkpoint lets them go.
  swept_.clear();
  if (!record_.extensions.empty()) {
    const RunExtension& e = record_.extensions.back();
    swept_ = ExtensionSweptCameras(scene, e, neighbours_);
    std::vector<int> left;  // the run's cameras that get no job
    for (int c = 0; c < e.views_before; ++c) {
      if (!swept_[c]) left.push_back(c);
    }
    spdlog::info(
        "extension: {} of {} cameras are swept (the new ones, their neighbours, and "
        "the old ones that look into their region); not swept: {}",
        std::count(swept_.begin(), swept_.end(), 1), swept_.size(),
        left.empty() ? "none" : IndexRanges(left));
  }
  BuildOrReplay(start, run_file);
  return NextOrStop();
}

RunRecord RunLifecycle::ExtendedRecord(Scene model) {
  const fs::path run_dir(options_.extend_run);
  std::error_code ec;
  const std::string run_file = (run_dir / "run.h5").string();
  if (!fs::exists(run_file)) {
    throw InputError("--run " + options_.extend_run + ": no run.h5 there (not a run folder)");
  }
  RunRecord record = ReadRunFile(run_file);
  if (record.stop_reason.empty()) {
    throw InputError(run_file +
                     ": the run has not finished; finish it first (the same command "
                     "with --resume), then extend it");
  }
  if (record.options_fingerprint != OptionsFingerprint(options_)) {
    throw InputError(run_file +
                     ": the run was made with other options (manifold, sweep, neighbour or "
                     "visible-mesh options differ); extend it with the same ones");
  }
  ExtendedScene extended = ExtendScene(record.scene, model, options_.input, options_.extend);
  const RunExtension& e = extended.extension;
  spdlog::info(
      "extending {} ({} cameras, {} iterations) with {}: {} new cameras, {} of its {} points "
      "seen by them; old cameras moved by at most {:.3g} and turned by at most {:.3g} degrees",
      run_file, e.views_before, record.completed_iterations(), options_.input,
      e.views_after - e.views_before, e.points_after - e.points_before, extended.model_points,
      extended.worst_shift, extended.worst_turn_deg);
  record.scene = std::move(extended.scene);
  record.scene_points = static_cast<int64_t>(record.scene.points.size());
  record.scene_copy_from.clear();
  record.scene_fingerprint = SceneFingerprint(record.scene);
  record.extensions.push_back(e);
  record.extensions.back().iteration = record.completed_iterations() + 1;
  record.stop_reason.clear();
  // The initial manifold is the run's: its meshes come along for the report.
  for (const char* name : {"initial.ply", "initial_surface.ply"}) {
    if (fs::exists(run_dir / name)) {
      fs::create_directories(options_.output_dir);
      fs::copy_file(run_dir / name, Path(name), fs::copy_options::overwrite_existing, ec);
    }
  }
  return record;
}

InsertionStats RunLifecycle::InsertBatch(int iteration, const std::vector<RayPoint>& batch) {
  for (const RunExtension& e : record_.extensions) {
    if (e.iteration == iteration) return RebuildWithExtension(e, batch);
  }
  return manifold_->Insert(batch);
}

// The paper's insertion discards a new point whose conflict region still meets O after
// shrinking, and a region only the new cameras see (where the run's O fans out in large cells to
// the Steiner box) loses most of its points that way. The manifold is built anew instead, from
// the run's vertices with their rays and the new points, in a Steiner box that holds every camera
// (docs/design/extend.md).
InsertionStats RunLifecycle::RebuildWithExtension(const RunExtension& e,
                                                  const std::vector<RayPoint>& batch) {
  std::vector<RayPoint> points = manifold_->Points();
  const int64_t before = static_cast<int64_t>(points.size());
  std::set<std::array<double, 3>> distinct;
  for (const RayPoint& p : points)
    distinct.insert({p.position.x(), p.position.y(), p.position.z()});
  const int64_t merged_before = before - static_cast<int64_t>(distinct.size());
  points.insert(points.end(), batch.begin(), batch.end());
  std::vector<ManifoldCamera> cameras = ManifoldCamerasFromScene(record_.scene);
  cameras.resize(e.views_after);
  manifold_.reset();  // its points are copied: the new one's build is the peak of memory
  manifold_ = std::make_unique<DelaunayManifold>(std::move(cameras), options_.manifold);
  const BuildStats built = manifold_->Build(std::move(points));
  InsertionStats s;
  s.requested = static_cast<int64_t>(batch.size());
  s.discarded_duplicate = built.merged_duplicates - merged_before;
  s.inserted = s.requested - s.discarded_duplicate;
  s.outside_cells = built.outside_cells;
  return s;
}

IterationStats RunLifecycle::InsertionRow(int iteration, size_t found,
                                          const InsertionStats& s) const {
  IterationStats row;
  row.iteration = static_cast<int32_t>(iteration);
  row.points_found = static_cast<int64_t>(found);
  row.points_inserted = s.inserted;
  row.discarded_conflict = s.discarded_conflict;
  row.discarded_duplicate = s.discarded_duplicate;
  row.discarded_outside = s.discarded_outside;
  row.vertices = static_cast<int64_t>(mesh_.NumVertices());
  row.faces = static_cast<int64_t>(mesh_.NumFaces());
  row.outside_cells = s.outside_cells;
  return row;
}

void RunLifecycle::InsertExtension() {
  const RunExtension& e = record_.extensions.back();
  MS_CHECK(e.iteration == record_.completed_iterations() + 1) << "no extension to insert";
  Timer insert;
  std::vector<RayPoint> batch = ExtensionBatch(record_.scene, e);
  const InsertionStats s = InsertBatch(e.iteration, batch);
  const double insert_s = insert.Seconds();
  Timer extract;
  Extract();
  IterationStats row = InsertionRow(e.iteration, batch.size(), s);
  row.cameras_in_matter = CountCamerasInMatter(e.iteration);
  row.seconds_insert = insert_s;
  row.seconds_extract = extract.Seconds();
  row.seconds_total = insert_s + row.seconds_extract;
  record_.batches.push_back(std::move(batch));
  record_.iterations.push_back(row);
  spdlog::info(
      "extension (iteration {}): {} new cameras; the manifold built anew with the run's "
      "vertices and their {} points ({} new, {} merged into others); mesh {} vertices, {} faces; "
      "{:.2f} s",
      e.iteration, e.views_after - e.views_before, row.points_found, s.inserted,
      s.discarded_duplicate, row.vertices, row.faces, insert_s);
  Checkpoint();
}

int RunLifecycle::SweepIterationsDone() const {
  const int first = record_.extensions.empty() ? 0 : record_.extensions.back().iteration;
  return record_.completed_iterations() - first;
}

// The initial manifold; on resume, the checkpointed batches inserted again, each of which must
// insert exactly what it did in the run.
void RunLifecycle::BuildOrReplay(Start start, const std::string& run_file) {
  const Scene& scene = record_.scene;
  // An extended run's manifold is built from the views and points before its extensions.
  std::vector<ManifoldCamera> cameras = ManifoldCamerasFromScene(scene);
  cameras.resize(record_.build_views());
  manifold_ = std::make_unique<DelaunayManifold>(std::move(cameras), options_.manifold);
  // The points' rays only while the manifold is built: it keeps what it needs of them and lets
  // them go before it grows the initial manifold.
  std::vector<RayPoint> rays = RayPointsFromScene(scene);
  rays.resize(record_.build_points());
  if (start == Start::kNew) {
    // The first checkpoint copies the scene from the stash, so that the scene's points are not
    // held while the manifold is built and its meshes extracted, the coordinator's peak of
    // memory (docs/design/performance.md).
    StashScenePoints(Path(kSceneStash), &record_);
    ReleaseFreeMemory();
  }
  Timer build;
  const BuildStats stats = manifold_->Build(std::move(rays));
  ReleaseFreeMemory();  // the build's own structures, gone: less resident for the steps to come
  const double build_s = build.Seconds();
  spdlog::info("initial manifold: {} points ({} Steiner), {} cells, {} outside; {:.2f} s",
               stats.points, stats.steiner_points, stats.cells, stats.outside_cells, build_s);
  spdlog::info("memory after the initial manifold: {} (manifold about {:.0f} MiB)", MemoryReport(),
               manifold_->MemoryBytes() / 1048576.0);
  if (start == Start::kNew) {
    WriteInitial(stats, build_s);
    return;
  }
  for (int i = 0; i < record_.completed_iterations(); ++i) {
    Timer replay;
    const InsertionStats s = InsertBatch(i + 1, record_.batches[i]);
    spdlog::info("replayed iteration {}: {} of {} points inserted, {:.2f} s", i + 1, s.inserted,
                 s.requested, replay.Seconds());
    if (s.inserted != record_.iterations[i + 1].points_inserted) {
      throw InputError(fmt::format(
          "{}: replaying iteration {} inserted {} points where the run inserted {}: the "
          "manifold code differs from the one that made the checkpoint",
          run_file, i + 1, s.inserted, record_.iterations[i + 1].points_inserted));
    }
  }
  if (start == Start::kExtend) return InsertExtension();
  Extract();
  if (!fs::exists(Path("initial.ply"))) {
    spdlog::warn("initial.ply is missing; it is not rewritten on resume");
  }
}

// initial.ply, initial_surface.ply, iteration 0's statistics and the first checkpoint.
void RunLifecycle::WriteInitial(const BuildStats& stats, double build_s) {
  Timer extract;
  Extract();
  if (mesh_.faces.empty()) {
    throw InputError(options_.input +
                     ": the initial manifold is empty: no cell reached the "
                     "free-space threshold (check the points' visibility and "
                     "--manifold.free-threshold)");
  }
  IterationStats row;
  row.iteration = 0;
  row.points_found = record_.scene_points;
  row.points_inserted = stats.points - stats.merged_duplicates;
  row.discarded_duplicate = stats.merged_duplicates;
  row.outside_cells = stats.outside_cells;
  row.cameras_in_matter = CountCamerasInMatter(0);
  row.seconds_insert = build_s;
  row.seconds_extract = extract.Seconds();
  record_.iterations.push_back(row);
  // A first checkpoint before the meshes: run.h5 then holds the scene, so its points are freed
  // before the meshes' float cleanup, the coordinator's peak. The second adds the meshes' counts.
  Checkpoint();
  IterationStats& initial = record_.iterations.back();
  Timer meshes;
  {
    const OutputMeshes written = WriteOutputMeshes("initial", true, &initial);
    spdlog::info("initial mesh: {} vertices, {} faces -> {}", written.closed.NumVertices(),
                 written.closed.NumFaces(), Path("initial.ply"));
  }
  initial.seconds_extract += meshes.Seconds();
  initial.seconds_total = build_s + initial.seconds_extract;
  Checkpoint();
  ReleaseFreeMemory();  // the float cleanup's structures, gone for good
  spdlog::info("memory after the initial meshes: {}", MemoryReport());
}

void RunLifecycle::InsertEarly(std::vector<RayPoint> points) {
  Timer insert;
  if (!insert_open_) {
    manifold_->BeginInsert();
    insert_open_ = true;
  }
  if (witnesses_) witness_rays_ += witnesses_->Add(&points);
  manifold_->InsertPart(points);
  early_points_.insert(early_points_.end(), points.begin(), points.end());
  early_seconds_ += insert.Seconds();
}

StepOutcome RunLifecycle::Integrate(std::vector<RayPoint> rest, const SweepRound& round) {
  WaitForCheckpoint();  // the previous iteration's, which reads record_
  const int iteration = record_.completed_iterations() + 1;
  Timer insert;
  if (!insert_open_) manifold_->BeginInsert();
  if (witnesses_) witness_rays_ += witnesses_->Add(&rest);
  witnesses_.reset();  // of this iteration's surface
  manifold_->InsertPart(rest);
  const InsertionStats s = manifold_->FinishInsert();
  const double insert_s = insert.Seconds();
  std::vector<RayPoint> batch = std::move(early_points_);
  batch.insert(batch.end(), rest.begin(), rest.end());
  const double early_s = early_seconds_;
  insert_open_ = false;
  early_points_.clear();
  early_seconds_ = 0;
  Timer extract;
  Extract();
  IterationStats row = InsertionRow(iteration, batch.size(), s);
  row.jobs = round.jobs;
  row.jobs_bad = round.jobs_bad;
  row.jobs_requeued = round.jobs_requeued;
  row.cameras_skipped = round.cameras_skipped;
  if (options_.run.save_iteration_meshes) {
    WriteOutputMeshes(fmt::format("iteration_{:02d}", iteration), false, &row);
  }
  row.cameras_in_matter = CountCamerasInMatter(iteration);
  row.seconds_jobs = round.seconds_jobs;
  row.job_bytes = round.job_bytes;
  row.job_max_bytes = round.job_max_bytes;
  row.jobs_smoothed = round.jobs_smoothed;
  row.image_noise_max = round.image_noise_max;
  row.witness_rays = std::exchange(witness_rays_, 0);
  row.seconds_sweep = round.seconds_sweep;
  row.seconds_insert = insert_s;
  row.seconds_insert_early = early_s;
  row.seconds_extract = extract.Seconds();
  row.workers = static_cast<int32_t>(round.jobs_by_worker.size());
  for (const auto& [name, jobs] : round.jobs_by_worker) {
    WorkerIterationStats w;
    w.iteration = row.iteration;
    w.worker = name.substr(0, 255);
    w.jobs = jobs;
    w.points = round.points_by_worker.count(name) ? round.points_by_worker.at(name) : 0;
    w.seconds_kernel =
        round.kernel_seconds_by_worker.count(name) ? round.kernel_seconds_by_worker.at(name) : 0;
    row.seconds_kernel += w.seconds_kernel;
    record_.workers.push_back(w);
  }
  // Jobs are built while the sweep runs: their seconds are inside seconds_sweep.
  row.seconds_total = row.seconds_sweep + row.seconds_insert + row.seconds_extract;
  record_.batches.push_back(std::move(batch));
  record_.iterations.push_back(row);
  const IterationStats& done = record_.iterations.back();
  spdlog::info(
      "iteration {} done: {} points found, {} inserted, {} discarded; mesh {} vertices, {} "
      "faces; jobs {:.2f} s (while sweeping), sweep {:.2f} s (inserting {:.2f} s meanwhile), "
      "insert {:.2f} s, extract {:.2f} s",
      iteration, done.points_found, done.points_inserted,
      done.discarded_conflict + done.discarded_duplicate + done.discarded_outside, done.vertices,
      done.faces, done.seconds_jobs, done.seconds_sweep, done.seconds_insert_early,
      done.seconds_insert, done.seconds_extract);
  if (done.jobs_smoothed > 0) {
    spdlog::info(
        "iteration {}: the images of {} of {} jobs were smoothed before matching (noise up to "
        "{:.2f} grey levels; --sweep.image-noise-target, docs/design/sweep.md \"Noisy images\")",
        iteration, done.jobs_smoothed, done.jobs, done.image_noise_max);
  }
  CheckpointInBackground();
  return NextOrStop();
}

int64_t RunLifecycle::CountCamerasInMatter(int iteration) {
  const std::vector<int32_t> enclosed = manifold_->CamerasInMatter();
  if (!enclosed.empty()) {
    const size_t shown = std::min<size_t>(enclosed.size(), 10);
    spdlog::warn(
        "iteration {}: {} camera(s) inside the matter (their centre is in no free-space cell "
        "of O, so they see the mesh from inside): {}{}; docs/design/manifold.md, \"Known limits\"",
        iteration, enclosed.size(),
        fmt::join(enclosed.begin(), enclosed.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
        shown < enclosed.size() ? ", ..." : "");
  }
  return static_cast<int64_t>(enclosed.size());
}

void RunLifecycle::Extract() {
  mesh_ = manifold_->ExtractSurface(&surface_info_);
  surface_.reset();  // of the manifold before; made from mesh_ when the jobs need it
}

Mesh RunLifecycle::TakeMesh(SurfaceInfo* info) {
  if (mesh_.vertices.empty()) return manifold_->ExtractSurface(info);
  *info = std::move(surface_info_);
  surface_info_ = SurfaceInfo();
  return std::exchange(mesh_, Mesh());
}

void RunLifecycle::MakeSweepSurface() {
  SurfaceInfo info;
  const Mesh mesh = TakeMesh(&info);
  surface_ = std::make_shared<const Mesh>(SurfaceWithoutSteinerFaces(mesh, info));
  if (options_.manifold.witness_tolerance > 0) {
    witnesses_ = std::make_unique<WitnessCameras>(record_.scene, witness_candidates_, mesh,
                                                  options_.manifold.witness_tolerance);
  }
}

OutputMeshes RunLifecycle::WriteOutputMeshes(const std::string& name, bool with_surface,
                                             IterationStats* row) {
  // The float cleanup is the coordinator's peak of memory: it starts from what the heap holds,
  // takes mesh_ rather than a copy, and no sweep surface is held meanwhile (the jobs' is made
  // again after: the same mesh, the manifold has not changed).
  surface_.reset();
  ReleaseFreeMemory();
  SurfaceInfo info;
  OutputMeshes out =
      MakeOutputMeshes(*manifold_, TakeMesh(&info), info, options_.manifold.float_cleanup);
  ReleaseFreeMemory();  // the cleaner's structures
  WriteMesh(out.closed, Path(name + ".ply"));
  if (with_surface) WriteMesh(out.surface, Path(name + "_surface.ply"));
  row->vertices = static_cast<int64_t>(out.closed.NumVertices());
  row->faces = static_cast<int64_t>(out.closed.NumFaces());
  row->cleanup_collapses = out.cleanup.collapses;
  row->cleanup_splits = out.cleanup.splits;
  row->float_problems_left = out.cleanup.problems_after;
  return out;
}

// Writes run.h5 and summary.json; the time it took goes into the last row (and reaches the file
// with the next checkpoint).
// run.h5, or, if it is damaged (truncated, corrupted: its content hash does not match), the
// previous checkpoint run.prev.h5; the damaged file is kept as run.damaged.h5 for inspection.
RunRecord RunLifecycle::ReadCheckpoint(const std::string& run_file) {
  try {
    return ReadRunFile(run_file);
  } catch (const InputError& e) {
    const std::string previous = Path("run.prev.h5");
    if (!fs::exists(previous)) throw;
    spdlog::error("{}; resuming from the previous checkpoint {}", e.what(), previous);
    RunRecord record;
    try {
      record = ReadRunFile(previous);
    } catch (const InputError& e2) {
      throw InputError(fmt::format("{}; and the previous checkpoint: {}", e.what(), e2.what()));
    }
    std::error_code ec;
    fs::rename(run_file, Path("run.damaged.h5"), ec);
    return record;
  }
}

void RunLifecycle::Checkpoint() {
  WaitForCheckpoint();
  WriteCheckpoint();
  ReleaseScenePointsOnce();
}

void RunLifecycle::CheckpointInBackground() {
  WaitForCheckpoint();
  checkpoint_ = std::async(std::launch::async, [this] { WriteCheckpoint(); });
}

void RunLifecycle::WaitForCheckpoint() {
  if (!checkpoint_.valid()) return;
  checkpoint_.get();
  ReleaseScenePointsOnce();
}

void RunLifecycle::CheckCheckpoint() {
  if (checkpoint_.valid() &&
      checkpoint_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    checkpoint_.get();
    ReleaseScenePointsOnce();
  }
}

// After the first checkpoint this process wrote (a resumed run's file may be the fallback
// run.prev.h5, which the next checkpoint replaces), run.h5 holds the whole scene.
void RunLifecycle::ReleaseScenePointsOnce() {
  if (record_.scene_copy_from == Path(kSceneStash)) {  // released before the build
    RemoveSceneStash();
    record_.scene_copy_from = Path("run.h5");
    return;
  }
  if (!record_.scene_copy_from.empty() || record_.scene.points.empty()) return;
  ReleaseScenePoints(Path("run.h5"), &record_);
  ReleaseFreeMemory();
  spdlog::info("memory after releasing the scene's points (run.h5 keeps them): {}", MemoryReport());
}

void RunLifecycle::WriteCheckpoint() {
  // Keep the checkpoint being replaced as run.prev.h5 (a hard link: no copy), then replace
  // run.h5 atomically, so a good checkpoint exists at every moment.
  const fs::path run = Path("run.h5"), previous = Path("run.prev.h5");
  if (fs::exists(run)) {
    std::error_code ec;
    fs::remove(previous, ec);
    fs::create_hard_link(run, previous, ec);
    if (ec) fs::copy_file(run, previous, fs::copy_options::overwrite_existing, ec);
    if (ec) spdlog::warn("cannot keep {} as {}: {}", run.string(), previous.string(), ec.message());
  }
  Timer timer;
  WriteRunFile(record_, Path("run.h5"));
  record_.iterations.back().seconds_checkpoint = timer.Seconds();
  WriteSummaryJson(record_, SummaryInfo(record_.stop_reason.empty() ? "running" : "finished"),
                   Path("summary.json"));
  spdlog::info("checkpoint of iteration {} written in {:.2f} s", record_.completed_iterations(),
               timer.Seconds());
}

RunSummaryInfo RunLifecycle::SummaryInfo(const std::string& status) const {
  RunSummaryInfo info;
  info.status = status;
  info.input = options_.input;
  if (!options_.input.empty()) {
    info.input_absolute = std::filesystem::absolute(options_.input).lexically_normal().string();
  }
  info.options = CoordinatorOptionValues(options_);
  info.seconds = process_timer_.Seconds();
  info.resumed = resumed_;
  if (status == "finished") {
    info.final_mesh = final_.final_mesh;
    info.final_is_closed_manifold = final_.final_is_closed_manifold;
    info.mesh_check = final_check_;
  }
  return info;
}

void RunLifecycle::WriteInterruptedSummary() {
  try {
    WaitForCheckpoint();
  } catch (const std::exception& e) {
    spdlog::warn("the checkpoint being written failed while stopping: {}", e.what());
  }
  if (record_loaded_) WriteSummaryJson(record_, SummaryInfo("interrupted"), Path("summary.json"));
}

StepOutcome RunLifecycle::NextOrStop() {
  StepOutcome outcome;
  const int done = record_.completed_iterations();
  // An extension sweeps its own --max-iterations; the insertion of its points is no sweep.
  const int swept = SweepIterationsDone();
  std::string reason;
  if (swept >= 1 && record_.iterations.back().points_inserted == 0) {
    reason = "converged: no new point was inserted";
  } else if (swept >= options_.run.max_iterations) {
    reason = fmt::format("reached --max-iterations {}", options_.run.max_iterations);
  } else {
    if (!surface_) MakeSweepSurface();
    job_options_.swept = swept_;
    outcome.jobs = std::make_unique<IterationJobSource>(record_.scene, neighbours_, surface_,
                                                        *catalog_, static_cast<uint32_t>(done + 1),
                                                        session_id_, job_options_);
    if (outcome.jobs->job_ids().empty()) reason = "no camera has a neighbour";
  }
  if (reason.empty()) {
    ReleaseFreeMemory();  // the sweep holds only its surface (MakeSweepSurface took mesh_)
    spdlog::info("memory at the start of iteration {}: {}", done + 1, MemoryReport());
    return outcome;
  }
  Finish(reason);
  outcome.stop = true;
  return outcome;
}

void RunLifecycle::Finish(const std::string& reason) {
  WaitForCheckpoint();  // the last iteration's: Finish changes its row
  const std::string path = Path("final.ply");
  const OutputMeshes written = WriteOutputMeshes("final", true, &record_.iterations.back());
  MeshCheckOptions check;
  check.check_self_intersections = false;  // exact but slow on large meshes
  const MeshReport report = CheckMesh(written.closed, check);
  const std::vector<std::string> problems = report.Problems();
  final_check_ = report.is_closed_manifold
                     ? "closed, oriented 2-manifold (self-intersections not checked)"
                     : "not a closed 2-manifold: " + (problems.empty() ? "" : problems[0]);
  final_.status = "finished";
  final_.stop_reason = reason;
  final_.final_mesh = path;
  final_.vertices = static_cast<int64_t>(written.closed.NumVertices());
  final_.faces = static_cast<int64_t>(written.closed.NumFaces());
  final_.final_is_closed_manifold = report.is_closed_manifold;
  record_.stop_reason = reason;
  Checkpoint();
  spdlog::info("finished after {} iterations ({}): {} vertices, {} faces -> {}; {}",
               record_.completed_iterations(), reason, final_.vertices, final_.faces, path,
               final_check_);
}

}  // namespace ms
